#include "core/message_text.h"

#include <cstdio>

namespace ceilpose {
namespace {

void append_escaped(std::string* out, std::string_view text) {
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u >= 0x7f) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\x%02X", static_cast<unsigned>(u));
      *out += esc;
    } else {
      *out += c;
    }
  }
}

}  // namespace

std::string shown_value(std::string_view text, size_t max_chars) {
  std::string out = "'";
  if (text.size() <= max_chars) {
    append_escaped(&out, text);
  } else {
    const size_t half = max_chars / 2;
    append_escaped(&out, text.substr(0, half));
    out += "...(" + std::to_string(text.size() - 2 * half) + " more bytes)...";
    append_escaped(&out, text.substr(text.size() - half));
  }
  return out + "'";
}

}  // namespace ceilpose
