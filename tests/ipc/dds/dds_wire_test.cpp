// What another vendor's ROS 2 subscriber depends on, checked on what a
// publisher in another process actually sends: the DDS type name, XCDR1 as
// the announced data representation, and the CDR bytes themselves.
#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "core/clock.h"
#include "ipc/dds/dds_messages.h"
#include "ipc/dds/dds_participant.h"
#include "tests/ipc/dds/dds_test_env.h"
#include "tests/support/child_process.h"

namespace ceilpose {
namespace {

using test::ChildProcess;

constexpr int64_t kTimeoutMs = 20'000;
const std::vector<dds_data_representation_id_t> kOnlyXcdr1{DDS_DATA_REPRESENTATION_XCDR1};

struct Announced {
  std::string type_name;
  std::vector<dds_data_representation_id_t> representations;
  bool reliable = false;
};

// Waits (bounded) for a remote writer on `topic` to show up in DCPSPublication.
bool wait_for_publication(dds_entity_t participant, const std::string& topic, Announced* out) {
  const dds_entity_t reader =
      dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  const dds_entity_t cond = dds_create_readcondition(reader, DDS_ANY_STATE);
  const dds_entity_t ws = dds_create_waitset(participant);
  dds_waitset_attach(ws, cond, 0);
  const int64_t deadline_ns = monotonic_ns() + kTimeoutMs * 1'000'000;
  bool found = false;
  while (!found && monotonic_ns() < deadline_ns) {
    dds_waitset_wait(ws, nullptr, 0, DDS_MSECS(200));
    void* samples[8] = {};
    dds_sample_info_t infos[8];
    const dds_return_t n = dds_take(cond, samples, infos, 8, 8);
    for (dds_return_t k = 0; k < n; ++k) {
      const auto* ep = static_cast<const dds_builtintopic_endpoint_t*>(samples[k]);
      if (!infos[k].valid_data || topic != ep->topic_name) continue;
      out->type_name = ep->type_name;
      uint32_t count = 0;
      dds_data_representation_id_t* values = nullptr;
      if (dds_qget_data_representation(ep->qos, &count, &values)) {
        out->representations.assign(values, values + count);
        dds_free(values);
      }
      dds_reliability_kind_t kind;
      dds_duration_t blocking;
      out->reliable =
          dds_qget_reliability(ep->qos, &kind, &blocking) && kind == DDS_RELIABILITY_RELIABLE;
      found = true;
    }
    if (n > 0) dds_return_loan(cond, samples, n);
  }
  dds_delete(ws);
  dds_delete(reader);
  return found;
}

class DdsWire : public ::testing::Test {
 protected:
  void SetUp() override {
    test::use_loopback_dds();
    domain_id_ = test::unique_domain_id();
    robot_ = test::unique_robot_name("wire");
    DdsDomainOptions options;
    options.domain_id = domain_id_;
    auto p = DdsParticipant::create(options);
    ASSERT_TRUE(p.ok()) << p.error().message;
    participant_ = std::move(p.value());
  }

  std::vector<std::string> fake_robot_args() const {
    return {CEILPOSE_DDS_FAKE_ROBOT,
            "--robot",
            robot_,
            "--domain",
            std::to_string(domain_id_),
            "--x",
            "1.25",
            "--y",
            "-0.5",
            "--yaw",
            "0.5",
            "--stamp-ns",
            "1700000000123456789",
            "--rate",
            "50",
            "--duration",
            "60"};
  }

