#pragma once
// Owns one Cyclone participant (and the domain, when ceilpose had to create it
// with its own configuration). Every other entity is a child of it, so one
// dds_delete here tears the whole tree down. Move-only; not thread-safe.
#include <dds/dds.h>

#include "core/result.h"
#include "ipc/dds/dds_options.h"

namespace ceilpose {

class DdsParticipant {
 public:
  DdsParticipant() = default;
  static Result<DdsParticipant> create(const DdsDomainOptions& options);

  DdsParticipant(DdsParticipant&& other) noexcept;
  DdsParticipant& operator=(DdsParticipant&& other) noexcept;
  DdsParticipant(const DdsParticipant&) = delete;
  DdsParticipant& operator=(const DdsParticipant&) = delete;
  ~DdsParticipant();

  dds_entity_t handle() const { return participant_; }
  uint32_t domain_id() const { return domain_id_; }
  bool valid() const { return participant_ > 0; }
  // Deletes the participant (and the domain it created) now; idempotent.
  void reset();

 private:
  dds_entity_t domain_ = 0;  // > 0 only when created by us
  dds_entity_t participant_ = 0;
  uint32_t domain_id_ = 0;
};

}  // namespace ceilpose
