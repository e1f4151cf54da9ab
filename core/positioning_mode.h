#pragma once
// The positioning methods and their names, once for every module: the
// pipeline chooses by them, the configuration and the command line name
// them, the shared-memory record and DDS status carry their values (the C
// client's CEILPOSE_MODE_* must equal them).
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ceilpose {

// Positioning methods: the thesis's two (one marker, three markers), and least
// squares over all markers, which uses every point the view offers.
enum class PositioningMode : uint8_t {
  kAuto = 0,
  kChangeOfAxes = 1,
  kBarycentric = 2,
  kLeastSquares = 3
};

inline constexpr std::array<PositioningMode, 4> kPositioningModes{
    PositioningMode::kAuto, PositioningMode::kChangeOfAxes, PositioningMode::kBarycentric,
    PositioningMode::kLeastSquares};

// Names used on the command line, in the configuration and in JSON output:
// auto, axes, barycentric, lsq.
std::string_view to_string(PositioningMode mode);
bool parse_positioning_mode(std::string_view text, PositioningMode* mode);
std::vector<std::string> positioning_mode_names();  // in kPositioningModes order
std::string positioning_mode_list();                // "auto, axes, barycentric or lsq"

// Whether the mode positions from the rectangles' centroids: the thesis's
// two do (a marker's centre and heading), least squares and auto from every
// point, the edges' among them. An edge-tracked frame measures no
// centroids, so these modes track with the windows' sweep (a 25 ms
// readout's drive, axes p99 2.5 -> 3.0 mm with edges).
bool positions_from_centroids(PositioningMode mode);

}  // namespace ceilpose
