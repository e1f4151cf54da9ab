#pragma once
// Values from files and command lines as error messages show them: quoted,
// with bytes that would not show (controls, non-ASCII) as \xNN, and cut in
// the middle when long, so that a 10 MB field names itself in one line.
#include <cstddef>
#include <string>
#include <string_view>

namespace ceilpose {

inline constexpr size_t kShownValueChars = 160;

// 'text', escaped, at most about max_chars characters of it (the start and
// the end, and how many bytes were left out between them).
std::string shown_value(std::string_view text, size_t max_chars = kShownValueChars);

}  // namespace ceilpose
