// The configuration loader on arbitrary text: an error or a configuration,
// never a crash (SPEC §7, config/config_loader.cpp).
#include <cstddef>
#include <cstdint>
#include <string>

#include "config/service_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)ceilpose::load_config_string(text, "fuzz.yaml");
  return 0;
}
