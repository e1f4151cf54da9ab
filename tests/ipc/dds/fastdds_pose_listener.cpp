// ceilpose_fastdds_pose_listener: another vendor's subscriber (eProsima Fast
// DDS, Debian's libfastrtps) for the interoperability test. It knows the
// message only as ROS 2's rmw_fastrtps does: by the type name and the XCDR1
// field layout, decoded by hand with Fast CDR; nothing is shared with
// Cyclone or with ceilpose's generated code.
//
// Prints one line per received sample and exits 0 after --count samples, 1
// if --timeout-ms passes first.
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <unistd.h>

#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

namespace fdds = eprosima::fastdds::dds;
namespace frtps = eprosima::fastrtps::rtps;

// geometry_msgs/PoseWithCovarianceStamped, or with `odom` nav_msgs/Odometry
// (the same header and pose with child_frame_id between, then the twist).
struct PoseMsg {
  int32_t sec = 0;
  uint32_t nanosec = 0;
  std::string frame_id;
  std::string child_frame_id;
  double position[3] = {};
  double orientation[4] = {};
  double covariance[36] = {};
  double linear[3] = {};
  double angular[3] = {};
  double twist_covariance[36] = {};
};

// Decodes one sample with `read` (the fields in rosidl's order), failing it
// when a field is missing or bytes are left over (CDR pads the end to 4
// bytes at most).
template <typename Read>
bool decode_payload(frtps::SerializedPayload_t* payload, Read&& read) {
  eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->length);
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN,
                             eprosima::fastcdr::Cdr::DDS_CDR);
  try {
    cdr.read_encapsulation();
    read(cdr);
    if (payload->length - cdr.getSerializedDataLength() >= 4) {
      std::fprintf(stderr, "fastdds listener: %zu bytes left over in a sample\n",
                   payload->length - cdr.getSerializedDataLength());
      return false;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fastdds listener: cannot decode a sample: %s\n", e.what());
    return false;
  }
  return true;
}

class PoseType : public fdds::TopicDataType {
 public:
  explicit PoseType(bool odom) : odom_(odom) {
    setName(odom ? "nav_msgs::msg::dds_::Odometry_"
                 : "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_");
    m_typeSize = 4 + 8192;  // encapsulation + a generous bound (frame_id is a string)
    m_isGetKeyDefined = false;
  }

  bool serialize(void* data, frtps::SerializedPayload_t* payload) override {
    auto* msg = static_cast<PoseMsg*>(data);
    eprosima::fastcdr::FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->max_size);
    eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN,
                               eprosima::fastcdr::Cdr::DDS_CDR);
    payload->encapsulation =
        cdr.endianness() == eprosima::fastcdr::Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
    cdr.serialize_encapsulation();
    cdr << msg->sec << msg->nanosec << msg->frame_id;
    if (odom_) cdr << msg->child_frame_id;
    cdr.serializeArray(msg->position, 3);
    cdr.serializeArray(msg->orientation, 4);
    cdr.serializeArray(msg->covariance, 36);
    if (odom_) {
      cdr.serializeArray(msg->linear, 3);
      cdr.serializeArray(msg->angular, 3);
      cdr.serializeArray(msg->twist_covariance, 36);
    }
    payload->length = static_cast<uint32_t>(cdr.getSerializedDataLength());
    return true;
  }

  bool deserialize(frtps::SerializedPayload_t* payload, void* data) override {
    auto* msg = static_cast<PoseMsg*>(data);
    return decode_payload(payload, [&](eprosima::fastcdr::Cdr& cdr) {
      cdr >> msg->sec >> msg->nanosec >> msg->frame_id;
      if (odom_) cdr >> msg->child_frame_id;
      cdr.deserializeArray(msg->position, 3);
      cdr.deserializeArray(msg->orientation, 4);
      cdr.deserializeArray(msg->covariance, 36);
      if (odom_) {
        cdr.deserializeArray(msg->linear, 3);
        cdr.deserializeArray(msg->angular, 3);
        cdr.deserializeArray(msg->twist_covariance, 36);
      }
    });
  }

  std::function<uint32_t()> getSerializedSizeProvider(void*) override {
    return [] { return 4u + 8192u; };
  }
  void* createData() override { return new PoseMsg(); }
  void deleteData(void* data) override { delete static_cast<PoseMsg*>(data); }
  bool getKey(void*, frtps::InstanceHandle_t*, bool) override { return false; }

 private:
  bool odom_;
};

