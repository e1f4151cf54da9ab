// The child-process support itself, on /bin/sh scripts: exit codes, output
// capture, timeouts that kill, signal deaths reported, and no zombie left.
#include "tests/support/child_process.h"

#include <errno.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <string>

namespace ceilpose::test {
namespace {

constexpr int kTimeoutMs = 20000;  // generous: ASan on a loaded 2-core machine

std::vector<std::string> sh(const std::string& script) { return {"/bin/sh", "-c", script}; }

ChildOptions capturing_stderr() {
  ChildOptions o;
  o.capture_stderr = true;
  return o;
}

TEST(ChildProcess, ReportsTheExitCode) {
  ChildProcess child(sh("exit 3"));
  ASSERT_TRUE(child.started()) << child.start_error();
  const auto e = child.wait(kTimeoutMs);
  ASSERT_TRUE(e.has_value());
  EXPECT_TRUE(e->exited);
  EXPECT_EQ(e->code, 3);
  EXPECT_EQ(e->signal, 0);
  EXPECT_FALSE(child.running());
}

TEST(ChildProcess, WaitExitReturnsTheCode) {
  ChildProcess child(sh("exit 0"));
  EXPECT_EQ(child.wait_exit(kTimeoutMs), 0);
  ChildProcess failing(sh("exit 42"));
  EXPECT_EQ(failing.wait_exit(kTimeoutMs), 42);
}

TEST(ChildProcess, CapturesStdoutAndStderrApart) {
  ChildProcess child(sh("echo to-out; echo to-err >&2; echo more-out"), capturing_stderr());
  ASSERT_EQ(child.wait_exit(kTimeoutMs), 0);
  EXPECT_EQ(child.output(), "to-out\nmore-out\n");
  EXPECT_EQ(child.error_output(), "to-err\n");
}

TEST(ChildProcess, LeavesStderrToTheTestUnlessAsked) {
  ChildProcess child(sh("echo to-err >&2"));
  ASSERT_EQ(child.wait_exit(kTimeoutMs), 0);
  EXPECT_EQ(child.error_output(), "");
}

TEST(ChildProcess, ReadUntilReturnsWhileTheChildRuns) {
  ChildProcess child(sh("echo ready; exec sleep 60"));
  EXPECT_NE(child.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);
  EXPECT_TRUE(child.running());
}

TEST(ChildProcess, ReadUntilStopsWhenTheChildEndsWithoutTheNeedle) {
  ChildProcess child(sh("echo something-else"));
  EXPECT_EQ(child.read_until("ready", kTimeoutMs), "something-else\n");
}

TEST(ChildProcess, KeepsOutputUpToTheBoundAndNeverBlocksTheChild) {
  ChildOptions options;
  options.max_output_bytes = 1000;
  // 4 MB: more than the pipe holds (1 MiB at most), so the child ends only
  // if it is read.
  ChildProcess child({"/usr/bin/head", "-c", "4000000", "/dev/zero"}, options);
  EXPECT_EQ(child.wait_exit(kTimeoutMs), 0);
  EXPECT_EQ(child.output().size(), 1000u);
}

TEST(ChildProcess, ReadErrorUntilReturnsWhileTheChildRuns) {
  ChildProcess child(sh("echo waiting >&2; exec sleep 60"), capturing_stderr());
  EXPECT_EQ(child.read_error_until("waiting", kTimeoutMs), "waiting\n");
  EXPECT_TRUE(child.running());
  EXPECT_EQ(child.output(), "");
}

TEST(ChildProcess, ReadErrorUntilIsEmptyWhenStderrIsNotCaptured) {
  ChildProcess child(sh("echo waiting >&2; exec sleep 60"));
  EXPECT_EQ(child.read_error_until("waiting", kTimeoutMs), "");
}

TEST(ChildProcess, WaitTimesOutAndLeavesTheChildRunning) {
  ChildProcess child(sh("exec sleep 60"));
  EXPECT_FALSE(child.wait(10).has_value());
  EXPECT_TRUE(child.running());
}

TEST(ChildProcess, WaitExitKillsAtTheDeadline) {
  ChildProcess child(sh("exec sleep 60"));
  EXPECT_EQ(child.wait_exit(10), -1);
  EXPECT_FALSE(child.running());
}

TEST(ChildProcess, ReportsDeathBySignal) {
  ChildProcess child(sh("kill -USR1 $$"));
  const auto e = child.wait(kTimeoutMs);
  ASSERT_TRUE(e.has_value());
  EXPECT_FALSE(e->exited);
  EXPECT_EQ(e->code, -1);
  EXPECT_EQ(e->signal, SIGUSR1);
}

TEST(ChildProcess, TerminateEndsAChildThatHonoursSigterm) {
  ChildProcess child(sh("exec sleep 60"));
  const ExitStatus e = child.terminate(kTimeoutMs);
  EXPECT_FALSE(e.exited);
  EXPECT_EQ(e.signal, SIGTERM);
}

TEST(ChildProcess, TerminateKillsAChildThatIgnoresSigterm) {
  // SIG_IGN survives exec: sleep ignores SIGTERM too.
  ChildProcess child(sh("trap '' TERM; echo ready; exec sleep 60"));
  ASSERT_NE(child.read_until("ready", kTimeoutMs).find("ready"), std::string::npos);
  const ExitStatus e = child.terminate(50);
  EXPECT_FALSE(e.exited);
  EXPECT_EQ(e.signal, SIGKILL);
}

TEST(ChildProcess, AppliesEnvironmentChanges) {
  ::setenv("CEILPOSE_CHILD_TEST_REMOVED", "still-here", 1);
  ChildOptions options;
  options.env["CEILPOSE_CHILD_TEST_ADDED"] = "added";
  options.env["CEILPOSE_CHILD_TEST_REMOVED"] = "";
  ChildProcess child(
      sh("echo \"${CEILPOSE_CHILD_TEST_ADDED}/${CEILPOSE_CHILD_TEST_REMOVED-unset}\""), options);
  ASSERT_EQ(child.wait_exit(kTimeoutMs), 0);
  EXPECT_EQ(child.output(), "added/unset\n");
  ::unsetenv("CEILPOSE_CHILD_TEST_REMOVED");
}

TEST(ChildProcess, GivesTheChildAnEmptyStdin) {
  ChildProcess child(sh("cat"));
  EXPECT_EQ(child.wait_exit(kTimeoutMs), 0);
  EXPECT_EQ(child.output(), "");
}

TEST(ChildProcess, SaysWhyAProgramCannotStart) {
  ChildProcess child({"/nonexistent/program"});
  EXPECT_FALSE(child.started());
  EXPECT_NE(child.start_error().find("/nonexistent/program"), std::string::npos)
      << child.start_error();
  EXPECT_FALSE(child.running());
  EXPECT_EQ(child.wait_exit(kTimeoutMs), -1);
}

TEST(ChildProcess, DestructorKillsAndReapsARunningChild) {
  pid_t pid = -1;
  {
    ChildProcess child(sh("exec sleep 60"));
    ASSERT_TRUE(child.started());
    pid = child.pid();
  }
  // Reaped: no zombie of it is left for this process to wait for.
  errno = 0;
  EXPECT_EQ(waitpid(pid, nullptr, WNOHANG), -1);
  EXPECT_EQ(errno, ECHILD);
}

TEST(RunToEnd, ReturnsTheCodeAndBothStreams) {
  const RunOutput r = run_to_end(sh("echo to-out; echo to-err >&2; exit 4"), kTimeoutMs);
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_EQ(r.out, "to-out\n");
  EXPECT_EQ(r.err, "to-err\n");
  EXPECT_EQ(r.failure, "");
}

TEST(RunToEnd, KillsAtTheDeadlineAndKeepsWhatWasWritten) {
  const RunOutput r = run_to_end(sh("echo started; exec sleep 60"), 200);
  EXPECT_EQ(r.exit_code, -1);
  EXPECT_EQ(r.out, "started\n");
  EXPECT_NE(r.failure.find("still running after 200 ms"), std::string::npos) << r.failure;
}

TEST(RunToEnd, SaysWhyAProgramCannotStart) {
  const RunOutput r = run_to_end({"/nonexistent/program"}, kTimeoutMs);
  EXPECT_EQ(r.exit_code, -1);
  EXPECT_NE(r.failure.find("/nonexistent/program"), std::string::npos) << r.failure;
}

}  // namespace
}  // namespace ceilpose::test
