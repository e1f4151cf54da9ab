// The C client (libceilpose_client.so): a thin C face over ShmPoseReader.
// No exception crosses the C boundary; detailed messages go to a per-thread
// buffer that ceilpose_last_error_message() returns.
#include "ceilpose/pose_client.h"

#include <new>
#include <string>

#include "core/refusal.h"
#include "ipc/shm/pose_record.h"
#include "ipc/shm/shm_fleet_reader.h"
#include "ipc/shm/shm_pose_reader.h"

struct ceilpose_client {
  ceilpose::ShmPoseReader reader;
};

struct ceilpose_fleet {
  ceilpose::ShmFleetReader reader;
};

namespace {

// What ceilpose_last_error_message() returns: the last call's, on this
// thread. Every call sets it, so an earlier failure never outlives a later
// call; a per-frame call only points it at a static text (no allocation).
thread_local std::string g_last_detail;
thread_local const char* g_last_message = "";

// A failure whose message names what failed (open, reattach).
int set_error(int code, const char* detail, const char* detail_tail = "") {
  try {
    g_last_detail = detail;
    g_last_detail += detail_tail;
    g_last_message = g_last_detail.c_str();
  } catch (...) {
    g_last_message = ceilpose_strerror(code);
  }
  return code;
}

// The outcome of any other call: "" on success, else the code's text.
int outcome(int code) {
  g_last_message = code == CEILPOSE_OK ? "" : ceilpose_strerror(code);
  return code;
}

int wait_code(ceilpose::WaitResult r) {
  switch (r) {
    case ceilpose::WaitResult::kPose:
      return CEILPOSE_OK;
    case ceilpose::WaitResult::kTimeout:
      return CEILPOSE_ERR_TIMEOUT;
    case ceilpose::WaitResult::kStopped:
      return CEILPOSE_ERR_STOPPED;
    case ceilpose::WaitResult::kWriterDead:
      return CEILPOSE_ERR_WRITER_DEAD;
    case ceilpose::WaitResult::kBusy:
      return CEILPOSE_ERR_BUSY;
  }
  return CEILPOSE_ERR_SYSTEM;
}

int read_code(ceilpose::ReadResult r) {
  switch (r) {
    case ceilpose::ReadResult::kOk:
      return CEILPOSE_OK;
    case ceilpose::ReadResult::kNoPose:
      return CEILPOSE_ERR_NO_POSE;
    case ceilpose::ReadResult::kBusy:
      return CEILPOSE_ERR_BUSY;
  }
  return CEILPOSE_ERR_SYSTEM;
}

// Opens a reader of kind Reader on `name` into a new Handle{reader}; what:
// "pose segment", "fleet segment" for the messages.
template <typename Handle, typename Reader>
int open_handle(const char* name, Handle** out, const char* what) {
  if (out == nullptr) return set_error(CEILPOSE_ERR_INVALID_ARGUMENT, "out handle is NULL");
  *out = nullptr;
  try {
    ceilpose::shm::ShmErrc code = ceilpose::shm::ShmErrc::kOk;
    auto reader = Reader::open(name != nullptr ? name : CEILPOSE_DEFAULT_SHM_NAME, &code);
    if (!reader) return set_error(static_cast<int>(code), reader.error().message.c_str());
    *out = new Handle{std::move(reader.value())};
    return outcome(CEILPOSE_OK);
  } catch (const std::bad_alloc&) {
    return set_error(CEILPOSE_ERR_NO_MEMORY, "out of memory opening the ", what);
  } catch (...) {
    return set_error(CEILPOSE_ERR_SYSTEM, "unexpected error opening the ", what);
  }
}

}  // namespace

