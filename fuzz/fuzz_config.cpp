// The configuration loader on arbitrary text: an error or a configuration,
// never a crash (SPEC §7, config/config_loader.cpp). A configuration it
// accepts, dumped and loaded again, is the same configuration.
#include <cstddef>
#include <cstdint>
#include <string>

#include "config/service_config.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace ceilpose;
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto config = load_config_string(text, "fuzz.yaml");
  if (!config) return 0;
  const std::string dumped = dump_config(*config);
  const auto again = load_config_string(dumped, "dumped.yaml");
  if (!again)
    fuzz::invariant_broken("fuzz_config", "its own dump is refused: " + again.error().message);
  if (config_values(*again) != config_values(*config))
    fuzz::invariant_broken("fuzz_config", "dumped and loaded, the configuration changed");
  return 0;
}
