#include "core/text_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "core/unique_fd.h"

namespace ceilpose {

Result<std::string> read_text_file(const std::string& path, const char* what, size_t max_bytes) {
  const std::string prefix = path + ": cannot read " + what + ": ";
  UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (!fd.valid()) return make_error(prefix + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) return make_error(prefix + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) {
    return make_error(prefix + (S_ISDIR(st.st_mode) ? "it is a directory" : "not a regular file"));
  }
  if (static_cast<size_t>(st.st_size) > max_bytes) {
    return make_error(prefix + "larger than " + std::to_string(max_bytes >> 20) + " MiB");
  }
  std::string text(static_cast<size_t>(st.st_size), '\0');
  size_t got = 0;
  while (got < text.size()) {
    const ssize_t n = ::read(fd.get(), text.data() + got, text.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return make_error(prefix + std::strerror(errno));
    if (n == 0) break;  // shrank while read: take what is there
    got += static_cast<size_t>(n);
  }
  text.resize(got);
  return text;
}

namespace {

Result<void> write_all(int fd, const std::string& path, const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, p + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return make_error(path + ": write error (" + std::strerror(errno) + ")");
    done += static_cast<size_t>(n);
  }
  return {};
}

}  // namespace

Result<void> write_file(const std::string& path, const void* data, size_t size) {
  // O_NOFOLLOW: a symbolic link planted where an output file goes (in a
  // directory another user can write) is not followed (issue 28 #11).
  UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644));
  if (!fd.valid() && errno == ELOOP)
    return make_error(path + ": is a symbolic link: not followed; remove it or write elsewhere");
  if (!fd.valid()) return make_error(path + ": cannot create (" + std::strerror(errno) + ")");
  if (auto wrote = write_all(fd.get(), path, data, size); !wrote) return wrote;
  if (::close(fd.release()) != 0)
    return make_error(path + ": close error (" + std::strerror(errno) + ")");
  return {};
}

Result<void> replace_file(const std::string& path, const std::string& text, unsigned mode) {
  const std::string tmp = path + ".tmp";
  // O_EXCL and fchmod: a temporary file left by someone else is never
  // reused with its own, wider, permissions.
  ::unlink(tmp.c_str());
  UniqueFd fd(::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode));
  if (!fd.valid()) return make_error(tmp + ": cannot create (" + std::strerror(errno) + ")");
  auto wrote =
      ::fchmod(fd.get(), mode) == 0
          ? write_all(fd.get(), tmp, text.data(), text.size())
          : Result<void>(make_error(tmp + ": cannot set mode (" + std::strerror(errno) + ")"));
  if (wrote && ::fsync(fd.get()) != 0)
    wrote = make_error(tmp + ": cannot flush to disk (" + std::strerror(errno) + ")");
  if (wrote && ::close(fd.release()) != 0)
    wrote = make_error(tmp + ": close error (" + std::strerror(errno) + ")");
  if (wrote && ::rename(tmp.c_str(), path.c_str()) != 0)
    wrote = make_error(path + ": cannot replace (" + std::strerror(errno) + ")");
  if (!wrote) ::unlink(tmp.c_str());
  return wrote;
}

}  // namespace ceilpose
