#include "ipc/dds/dds_participant.h"

#include <string>
#include <utility>

#include "ipc/dds/dds_error.h"

namespace ceilpose {

Result<DdsParticipant> DdsParticipant::create(const DdsDomainOptions& options) {
  if (auto ok = validate(options); !ok) return ok.error();
  DdsParticipant p;
  p.domain_id_ = options.domain_id;
  const std::string domain_name = "DDS domain " + std::to_string(options.domain_id);
  if (options.needs_explicit_domain()) {
    // The explicit options replace CYCLONEDDS_URI for this domain: Cyclone
    // would merge lists such as <Interfaces> from both and then refuse an
    // interface named twice, so layering cannot express "use these instead".
    const std::string config = cyclone_config_xml(options);
    p.domain_ = dds_create_domain(options.domain_id, config.c_str());
    if (p.domain_ < 0) {
      const dds_return_t rc = p.domain_;
      p.domain_ = 0;
      if (rc == DDS_RETCODE_PRECONDITION_NOT_MET) {
        return make_error(domain_name +
                          " already exists in this process: network interfaces and peers can "
                          "be given only to the first participant of a domain");
      }
      return dds_error("cannot create " + domain_name + " with configuration " + config, rc);
    }
  }
  dds_qos_t* qos = nullptr;
  if (options.security) {
    qos = dds_create_qos();
    for (const auto& [name, value] :
         cyclone_security_properties(*options.security, cyclone_security_plugin_dir())) {
      dds_qset_prop(qos, name.c_str(), value.c_str());
    }
  }
  p.participant_ = dds_create_participant(options.domain_id, qos, nullptr);
  if (qos != nullptr) dds_delete_qos(qos);
  if (p.participant_ < 0) {
    const dds_return_t rc = p.participant_;
    p.participant_ = 0;
    return dds_error(options.security ? "the DDS Security plugins refused the enclave of " +
                                            options.security->certificate + " on " + domain_name +
                                            " (run with CYCLONEDDS_URI tracing 'security' for why)"
                                      : "cannot create a participant on " + domain_name +
                                            " (check CYCLONEDDS_URI and the network interfaces; "
                                            "with unicast discovery (peers) a host holds at most "
                                            "Discovery/MaxAutoParticipantIndex + 1 participants, "
                                            "Cyclone's default 10: raise "
                                            "dds.max_participants_per_host, or "
                                            "MaxAutoParticipantIndex in CYCLONEDDS_URI; "
                                            "docs/fleet.md)",
                     rc);
  }
  return p;
}

DdsParticipant::DdsParticipant(DdsParticipant&& other) noexcept
    : domain_(std::exchange(other.domain_, 0)),
      participant_(std::exchange(other.participant_, 0)),
      domain_id_(other.domain_id_) {}

DdsParticipant& DdsParticipant::operator=(DdsParticipant&& other) noexcept {
  if (this != &other) {
    reset();
    domain_ = std::exchange(other.domain_, 0);
    participant_ = std::exchange(other.participant_, 0);
    domain_id_ = other.domain_id_;
  }
  return *this;
}

DdsParticipant::~DdsParticipant() { reset(); }

void DdsParticipant::reset() {
  // A domain created with dds_create_domain outlives its participants, so it
  // is the root to delete; otherwise the participant is.
  if (domain_ > 0) {
    dds_delete(domain_);
  } else if (participant_ > 0) {
    dds_delete(participant_);
  }
  domain_ = 0;
  participant_ = 0;
}

}  // namespace ceilpose
