#include "tests/keystore/test_keystore.h"

#include <stdexcept>

namespace ceilpose::test {

TestKeystore::TestKeystore(std::initializer_list<const char*> robots) : dir_(tmp_.sub("keystore")) {
  const std::time_t now = std::time(nullptr);
  if (auto ok = keystore::init_keystore(dir_, {now - 30 * 24 * 3600, keystore::kDefaultCaDays});
      !ok) {
    throw std::runtime_error(ok.error().message);
  }
  for (const char* robot : robots) add(robot, now, 30);
}

void TestKeystore::add(const std::string& robot, std::time_t not_before, int days) const {
  const keystore::EnclaveRequest request{
      .name = robot, .validity = {not_before, days}, .replace = true};
  if (auto ok = keystore::add_enclave(dir_, request); !ok) {
    throw std::runtime_error(ok.error().message);
  }
}

}  // namespace ceilpose::test
