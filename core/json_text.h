#pragma once
// Text helpers for the JSON that ceilposectl and the daemon print by hand
// (JSON Lines, status): one quoting rule for every command.
#include <string>
#include <string_view>

namespace ceilpose {

// `text` as a JSON string literal, with its quotes; control characters escaped.
std::string json_quote(std::string_view text);

// The value to print with `decimals` decimals (printf "%.*f") so that the
// printed number, read back, still lies in SPEC §1's (−π, π]: plain rounding
// turns a yaw within half a last digit of ±π into 3.1415927 or −3.1415927
// (7 decimals), both outside. Those print as the largest decimal below π.
double printable_yaw_rad(double yaw_rad, int decimals);

struct Pose2D;
// SPEC §5's pose fields, the one place their names are written:
// ,"x_m":…,"y_m":…,"yaw_rad":… with 7 decimals (the yaw printable), or the
// three as null without a pose. A non-finite number is null too: JSON has no
// NaN. `locate`, `pose`/`watch` and `fleet` all print them through this.
std::string pose_fields_json(const Pose2D* pose);

}  // namespace ceilpose
