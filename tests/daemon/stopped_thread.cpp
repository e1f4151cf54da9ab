#include "tests/daemon/stopped_thread.h"

#include <dirent.h>
#include <sys/ptrace.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>
#include <fstream>

namespace ceilpose::test {
namespace {

pid_t find_thread(pid_t pid, const std::string& name) {
  const std::string tasks = "/proc/" + std::to_string(pid) + "/task";
  DIR* dir = ::opendir(tasks.c_str());
  if (dir == nullptr) return -1;
  pid_t found = -1;
  while (dirent* e = ::readdir(dir)) {
    if (e->d_name[0] == '.') continue;
    std::ifstream comm(tasks + "/" + e->d_name + "/comm");
    std::string text;
    std::getline(comm, text);
    if (text == name) {
      found = static_cast<pid_t>(std::stol(e->d_name));
      break;
    }
  }
  ::closedir(dir);
  return found;
}

}  // namespace

StoppedThread::StoppedThread(pid_t pid, const std::string& name) {
  const pid_t tid = find_thread(pid, name);
  if (tid < 0) {
    error_ = "no thread '" + name + "' in process " + std::to_string(pid);
    return;
  }
  // SEIZE + INTERRUPT stops this one thread, unlike SIGSTOP (the process).
  if (::ptrace(PTRACE_SEIZE, tid, nullptr, nullptr) != 0) {
    error_ = "PTRACE_SEIZE of thread " + std::to_string(tid) + ": " + std::strerror(errno);
    return;
  }
  int status = 0;
  if (::ptrace(PTRACE_INTERRUPT, tid, nullptr, nullptr) != 0 ||
      ::waitpid(tid, &status, __WALL) != tid || !WIFSTOPPED(status)) {
    error_ = "stopping thread " + std::to_string(tid) + ": " + std::strerror(errno);
    ::ptrace(PTRACE_DETACH, tid, nullptr, nullptr);
    return;
  }
  tid_ = tid;
}

StoppedThread::~StoppedThread() { release(); }

void StoppedThread::release() {
  if (tid_ > 0) ::ptrace(PTRACE_DETACH, tid_, nullptr, nullptr);
  tid_ = -1;
}

}  // namespace ceilpose::test
