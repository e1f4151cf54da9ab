#pragma once
// Helpers for the shared-memory tests: unique segment names, a pose whose
// fields all derive from its sequence number (a torn copy breaks the
// relation), and a forked child process with a one-byte handshake.
#include <gtest/gtest.h>
#include <sys/types.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ipc/shm/pose_record.h"
#include "ipc/shm/shm_pose_reader.h"
#include "ipc/shm/shm_pose_writer.h"

namespace ceilpose::test {

// Sanitizers slow the hammer loops down; scale them, never the assertions.
#if defined(__SANITIZE_THREAD__)
inline constexpr uint64_t kSanitizerDivisor = 10;
#elif defined(__SANITIZE_ADDRESS__)
inline constexpr uint64_t kSanitizerDivisor = 4;
#else
inline constexpr uint64_t kSanitizerDivisor = 1;
#endif

// "/ceilpose-test-<pid>-<test name>", unique per process and test.
std::string unique_shm_name();

// Removes the segment (and companion) of `name` when it goes out of scope.
class ScopedSegmentName {
 public:
  ScopedSegmentName() : name_(unique_shm_name()) {}
  ~ScopedSegmentName();
  ScopedSegmentName(const ScopedSegmentName&) = delete;
  ScopedSegmentName& operator=(const ScopedSegmentName&) = delete;
  const std::string& str() const { return name_; }

 private:
  std::string name_;
};

// A pose whose payload is a function of `k`; the writer sets seq = k when it
// publishes the k-th pose.
PoseRecord check_pose(uint64_t k);
// True when every field agrees with p.seq (the pose was copied whole).
bool is_consistent(const PoseRecord& p);

// A forked child running `body` in a copy of the test process (a separate
// program runs through tests/support's ChildProcess instead). The child
// exits with body's return value (never returns into the test framework).
// It can signal the parent once with notify_parent(), the parent can
// release it with release_child().
class ForkedChild {
 public:
  using Body = std::function<int(ForkedChild&)>;
  explicit ForkedChild(Body body);
  ~ForkedChild();  // kills and reaps the child if still running
  ForkedChild(const ForkedChild&) = delete;
  ForkedChild& operator=(const ForkedChild&) = delete;

  pid_t pid() const { return pid_; }
  // Parent side: waits up to timeout_ms for the child's notify; false on
  // timeout or if the child exited first.
  bool wait_for_child(int timeout_ms);
  void release_child();
  // Child side.
  void notify_parent();
  bool wait_for_parent(int timeout_ms);

  void kill_child(int signal);
  // Waits up to timeout_ms; returns the exit status (WEXITSTATUS), 128+signal
  // if killed, -1 on timeout.
  int wait_exit(int timeout_ms);

 private:
  pid_t pid_ = -1;
  int to_parent_[2] = {-1, -1};
  int to_child_[2] = {-1, -1};
  bool reaped_ = false;
};

// A child body that creates a writer on `name` (exit 10 if it cannot) and
// then runs `then` with it.
ForkedChild::Body writer_child(const std::string& name,
                               std::function<int(ShmPoseWriter&, ForkedChild&)> then);

// A unique segment name per test, plus a writer and a reader on it.
class ShmFixture : public ::testing::Test {
 protected:
  // Creates the writer and opens a reader; use with ASSERT_NO_FATAL_FAILURE.
  void start(int heartbeat_period_ms = 50, int stale_after_ms = ShmOptions{}.stale_after_ms);
  const std::string& name() const { return name_.str(); }
  ShmPoseWriter& writer() { return *writer_; }
  ShmPoseReader& reader() { return *reader_; }

  ScopedSegmentName name_;
  std::optional<ShmPoseWriter> writer_;
  std::optional<ShmPoseReader> reader_;
};

// Waits up to timeout_ms until thread `tid` of this process sits blocked in
// one of `syscalls` (numbers from <sys/syscall.h>), as /proc/self/task/TID/
// syscall shows it: the handshake that proves a reader really blocked before
// the event it waits for, instead of a sleep that only makes it likely.
bool wait_until_blocked_in(pid_t tid, const std::vector<long>& syscalls, int timeout_ms);

// The syscalls a blocked wait_next() and a waiting open_waiting() sit in.
std::vector<long> futex_syscalls();
std::vector<long> poll_syscalls();

}  // namespace ceilpose::test