  uint32_t domain_id_ = 0;
  std::string robot_;
  DdsParticipant participant_;
};

TEST_F(DdsWire, PoseTopicAnnouncesRos2TypeNameAndXcdr1) {
  ChildProcess child(fake_robot_args());
  ASSERT_NE(child.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);
  Announced a;
  ASSERT_TRUE(wait_for_publication(participant_.handle(), "rt/" + robot_ + "/pose", &a));

  EXPECT_EQ(a.type_name, "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_");
  EXPECT_EQ(a.representations, kOnlyXcdr1);
  EXPECT_TRUE(a.reliable);
}

TEST_F(DdsWire, StatusTopicAnnouncesItsTypeName) {
  ChildProcess child(fake_robot_args());
  ASSERT_NE(child.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);
  Announced a;
  const std::string topic = "rt/" + robot_ + "/ceilpose_status";
  ASSERT_TRUE(wait_for_publication(participant_.handle(), topic, &a));

  EXPECT_EQ(a.type_name, "ceilpose::msg::dds_::Status_");
  EXPECT_EQ(a.representations, kOnlyXcdr1);
}

// The bytes rmw would put on the wire for the same message, written out by
// hand: XCDR1 little-endian encapsulation header, then the fields in order,
// each aligned to its size (at most 8) counted from the end of the header.
class CdrWriter {
 public:
  CdrWriter() { bytes_ = {0x00, 0x01, 0x00, 0x00}; }  // CDR_LE, options 0
  void align(size_t n) {
    while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
  }
  template <typename T>
  void put(T v) {
    align(sizeof(T));
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));  // x86-64 and aarch64 are little-endian
    bytes_.insert(bytes_.end(), raw, raw + sizeof(T));
  }
  void put_string(const char* s) {
    put<uint32_t>(static_cast<uint32_t>(std::strlen(s) + 1));
    bytes_.insert(bytes_.end(), s, s + std::strlen(s) + 1);
  }
  const std::vector<unsigned char>& bytes() const { return bytes_; }

 private:
  std::vector<unsigned char> bytes_;
};

TEST_F(DdsWire, SerializedPoseEqualsRos2Cdr) {
  ChildProcess child(fake_robot_args());
  ASSERT_NE(child.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);
  const std::string topic_name = "rt/" + robot_ + "/pose";
  const dds_entity_t topic = dds_create_topic(
      participant_.handle(), &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
      topic_name.c_str(), nullptr, nullptr);
  ASSERT_GT(topic, 0);
  const dds_entity_t reader = dds_create_reader(participant_.handle(), topic, nullptr, nullptr);
  ASSERT_GT(reader, 0);
  const dds_entity_t cond = dds_create_readcondition(reader, DDS_ANY_STATE);
  const dds_entity_t ws = dds_create_waitset(participant_.handle());
  ASSERT_EQ(dds_waitset_attach(ws, cond, 0), DDS_RETCODE_OK);

  std::vector<unsigned char> wire;
  const int64_t deadline_ns = monotonic_ns() + kTimeoutMs * 1'000'000;
  while (wire.empty() && monotonic_ns() < deadline_ns) {
    dds_waitset_wait(ws, nullptr, 0, DDS_MSECS(200));
    ddsi_serdata* sd = nullptr;
    dds_sample_info_t info;
    if (dds_takecdr(cond, &sd, 1, &info, DDS_ANY_STATE) == 1) {
      if (info.valid_data) {
        wire.resize(ddsi_serdata_size(sd));
        ddsi_serdata_to_ser(sd, 0, wire.size(), wire.data());
      }
      ddsi_serdata_unref(sd);
    }
  }
  ASSERT_FALSE(wire.empty()) << "no sample from " << topic_name;

  CdrWriter cdr;
  cdr.put<int32_t>(1'700'000'000);                                         // header.stamp.sec
  cdr.put<uint32_t>(123'456'789);                                          // header.stamp.nanosec
  cdr.put_string("map");                                                   // header.frame_id
  for (double v : {1.25, -0.5, 0.0}) cdr.put(v);                           // position
  for (double v : {0.0, 0.0, std::sin(0.25), std::cos(0.25)}) cdr.put(v);  // orientation
  double cov[36] = {};
  cov[0] = 1e-4;  // the fake robot's (x, y, yaw) covariance, placed by hand
  cov[1] = 1e-5;
  cov[6] = 1e-5;
  cov[7] = 2e-4;
  cov[35] = 3e-3;
  cov[14] = cov[21] = cov[28] = 1e6;  // z, roll, pitch unobserved
  for (double v : cov) cdr.put(v);

  EXPECT_EQ(cdr.bytes().size(), 4u + 360u);
  EXPECT_EQ(wire, cdr.bytes());
  dds_delete(ws);
}

}  // namespace
}  // namespace ceilpose
