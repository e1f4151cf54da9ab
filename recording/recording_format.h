#pragma once
// Names fixed by SPEC §4, shared by the reader and the writer.
namespace ceilpose::recording_format {

inline constexpr const char* kYamlName = "recording.yaml";
inline constexpr const char* kCsvName = "frames.csv";
inline constexpr const char* kFramesDir = "frames";
inline constexpr const char* kFormat = "ceilpose-recording";
inline constexpr int kVersion = 1;
inline constexpr int kDistortionCoefficients = 5;  // k1 k2 p1 p2 k3 (plumb_bob)

}  // namespace ceilpose::recording_format