// Reads what every ROS message starts with: std_msgs/Header.
void read_header(eprosima::fastcdr::Cdr& cdr, int32_t* sec, uint32_t* nanosec,
                 std::string* frame_id) {
  cdr >> *sec >> *nanosec >> *frame_id;
}

// A by-hand decoder: `decode` reads every field of one sample into `text`
// (what main prints), in the order rosidl lays them out; any field missing
// or left over fails the sample.
class DecodedType : public fdds::TopicDataType {
 public:
  using Decode = void (*)(eprosima::fastcdr::Cdr& cdr, std::string* text);
  DecodedType(const char* name, Decode decode) : decode_(decode) {
    setName(name);
    m_typeSize = 4 + (1u << 20);  // the ceiling of a 256-marker grid fits
    m_isGetKeyDefined = false;
  }
  bool serialize(void*, frtps::SerializedPayload_t*) override { return false; }  // read only
  bool deserialize(frtps::SerializedPayload_t* payload, void* data) override {
    auto* text = static_cast<std::string*>(data);
    return decode_payload(payload, [&](eprosima::fastcdr::Cdr& cdr) { decode_(cdr, text); });
  }
  std::function<uint32_t()> getSerializedSizeProvider(void*) override {
    return [] { return 4u + (1u << 20); };
  }
  void* createData() override { return new std::string(); }
  void deleteData(void* data) override { delete static_cast<std::string*>(data); }
  bool getKey(void*, frtps::InstanceHandle_t*, bool) override { return false; }

 private:
  Decode decode_;
};

std::string fmt(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* format, ...) {
  char text[1024];
  va_list args;
  va_start(args, format);
  std::vsnprintf(text, sizeof text, format, args);
  va_end(args);
  return text;
}

// tf2_msgs/TFMessage: geometry_msgs/TransformStamped[] transforms.
void decode_tf(eprosima::fastcdr::Cdr& cdr, std::string* text) {
  uint32_t n = 0;
  cdr >> n;
  *text = fmt("tf transforms=%u", n);
  for (uint32_t k = 0; k < n; ++k) {
    int32_t sec = 0;
    uint32_t nanosec = 0;
    std::string parent, child;
    read_header(cdr, &sec, &nanosec, &parent);
    cdr >> child;
    double t[3], q[4];
    cdr.deserializeArray(t, 3);
    cdr.deserializeArray(q, 4);
    *text +=
        fmt(" | sec=%d nanosec=%u parent=%s child=%s x=%.9g y=%.9g z=%.9g qx=%.9g qy=%.9g "
            "qz=%.9g qw=%.9g",
            sec, nanosec, parent.c_str(), child.c_str(), t[0], t[1], t[2], q[0], q[1], q[2], q[3]);
  }
}

// visualization_msgs/MarkerArray: Marker[] markers, each field of Humble's
// Marker.msg in order. Prints the count, then per marker its identity,
// pose, scale, colour, the number of points and the first, and the text.
void decode_markers(eprosima::fastcdr::Cdr& cdr, std::string* text) {
  uint32_t n = 0;
  cdr >> n;
  *text = fmt("markers count=%u", n);
  for (uint32_t k = 0; k < n; ++k) {
    int32_t sec = 0, id = 0, type = 0, action = 0, life_sec = 0;
    uint32_t nanosec = 0, life_nanosec = 0;
    std::string frame, ns, texture_resource, texture_frame, texture_format, label, mesh_resource,
        mesh_filename;
    read_header(cdr, &sec, &nanosec, &frame);
    cdr >> ns >> id >> type >> action;
    double pose[7], scale[3];
    cdr.deserializeArray(pose, 7);
    cdr.deserializeArray(scale, 3);
    float color[4];
    cdr.deserializeArray(color, 4);
    cdr >> life_sec >> life_nanosec;
    bool frame_locked = false, embedded = false;
    cdr >> frame_locked;
    uint32_t points = 0;
    cdr >> points;
    double first[3] = {};
    for (uint32_t p = 0; p < points; ++p) {
      double xyz[3];
      cdr.deserializeArray(xyz, 3);
      if (p == 0) std::memcpy(first, xyz, sizeof xyz);
    }
    uint32_t colors = 0;
    cdr >> colors;
    for (uint32_t c = 0; c < colors; ++c) {
      float rgba[4];
      cdr.deserializeArray(rgba, 4);
    }
    cdr >> texture_resource;
    int32_t tsec = 0;
    uint32_t tnanosec = 0;
    read_header(cdr, &tsec, &tnanosec, &texture_frame);
    cdr >> texture_format;
    std::vector<uint8_t> bytes;
    cdr >> bytes;
    uint32_t uvs = 0;
    cdr >> uvs;
    for (uint32_t u = 0; u < uvs; ++u) {
      float uv[2];
      cdr.deserializeArray(uv, 2);
    }
    cdr >> label >> mesh_resource >> mesh_filename >> bytes >> embedded;
    *text +=
        fmt(" | frame=%s sec=%d ns=%s id=%d type=%d action=%d x=%.9g y=%.9g z=%.9g qw=%.9g "
            "scale=%.9g,%.9g,%.9g rgba=%.3g,%.3g,%.3g,%.3g lifetime=%d frame_locked=%d points=%u "
            "first=%.9g,%.9g,%.9g colors=%u texture=%s uv=%u text=%s mesh=%s embedded=%d",
            frame.c_str(), sec, ns.c_str(), id, type, action, pose[0], pose[1], pose[2], pose[6],
            scale[0], scale[1], scale[2], color[0], color[1], color[2], color[3], life_sec,
            frame_locked ? 1 : 0, points, first[0], first[1], first[2], colors,
            texture_resource.c_str(), uvs, label.c_str(), mesh_resource.c_str(), embedded ? 1 : 0);
  }
}

}  // namespace

