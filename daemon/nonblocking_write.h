#pragma once
// Writes a line to a descriptor the daemon does not own (stdout for
// --print-poses, stderr for the log) without ever blocking: a terminal
// nobody reads, a pipe into a stalled program or a full disk must not stop
// the control thread, which feeds the watchdog and hears SIGTERM.
#include <cstddef>

namespace ceilpose::daemon {

enum class WriteOutcome {
  kWritten,
  kDropped,  // the reader is not keeping up (full pipe or terminal): line lost
  kClosed,   // nobody will ever read (EPIPE; SIGPIPE is ignored)
  kFailed,   // an error such as ENOSPC or EIO; errno says which
};

// One write(2) of the whole line, only when poll() says the descriptor takes
// data now. A line of at most PIPE_BUF bytes then goes into a pipe whole or
// not at all.
WriteOutcome write_without_blocking(int fd, const char* data, size_t size);

}  // namespace ceilpose::daemon
