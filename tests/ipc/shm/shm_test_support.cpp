#include "shm_test_support.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.h"

namespace ceilpose::test {

std::string unique_shm_name() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string test = info != nullptr ? info->name() : "none";
  for (char& c : test) {
    if (c == '/') c = '_';
  }
  return "/ceilpose-test-" + std::to_string(::getpid()) + "-" + test.substr(0, 150);
}

ScopedSegmentName::~ScopedSegmentName() { (void)ShmPoseWriter::remove(name_); }

PoseRecord check_pose(uint64_t k) {
  PoseRecord p{};
  p.capture_mono_ns = static_cast<int64_t>(k) * 3;
  p.capture_real_ns = static_cast<int64_t>(k) * 5;
  p.publish_mono_ns = static_cast<int64_t>(k) * 7;
  p.publish_real_ns = static_cast<int64_t>(k) * 11;
  p.x_m = static_cast<double>(k);
  p.y_m = -0.5 * static_cast<double>(k);
  p.yaw_rad = static_cast<double>(k % 1000) * 1e-3;
  for (int i = 0; i < 9; ++i) p.covariance[i] = static_cast<double>(k + i);
  p.flags = kPoseValid | static_cast<uint32_t>((k & 1) != 0 ? kPoseFiltered : 0);
  p.mode = static_cast<uint8_t>(k % 4);
  p.markers = static_cast<uint16_t>(k & 0xffff);
  // The motion words too: a torn copy of the record's tail must show.
  p.vx_mps = static_cast<double>(k) * 0.25;
  for (int i = 0; i < CEILPOSE_STATE_SIZE * CEILPOSE_STATE_SIZE; ++i)
    p.state_covariance[i] = static_cast<double>(k * 3 + static_cast<uint64_t>(i));
  p.predict_horizon_ms = static_cast<uint32_t>(k);
  return p;
}

bool is_consistent(const PoseRecord& p) {
  PoseRecord expected = check_pose(p.seq);
  expected.seq = p.seq;
  return std::memcmp(&expected, &p, sizeof p) == 0;
}

namespace {

bool wait_byte(int fd, int timeout_ms) {
  pollfd pfd{fd, POLLIN, 0};
  if (::poll(&pfd, 1, timeout_ms) != 1) return false;
  char c = 0;
  return ::read(fd, &c, 1) == 1;
}

void send_byte(int fd) {
  const char c = 1;
  while (::write(fd, &c, 1) < 0 && errno == EINTR) {
  }
}

}  // namespace

ForkedChild::ForkedChild(Body body) {
  if (::pipe2(to_parent_, O_CLOEXEC) != 0 || ::pipe2(to_child_, O_CLOEXEC) != 0) {
    ADD_FAILURE() << "pipe2 failed: " << std::strerror(errno);
    return;
  }
  pid_ = ::fork();
  if (pid_ == 0) {
    ::close(to_parent_[0]);
    ::close(to_child_[1]);
    const int rc = body(*this);
    ::_exit(rc);
  }
  ::close(to_parent_[1]);
  ::close(to_child_[0]);
  to_parent_[1] = -1;
  to_child_[0] = -1;
}

ForkedChild::~ForkedChild() {
  if (pid_ > 0 && !reaped_) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  for (int fd : {to_parent_[0], to_child_[1]}) {
    if (fd >= 0) ::close(fd);
  }
}

bool ForkedChild::wait_for_child(int timeout_ms) { return wait_byte(to_parent_[0], timeout_ms); }
void ForkedChild::release_child() { send_byte(to_child_[1]); }
void ForkedChild::notify_parent() { send_byte(to_parent_[1]); }
bool ForkedChild::wait_for_parent(int timeout_ms) { return wait_byte(to_child_[0], timeout_ms); }

void ForkedChild::kill_child(int signal) {
  if (pid_ > 0 && !reaped_) ::kill(pid_, signal);
}

int ForkedChild::wait_exit(int timeout_ms) {
  if (pid_ <= 0) return -1;
  const int64_t deadline = monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
  for (;;) {
    int status = 0;
    const pid_t r = ::waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      reaped_ = true;
      if (WIFEXITED(status)) return WEXITSTATUS(status);
      if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
      return -1;
    }
    if (monotonic_ns() > deadline) return -1;
    ::usleep(2000);
  }
}

ForkedChild::Body writer_child(const std::string& name,
                               std::function<int(ShmPoseWriter&, ForkedChild&)> then) {
  return [name, then](ForkedChild& self) {
    ShmOptions options;
    options.name = name;
    auto writer = ShmPoseWriter::create(options);
    if (!writer) return 10;
    return then(writer.value(), self);
  };
}

void ShmFixture::start(int heartbeat_period_ms, int stale_after_ms) {
  ShmOptions options;
  options.name = name();
  options.heartbeat_period_ms = heartbeat_period_ms;
  options.stale_after_ms = stale_after_ms;
  auto writer = ShmPoseWriter::create(options);
  ASSERT_TRUE(writer) << writer.error().message;
  writer_.emplace(std::move(writer.value()));
  auto reader = ShmPoseReader::open(name());
  ASSERT_TRUE(reader) << reader.error().message;
  reader_.emplace(std::move(reader.value()));
}

bool wait_until_blocked_in(pid_t tid, const std::vector<long>& syscalls, int timeout_ms) {
  const std::string path = "/proc/self/task/" + std::to_string(tid) + "/syscall";
  const int64_t deadline_ns = monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
  while (monotonic_ns() < deadline_ns) {
    std::ifstream in(path);
    long nr = -1;
    if (in >> nr) {  // "running" when it is not in a syscall: no number
      for (long s : syscalls)
        if (nr == s) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

std::vector<long> futex_syscalls() { return {SYS_futex}; }

std::vector<long> poll_syscalls() {
#ifdef SYS_poll
  return {SYS_poll, SYS_ppoll};
#else
  return {SYS_ppoll};  // aarch64 has ppoll only
#endif
}

}  // namespace ceilpose::test
