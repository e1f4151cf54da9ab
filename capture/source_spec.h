#pragma once
// The SPEC §7 source grammar, once: synthetic | replay:DIR | v4l2:/dev/videoN
// | libcamera[:ID]. The configuration's check, make_frame_source() and the
// daemon's and recorder's decisions ("is this a replay?") all parse with this.
// Header-only: config/ checks values without linking capture.
#include <optional>
#include <string>
#include <string_view>

namespace ceilpose::capture {

inline constexpr std::string_view kSourceSpecForms =
    "synthetic | replay:DIR | v4l2:/dev/videoN | libcamera[:ID]";

enum class SourceKind { kSynthetic, kReplay, kV4l2, kLibcamera };

struct SourceSpec {
  SourceKind kind = SourceKind::kSynthetic;
  std::string argument;  // replay: the directory; v4l2: the device path; libcamera: the id or ""
};

// The parsed spec, or nullopt with `why` (if given) saying what is wrong.
// A V4L2 device path must be absolute; a replay directory non-empty.
inline std::optional<SourceSpec> parse_source_spec(std::string_view spec,
                                                   std::string* why = nullptr) {
  auto fail = [&](const char* text) -> std::optional<SourceSpec> {
    if (why != nullptr) *why = text;
    return std::nullopt;
  };
  auto after = [&](std::string_view prefix) { return std::string(spec.substr(prefix.size())); };
  if (spec == "synthetic") return SourceSpec{SourceKind::kSynthetic, {}};
  if (spec == "libcamera") return SourceSpec{SourceKind::kLibcamera, {}};
  if (spec.starts_with("replay:")) {
    if (spec.size() == 7) return fail("replay needs a recording directory");
    return SourceSpec{SourceKind::kReplay, after("replay:")};
  }
  if (spec.starts_with("v4l2:")) {
    if (spec.size() < 7 || spec[5] != '/') return fail("v4l2 needs an absolute device path");
    return SourceSpec{SourceKind::kV4l2, after("v4l2:")};
  }
  if (spec.starts_with("libcamera:")) {
    if (spec.size() == 10) return fail("libcamera: needs a camera id (or plain libcamera)");
    return SourceSpec{SourceKind::kLibcamera, after("libcamera:")};
  }
  return fail(spec.empty() ? "the source is empty" : "unknown source");
}

inline bool is_replay_spec(std::string_view spec) {
  const auto parsed = parse_source_spec(spec);
  return parsed && parsed->kind == SourceKind::kReplay;
}
inline bool is_synthetic_spec(std::string_view spec) {
  const auto parsed = parse_source_spec(spec);
  return parsed && parsed->kind == SourceKind::kSynthetic;
}

}  // namespace ceilpose::capture
