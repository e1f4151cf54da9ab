#include "daemon/signal_channel.h"

#include <poll.h>
#include <pthread.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace ceilpose::daemon {
namespace {

volatile std::sig_atomic_t g_noted_signal = 0;

void note_signal(int sig) { g_noted_signal = sig; }

}  // namespace

void hold_stop_signals() {
  struct sigaction action {};
  action.sa_handler = &note_signal;
  sigfillset(&action.sa_mask);
  for (int sig : {SIGTERM, SIGINT, SIGHUP}) sigaction(sig, &action, nullptr);
  sigset_t set;
  sigemptyset(&set);
  for (int sig : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&set, sig);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

SignalChannel::SignalChannel() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGHUP);
  if (const int r = pthread_sigmask(SIG_BLOCK, &set, &previous_); r != 0)
    throw std::system_error(r, std::generic_category(), "pthread_sigmask(SIG_BLOCK)");
  fd_ = signalfd(-1, &set, SFD_CLOEXEC | SFD_NONBLOCK);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "signalfd");
}

SignalChannel::~SignalChannel() {
  if (fd_ >= 0) close(fd_);
  pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
}

int SignalChannel::wait(int timeout_ms) {
  if (const int noted = g_noted_signal; noted != 0) {
    g_noted_signal = 0;
    return noted;
  }
  pollfd p{fd_, POLLIN, 0};
  const int r = poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
  if (r <= 0) return 0;  // timeout, or EINTR: the caller's loop comes back
  signalfd_siginfo info{};
  if (read(fd_, &info, sizeof(info)) != static_cast<ssize_t>(sizeof(info))) return 0;
  return static_cast<int>(info.ssi_signo);
}

}  // namespace ceilpose::daemon
