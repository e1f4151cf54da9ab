#include "daemon/thread_stacks.h"

#include <pthread.h>

#include <cstring>
#include <string>

namespace ceilpose::daemon {

Result<void> limit_thread_stacks() {
  pthread_attr_t attr;
  if (int r = pthread_attr_init(&attr); r != 0)
    return make_error(std::string("pthread_attr_init: ") + std::strerror(r));
  int r = pthread_attr_setstacksize(&attr, kThreadStackBytes);
  if (r == 0) r = pthread_setattr_default_np(&attr);
  pthread_attr_destroy(&attr);
  if (r != 0) {
    return make_error("cannot set the threads' stack size to " +
                      std::to_string(kThreadStackBytes >> 10) + " KiB: " + std::strerror(r));
  }
  return {};
}

}  // namespace ceilpose::daemon
