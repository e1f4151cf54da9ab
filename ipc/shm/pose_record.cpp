#include "ipc/shm/pose_record.h"

#include <cstring>

namespace ceilpose {

const char* to_string(WriterState state) {
  switch (state) {
    case WriterState::kStarting:
      return "starting";
    case WriterState::kRunning:
      return "running";
    case WriterState::kStopped:
      return "stopped";
  }
  return "unknown";
}

const char* pose_mode_name(uint8_t mode) {
  // The names are string_views over literals: NUL-terminated.
  return mode < kPositioningModes.size() ? to_string(static_cast<PositioningMode>(mode)).data()
                                         : "unknown";
}

void set_status_source(StatusRecord* status, const char* text) {
  std::strncpy(status->source, text, sizeof(status->source) - 1);
  status->source[sizeof(status->source) - 1] = '\0';
}

}  // namespace ceilpose
