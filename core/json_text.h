#pragma once
// Text helpers for the JSON that ceilposectl and the daemon print by hand
// (JSON Lines, status): one quoting rule for every command.
#include <string>
#include <string_view>

namespace ceilpose {

// `text` as a JSON string literal, with its quotes; control characters escaped.
std::string json_quote(std::string_view text);

}  // namespace ceilpose
