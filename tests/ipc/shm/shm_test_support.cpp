#include "shm_test_support.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "core/clock.h"

extern char** environ;

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

void ShmFixture::start(int heartbeat_period_ms) {
  ShmOptions options;
  options.name = name();
  options.heartbeat_period_ms = heartbeat_period_ms;
  auto writer = ShmPoseWriter::create(options);
  ASSERT_TRUE(writer) << writer.error().message;
  writer_.emplace(std::move(writer.value()));
  auto reader = ShmPoseReader::open(name());
  ASSERT_TRUE(reader) << reader.error().message;
  reader_.emplace(std::move(reader.value()));
}

SpawnedProgram::SpawnedProgram(const std::string& path, const std::vector<std::string>& args) {
  int out[2];
  int err[2];
  if (::pipe2(out, O_CLOEXEC) != 0) return;
  if (::pipe2(err, O_CLOEXEC) != 0) {
    ::close(out[0]);
    ::close(out[1]);
    return;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], 1);
  posix_spawn_file_actions_adddup2(&actions, err[1], 2);
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(path.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, path.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(out[1]);
  ::close(err[1]);
  out_fd_ = out[0];
  err_fd_ = err[0];
  if (rc == 0) pid_ = pid;
}

SpawnedProgram::~SpawnedProgram() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  for (int fd : {out_fd_, err_fd_}) {
    if (fd >= 0) ::close(fd);
  }
}

bool SpawnedProgram::pump(int timeout_ms) {
  pollfd pfds[2] = {{out_fd_, POLLIN, 0}, {err_fd_, POLLIN, 0}};
  if (out_fd_ < 0 && err_fd_ < 0) return false;
  if (::poll(pfds, 2, timeout_ms) <= 0) return true;
  char buf[4096];
  for (int i = 0; i < 2; ++i) {
    if ((pfds[i].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
    int& fd = i == 0 ? out_fd_ : err_fd_;
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) {
      (i == 0 ? out_ : err_).append(buf, static_cast<size_t>(n));
    } else {
      ::close(fd);
      fd = -1;
    }
  }
  return true;
}

bool SpawnedProgram::wait_for_stdout(const std::string& text, int timeout_ms) {
  const int64_t deadline = monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
  while (out_.find(text) == std::string::npos) {
    const int64_t left_ms = (deadline - monotonic_ns()) / 1'000'000;
    if (left_ms <= 0 || !pump(static_cast<int>(left_ms))) return false;
  }
  return true;
}

bool SpawnedProgram::wait_for_stderr(const std::string& text, int timeout_ms) {
  const int64_t deadline = monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
  while (err_.find(text) == std::string::npos) {
    const int64_t left_ms = (deadline - monotonic_ns()) / 1'000'000;
    if (left_ms <= 0 || !pump(static_cast<int>(left_ms))) return false;
  }
  return true;
}

int SpawnedProgram::finish(int timeout_ms) {
  if (pid_ <= 0) return -1;
  const int64_t deadline = monotonic_ns() + int64_t{timeout_ms} * 1'000'000;
  bool timed_out = false;
  for (;;) {
    const int64_t left_ms = (deadline - monotonic_ns()) / 1'000'000;
    if (left_ms <= 0) {
      timed_out = true;
      break;
    }
    if (!pump(static_cast<int>(left_ms))) break;
  }
  if (timed_out) ::kill(pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
  if (timed_out) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + WTERMSIG(status);
}

int run_program(const std::string& path, const std::vector<std::string>& args, int timeout_ms,
                std::string* stdout_text, std::string* stderr_text) {
  SpawnedProgram program(path, args);
  if (!program.started()) return -1;
  const int rc = program.finish(timeout_ms);
  if (stdout_text != nullptr) *stdout_text = program.out();
  if (stderr_text != nullptr) *stderr_text = program.err();
  return rc;
}

}  // namespace ceilpose::test
