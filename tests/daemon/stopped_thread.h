#pragma once
// Stops one thread of a child process with ptrace, as a hung thread would be
// (blocked in a driver, spinning in a bug), while its other threads run on:
// the real failure ceilposed's watchdog gate is for, with no hook in the
// daemon. Use from one test thread (ptrace requests come from the tracer
// thread); the destructor lets the thread run again.
#include <sys/types.h>

#include <string>

namespace ceilpose::test {

class StoppedThread {
 public:
  // Finds the thread of `pid` whose name (/proc/PID/task/TID/comm) is `name`
  // and stops it. ok() says whether it worked; error() why not.
  StoppedThread(pid_t pid, const std::string& name);
  ~StoppedThread();
  StoppedThread(const StoppedThread&) = delete;
  StoppedThread& operator=(const StoppedThread&) = delete;

  bool ok() const { return tid_ > 0; }
  const std::string& error() const { return error_; }
  // Lets the thread run again (also done by the destructor).
  void release();

 private:
  pid_t tid_ = -1;
  std::string error_;
};

}  // namespace ceilpose::test