extern "C" {

int ceilpose_client_open(const char* name, ceilpose_client** out) {
  return open_handle<ceilpose_client, ceilpose::ShmPoseReader>(name, out, "pose segment");
}

void ceilpose_client_close(ceilpose_client* client) { delete client; }

int ceilpose_client_read_latest(ceilpose_client* client, ceilpose_pose* out) {
  if (client == nullptr || out == nullptr) return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  return outcome(read_code(client->reader.read_latest(out)));
}

int ceilpose_client_wait_next(ceilpose_client* client, uint64_t after_seq, int32_t timeout_ms,
                              ceilpose_pose* out) {
  if (client == nullptr || out == nullptr) return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  return outcome(wait_code(client->reader.wait_next(after_seq, timeout_ms, out)));
}

int ceilpose_client_predict(ceilpose_client* client, int64_t t_mono_ns, ceilpose_pose* out) {
  if (client == nullptr || out == nullptr) return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  ceilpose_pose latest;
  const int rc = read_code(client->reader.read_latest(&latest));
  if (rc != CEILPOSE_OK) return outcome(rc);
  switch (ceilpose::predict_pose(latest, t_mono_ns, out)) {
    case ceilpose::PredictResult::kOk:
      return outcome(CEILPOSE_OK);
    case ceilpose::PredictResult::kNoMotion:
      return outcome(CEILPOSE_ERR_NO_MOTION);
    case ceilpose::PredictResult::kBeyondHorizon:
      return outcome(CEILPOSE_ERR_HORIZON);
  }
  return outcome(CEILPOSE_ERR_SYSTEM);
}

int ceilpose_client_liveness(ceilpose_client* client, int64_t stale_after_ms,
                             enum ceilpose_liveness* out) {
  if (client == nullptr || out == nullptr || stale_after_ms < 0) {
    return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  }
  switch (client->reader.liveness(stale_after_ms)) {
    case ceilpose::Liveness::kLive:
      *out = CEILPOSE_LIVE;
      break;
    case ceilpose::Liveness::kStarting:
      *out = CEILPOSE_LIVE_STARTING;
      break;
    case ceilpose::Liveness::kStopped:
      *out = CEILPOSE_STOPPED;
      break;
    case ceilpose::Liveness::kStale:
      *out = CEILPOSE_STALE;
      break;
    case ceilpose::Liveness::kWriterDead:
      *out = CEILPOSE_WRITER_DEAD;
      break;
    case ceilpose::Liveness::kRestarted:
      *out = CEILPOSE_RESTARTED;
      break;
  }
  return outcome(CEILPOSE_OK);
}

int ceilpose_client_reattach(ceilpose_client* client) {
  if (client == nullptr) return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  try {
    ceilpose::shm::ShmErrc code = ceilpose::shm::ShmErrc::kOk;
    auto r = client->reader.reattach(&code);
    if (!r) return set_error(static_cast<int>(code), r.error().message.c_str());
    return outcome(CEILPOSE_OK);
  } catch (const std::bad_alloc&) {
    return set_error(CEILPOSE_ERR_NO_MEMORY, "out of memory re-opening the pose segment");
  } catch (...) {
    return set_error(CEILPOSE_ERR_SYSTEM, "unexpected error re-opening the pose segment");
  }
}

int ceilpose_client_read_status(ceilpose_client* client, ceilpose_status* out) {
  if (client == nullptr || out == nullptr) return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  return outcome(read_code(client->reader.read_status(out)));
}

int ceilpose_client_writer_info(ceilpose_client* client, ceilpose_writer_info* out) {
  if (client == nullptr || out == nullptr) return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  const ceilpose::WriterInfo info = client->reader.writer_info();
  out->pid = info.pid;
  out->state = static_cast<uint32_t>(info.state);
  out->generation = info.generation;
  out->start_mono_ns = info.start_mono_ns;
  out->start_real_ns = info.start_real_ns;
  out->heartbeat_mono_ns = info.heartbeat_mono_ns;
  out->stale_after_ms = static_cast<uint32_t>(info.stale_after_ms);
  return outcome(CEILPOSE_OK);
}

int ceilpose_client_read_recent(ceilpose_client* client, ceilpose_pose* out, uint32_t max_poses,
                                uint32_t* count) {
  if (client == nullptr || out == nullptr || count == nullptr) {
    return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  }
  const int limit = max_poses > CEILPOSE_POSE_RING_LENGTH ? CEILPOSE_POSE_RING_LENGTH
                                                          : static_cast<int>(max_poses);
  *count = static_cast<uint32_t>(client->reader.read_recent(out, limit));
  return outcome(CEILPOSE_OK);
}

int ceilpose_client_fleet_open(const char* shm, ceilpose_fleet** out) {
  return open_handle<ceilpose_fleet, ceilpose::ShmFleetReader>(shm, out, "fleet segment");
}

void ceilpose_client_fleet_close(ceilpose_fleet* fleet) { delete fleet; }

int ceilpose_client_fleet_read(ceilpose_fleet* fleet, int64_t t_mono_ns, ceilpose_fleet_robot* out,
                               uint32_t max_robots, uint32_t* count) {
  if (fleet == nullptr || count == nullptr || (out == nullptr && max_robots > 0)) {
    return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  }
  *count = fleet->reader.read(t_mono_ns, out, max_robots);
  return outcome(CEILPOSE_OK);
}

int ceilpose_client_fleet_find(ceilpose_fleet* fleet, const char* robot, int64_t t_mono_ns,
                               ceilpose_fleet_robot* out) {
  if (fleet == nullptr || robot == nullptr || out == nullptr) {
    return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  }
  return outcome(fleet->reader.find(robot, t_mono_ns, out) ? CEILPOSE_OK : CEILPOSE_ERR_NO_POSE);
}

int ceilpose_client_fleet_info(ceilpose_fleet* fleet, ceilpose_fleet_info* out) {
  if (fleet == nullptr || out == nullptr) return outcome(CEILPOSE_ERR_INVALID_ARGUMENT);
  *out = fleet->reader.info();
  return outcome(CEILPOSE_OK);
}

const char* ceilpose_mode_name(uint8_t mode) { return ceilpose::pose_mode_name(mode); }

// The names are std::string_views over string literals: NUL-terminated.
const char* ceilpose_refusal_name(unsigned index) {
  return ceilpose::refusal_name(index > 255 ? -1 : static_cast<int>(index)).data();
}

const char* ceilpose_strerror(int code) {
  switch (code) {
    case CEILPOSE_OK:
      return "success";
    case CEILPOSE_ERR_INVALID_ARGUMENT:
      return "invalid argument";
    case CEILPOSE_ERR_NOT_FOUND:
      return "no pose segment of that name (daemon not running?)";
    case CEILPOSE_ERR_PERMISSION:
      return "permission denied on the pose segment";
    case CEILPOSE_ERR_ABI_MISMATCH:
      return "pose segment has another ABI version";
    case CEILPOSE_ERR_BAD_SIZE:
      return "pose segment has the wrong size";
    case CEILPOSE_ERR_BAD_MAGIC:
      return "not a ceilpose pose segment";
    case CEILPOSE_ERR_NOT_READY:
      return "pose segment is still being initialized";
    case CEILPOSE_ERR_SYSTEM:
      return "system error";
    case CEILPOSE_ERR_NO_MEMORY:
      return "out of memory";
    case CEILPOSE_ERR_NO_POSE:
      return "no pose published yet";
    case CEILPOSE_ERR_BUSY:
      return "pose kept changing during the read";
    case CEILPOSE_ERR_TIMEOUT:
      return "timed out waiting for a pose";
    case CEILPOSE_ERR_STOPPED:
      return "the daemon stopped";
    case CEILPOSE_ERR_WRITER_DEAD:
      return "the daemon process is gone";
    case CEILPOSE_ERR_LIVE_WRITER:
      return "another daemon is publishing on that name";
    case CEILPOSE_ERR_NO_GROUP:
      return "the configured group does not exist";
    case CEILPOSE_ERR_NO_MOTION:
      return "the latest pose is invalid or has no filter motion to predict from";
    case CEILPOSE_ERR_HORIZON:
      return "the instant is beyond the prediction horizon of the latest pose";
    default:
      return "unknown error code";
  }
}

const char* ceilpose_last_error_message(void) { return g_last_message; }

}  // extern "C"
