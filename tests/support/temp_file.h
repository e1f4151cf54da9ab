#pragma once
// Test support: files under the test temp dir, named per process and
// removed when the process exits, so that runs of the suite leave nothing
// behind in /tmp (they used to: ~1700 files after a few dozen runs).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

namespace ceilpose::test {

// The paths to remove at exit.
class TempFiles {
 public:
  static TempFiles& instance() {
    static TempFiles files;
    return files;
  }
  void add(const std::string& path) {
    const std::lock_guard lock(mutex_);
    paths_.push_back(path);
  }
  ~TempFiles() {
    for (const std::string& path : paths_) std::remove(path.c_str());
  }

 private:
  TempFiles() = default;
  std::mutex mutex_;
  std::vector<std::string> paths_;
};

// `text` in <temp dir>/<prefix>-<pid>-<name>, removed when the process exits.
inline std::string write_temp(const std::string& prefix, const std::string& name,
                              const std::string& text) {
  const std::string path =
      ::testing::TempDir() + prefix + "-" + std::to_string(getpid()) + "-" + name;
  std::ofstream(path) << text;
  TempFiles::instance().add(path);
  return path;
}

// The calibration tests' files.
inline std::string write_temp(const std::string& name, const std::string& text) {
  return write_temp("ceilpose-calibration", name, text);
}

}  // namespace ceilpose::test
