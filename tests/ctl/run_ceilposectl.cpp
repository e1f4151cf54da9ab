#include "tests/ctl/run_ceilposectl.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <map>
#include <thread>

#include "tests/recording/recording_test_support.h"

extern char** environ;

namespace ceilpose::test {

CommandOutput run_ceilposectl(const std::vector<std::string>& args, const std::string& scratch_dir,
                              int timeout_ms) {
  CommandOutput result;
  const std::string out_path = scratch_dir + "/ceilposectl.out";
  const std::string err_path = scratch_dir + "/ceilposectl.err";
  std::vector<std::string> argv_text{CEILPOSECTL_PATH};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, CEILPOSECTL_PATH, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    ADD_FAILURE() << "cannot start " << CEILPOSECTL_PATH << ": " << std::strerror(rc);
    return result;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  int status = 0;
  while (true) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      ADD_FAILURE() << "ceilposectl did not finish within " << timeout_ms << " ms";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  result.out = read_text_file(out_path);
  result.err = read_text_file(err_path);
  return result;
}

bool has_subcommand(const std::string& name, const std::string& scratch_dir) {
  // Asked once per name: every start of ceilposectl costs a few hundred ms.
  static std::map<std::string, bool> known;
  const auto it = known.find(name);
  if (it != known.end()) return it->second;
  const bool has = run_ceilposectl({name, "--help"}, scratch_dir).exit_code == 0;
  known[name] = has;
  return has;
}

}  // namespace ceilpose::test
