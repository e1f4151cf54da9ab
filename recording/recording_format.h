#pragma once
#include <string_view>

// Names fixed by SPEC §4, shared by the reader and the writer.
namespace ceilpose::recording_format {

inline constexpr const char* kYamlName = "recording.yaml";
inline constexpr const char* kCsvName = "frames.csv";
inline constexpr const char* kFramesDir = "frames";
inline constexpr const char* kFormat = "ceilpose-recording";
inline constexpr int kVersion = 1;
inline constexpr int kDistortionCoefficients = 5;  // k1 k2 p1 p2 k3 (plumb_bob)

// frames.csv's columns, in the order the writer puts them: three required,
// then the optional ground truth (all three or none).
inline constexpr const char* kColIndex = "index";
inline constexpr const char* kColTimestamp = "timestamp_ns";
inline constexpr const char* kColFile = "file";
inline constexpr const char* kColGtX = "gt_x_m";
inline constexpr const char* kColGtY = "gt_y_m";
inline constexpr const char* kColGtYaw = "gt_yaw_rad";
// The header lines the writer writes (a test checks they are the names above).
inline constexpr std::string_view kHeader = "index,timestamp_ns,file\n";
inline constexpr std::string_view kHeaderWithTruth =
    "index,timestamp_ns,file,gt_x_m,gt_y_m,gt_yaw_rad\n";

}  // namespace ceilpose::recording_format
