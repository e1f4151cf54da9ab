#pragma once
// Turns a Cyclone return code into an Error that says what was attempted.
#include <dds/dds.h>

#include <string>
#include <string_view>

#include "core/result.h"

namespace ceilpose {

inline Error dds_error(std::string_view what, dds_return_t rc) {
  return make_error(std::string(what) + ": " + dds_strretcode(rc));
}

}  // namespace ceilpose