int main(int argc, char** argv) {
  int domain_id = 0;
  std::string topic_name;
  int count = 3;
  long timeout_ms = 20000;
  bool odom = false;
  std::string kind = "pose";  // pose | odom | tf | markers
  std::string enclave_dir;    // set: DDS Security with this SROS2 enclave's files
  for (int k = 1; k + 1 < argc; k += 2) {
    if (std::strcmp(argv[k], "--domain") == 0)
      domain_id = std::atoi(argv[k + 1]);
    else if (std::strcmp(argv[k], "--topic") == 0)
      topic_name = argv[k + 1];
    else if (std::strcmp(argv[k], "--count") == 0)
      count = std::atoi(argv[k + 1]);
    else if (std::strcmp(argv[k], "--timeout-ms") == 0)
      timeout_ms = std::atol(argv[k + 1]);
    else if (std::strcmp(argv[k], "--type") == 0)
      kind = argv[k + 1];
    else if (std::strcmp(argv[k], "--enclave-dir") == 0)
      enclave_dir = argv[k + 1];
  }
  if (topic_name.empty()) {
    std::fprintf(
        stderr,
        "usage: %s --topic rt/<robot>/pose [--type pose|odom|tf|markers] [--domain ID] [--count N] "
        "[--timeout-ms T] [--enclave-dir DIR]\n",
        argv[0]);
    return 2;
  }

  // Loopback UDP only, discovery by unicast to the participant ports of
  // 127.0.0.1, as the Cyclone side is configured.
  fdds::DomainParticipantQos pqos;
  pqos.name("ceilpose_fastdds_pose_listener");
  pqos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.push_back("127.0.0.1");
  udp->maxInitialPeersRange = 41;
  pqos.transport().user_transports.push_back(udp);
  frtps::Locator_t peer;
  frtps::IPLocator::setIPv4(peer, 127, 0, 0, 1);
  pqos.wire_protocol().builtin.initialPeersList.push_back(peer);
  if (!enclave_dir.empty()) {
    // Fast DDS's builtin plugins by their DDS Security names, as an SROS2
    // user's rmw_fastrtps sets them from ROS_SECURITY_ENCLAVE.
    const std::string f = "file://" + enclave_dir + "/";  // Fast DDS wants a file:// URI
    for (const auto& [name, value] : std::initializer_list<std::pair<const char*, std::string>>{
             {"dds.sec.auth.plugin", "builtin.PKI-DH"},
             {"dds.sec.auth.builtin.PKI-DH.identity_ca", f + "identity_ca.cert.pem"},
             {"dds.sec.auth.builtin.PKI-DH.identity_certificate", f + "cert.pem"},
             {"dds.sec.auth.builtin.PKI-DH.private_key", f + "key.pem"},
             {"dds.sec.access.plugin", "builtin.Access-Permissions"},
             {"dds.sec.access.builtin.Access-Permissions.permissions_ca",
              f + "permissions_ca.cert.pem"},
             {"dds.sec.access.builtin.Access-Permissions.governance", f + "governance.p7s"},
             {"dds.sec.access.builtin.Access-Permissions.permissions", f + "permissions.p7s"},
             {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"}}) {
      pqos.properties().properties().emplace_back(name, value);
    }
  }

  auto* factory = fdds::DomainParticipantFactory::get_instance();
  fdds::DomainParticipant* participant = factory->create_participant(domain_id, pqos);
  if (participant == nullptr) {
    std::fprintf(stderr, "fastdds listener: cannot create a participant on domain %d\n", domain_id);
    return 1;
  }
  odom = kind == "odom";
  const bool decoded = kind == "tf" || kind == "markers";
  fdds::TypeSupport type(
      decoded ? static_cast<fdds::TopicDataType*>(
                    kind == "tf" ? new DecodedType("tf2_msgs::msg::dds_::TFMessage_", &decode_tf)
                                 : new DecodedType("visualization_msgs::msg::dds_::MarkerArray_",
                                                   &decode_markers))
              : new PoseType(odom));
  type.register_type(participant);
  fdds::Topic* topic =
      participant->create_topic(topic_name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  fdds::Subscriber* subscriber = participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  fdds::DataReaderQos rqos = fdds::DATAREADER_QOS_DEFAULT;
  rqos.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;  // as ROS 2's default profile
  rqos.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  rqos.history().depth = 10;
  // The ceiling is published once, transient local: a late reader asks for it.
  if (kind == "markers") rqos.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
  fdds::DataReader* reader = topic != nullptr && subscriber != nullptr
                                 ? subscriber->create_datareader(topic, rqos)
                                 : nullptr;
  if (reader == nullptr) {
    std::fprintf(stderr, "fastdds listener: cannot create a reader for %s\n", topic_name.c_str());
    return 1;
  }
  std::printf("ready\n");
  std::fflush(stdout);

  int received = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (decoded && received < count && std::chrono::steady_clock::now() < deadline) {
    if (!reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(0, 200'000'000))) continue;
    std::string text;
    fdds::SampleInfo info;
    while (received < count && reader->take_next_sample(&text, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      ++received;
      std::printf("%s\n", text.c_str());
      std::fflush(stdout);
    }
  }
  while (!decoded && received < count && std::chrono::steady_clock::now() < deadline) {
    if (!reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(0, 200'000'000))) continue;
    PoseMsg msg;
    fdds::SampleInfo info;
    while (received < count && reader->take_next_sample(&msg, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      ++received;
      std::printf(
          "sample type=%s sec=%d nanosec=%u frame=%s x=%.9g y=%.9g z=%.9g qx=%.9g qy=%.9g qz=%.9g "
          "qw=%.9g cxx=%.9g cxy=%.9g cyy=%.9g cyawyaw=%.9g czz=%.9g\n",
          type.get_type_name().c_str(), msg.sec, msg.nanosec, msg.frame_id.c_str(), msg.position[0],
          msg.position[1], msg.position[2], msg.orientation[0], msg.orientation[1],
          msg.orientation[2], msg.orientation[3], msg.covariance[0], msg.covariance[1],
          msg.covariance[7], msg.covariance[35], msg.covariance[14]);
      if (odom) {
        const double* t = msg.twist_covariance;
        std::printf(
            "odom child=%s vx=%.9g vy=%.9g vz=%.9g wx=%.9g wy=%.9g wz=%.9g tvxvx=%.9g tvxvy=%.9g "
            "tvyvy=%.9g twzwz=%.9g tvxwz=%.9g tvzvz=%.9g twxwx=%.9g\n",
            msg.child_frame_id.c_str(), msg.linear[0], msg.linear[1], msg.linear[2], msg.angular[0],
            msg.angular[1], msg.angular[2], t[0], t[1], t[7], t[35], t[5], t[14], t[21]);
      }
      std::fflush(stdout);
    }
  }
  // Leave without tearing Fast DDS down: its 2.9.1 reader destructor frees a
  // statistics object with the wrong type (ASan: new-delete-type-mismatch)
  // and it keeps process-wide singletons to the end; neither is ours to
  // judge, and the process ends here anyway.
  std::fflush(stdout);
  _exit(received >= count ? 0 : 1);
}
