#include "core/resource_limits.h"

#include <dirent.h>
#include <sys/resource.h>

namespace ceilpose {
namespace {

size_t open_descriptors() {
  size_t n = 0;
  if (DIR* dir = ::opendir("/proc/self/fd")) {
    while (const dirent* e = ::readdir(dir)) n += e->d_name[0] != '.';
    ::closedir(dir);
    return n > 0 ? n - 1 : 0;  // not the one opendir holds
  }
  return 3;  // no /proc: stdin, stdout, stderr
}

}  // namespace

std::string resource_limit_problem(const ResourceNeeds& needs) {
  rlimit files{};
  if (::getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY) {
    const size_t open = open_descriptors();
    if (files.rlim_cur < open + needs.file_descriptors) {
      return "the open-file limit is " + std::to_string(files.rlim_cur) + " (ulimit -n), " +
             std::to_string(open) + " already open; needs " +
             std::to_string(needs.file_descriptors) +
             " more (sockets, camera, shared memory): raise it (systemd: LimitNOFILE=)";
    }
  }
  rlimit space{};
  if (::getrlimit(RLIMIT_AS, &space) == 0 && space.rlim_cur != RLIM_INFINITY) {
    const size_t mib = static_cast<size_t>(space.rlim_cur >> 20);
    if (mib < needs.address_space_mib) {
      return "the address-space limit is " + std::to_string(mib) + " MiB (ulimit -v " +
             std::to_string(space.rlim_cur >> 10) + "); needs at least " +
             std::to_string(needs.address_space_mib) +
             " MiB (thread stacks, DDS, frame buffers): raise it (systemd: LimitAS=)";
    }
  }
  return {};
}

}  // namespace ceilpose
