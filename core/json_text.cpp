#include "core/json_text.h"

#include <cmath>
#include <cstdio>

#include "core/pose.h"

namespace ceilpose {

std::string json_quote(std::string_view text) {
  std::string out = "\"";
  out.reserve(text.size() + 2);
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char esc[8];
          std::snprintf(esc, sizeof esc, "\\u%04x",
                        static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += esc;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

double printable_yaw_rad(double yaw_rad, int decimals) {
  if (!std::isfinite(yaw_rad)) return yaw_rad;
  const double scale = std::pow(10.0, decimals);
  const double printed = std::round(yaw_rad * scale) / scale;
  if (printed > M_PI || printed <= -M_PI) return std::floor(M_PI * scale) / scale;
  return yaw_rad;
}

std::string pose_fields_json(const Pose2D* pose) {
  if (pose == nullptr) return R"(,"x_m":null,"y_m":null,"yaw_rad":null)";
  const auto number = [](double v) {
    if (!std::isfinite(v)) return std::string("null");
    char text[48];
    std::snprintf(text, sizeof text, "%.7f", v);
    return std::string(text);
  };
  return ",\"x_m\":" + number(pose->x_m) + ",\"y_m\":" + number(pose->y_m) +
         ",\"yaw_rad\":" + number(printable_yaw_rad(pose->yaw_rad, 7));
}

}  // namespace ceilpose
