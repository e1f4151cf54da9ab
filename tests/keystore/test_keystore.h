#pragma once
// Test support: a keystore in a fresh temporary directory, with a CA and an
// enclave per named robot, made by keystore/ (the library behind `ceilposectl
// keys`), removed with its directory.
#include <ctime>
#include <initializer_list>
#include <string>

#include "ipc/dds/dds_options.h"
#include "keystore/keystore.h"
#include "keystore/keystore_layout.h"
#include "tests/recording/recording_test_support.h"

namespace ceilpose::test {

class TestKeystore {
 public:
  // The CA is valid from 30 days ago, so that enclaves can be back-dated.
  explicit TestKeystore(std::initializer_list<const char*> robots);
  const std::string& dir() const { return dir_; }
  keystore::KeystoreLayout layout() const { return {dir_}; }
  DdsSecurityFiles files(const std::string& robot) const { return layout().enclave_files(robot); }
  // Adds (or replaces) `robot` valid from `not_before` for `days`.
  void add(const std::string& robot, std::time_t not_before, int days) const;
  // Another keystore's directory beside this one ("other" + n).
  std::string sibling(const std::string& name) const { return tmp_.sub(name); }

 private:
  TempDir tmp_;
  std::string dir_;
};

}  // namespace ceilpose::test
