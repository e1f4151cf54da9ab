#include "fuzz/fuzz_support.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace ceilpose::fuzz {

namespace {

std::string scratch_path() { return "/dev/shm/ceilpose-fuzz-" + std::to_string(::getpid()); }

// At exit: /dev/shm is memory, and every fuzz run used to leave its directory.
void remove_scratch() {
  std::error_code ec;
  std::filesystem::remove_all(scratch_path(), ec);
}

}  // namespace

const std::string& scratch_dir() {
  static const std::string dir = [] {
    std::atexit(remove_scratch);
    return scratch_path();
  }();
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  std::filesystem::create_directories(dir, ec);
  return dir;
}

void write_bytes(const std::string& path, std::string_view bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void split_input(const uint8_t* data, size_t size, std::string_view* parts, int count) {
  constexpr std::string_view kCut = "\n--8<--\n";
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  for (int k = 0; k < count; ++k) {
    const size_t at = k + 1 < count ? rest.find(kCut) : std::string_view::npos;
    parts[k] = rest.substr(0, at);
    rest = at == std::string_view::npos ? std::string_view() : rest.substr(at + kCut.size());
  }
}

void invariant_broken(const char* target, const std::string& what) {
  std::fprintf(stderr, "%s: invariant broken: %s\n", target, what.c_str());
  std::abort();
}

}  // namespace ceilpose::fuzz
