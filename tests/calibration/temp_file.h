#pragma once
// Test support: a file with `text` under the test temp dir, named per process.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

namespace ceilpose::test {

inline std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path =
      ::testing::TempDir() + "ceilpose-calibration-" + std::to_string(getpid()) + "-" + name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace ceilpose::test
