#pragma once
// The calibration target of `ceilposectl calibrate camera --board` (SPEC §7):
// "checkerboard:COLSxROWS:SQUARE_M", inner corners as OpenCV counts them.
#include <cmath>
#include <cstdio>
#include <string>

#include "core/result.h"

namespace ceilpose {

struct BoardSpec {
  int cols = 0;  // inner corners along a row
  int rows = 0;  // inner corners along a column
  double square_m = 0.0;
};

inline Result<BoardSpec> parse_board_spec(const std::string& text) {
  BoardSpec b;
  char tail = 0;
  if (std::sscanf(text.c_str(), "checkerboard:%dx%d:%lf%c", &b.cols, &b.rows, &b.square_m, &tail) !=
          3 ||
      b.cols < 2 || b.rows < 2 || b.cols > 100 || b.rows > 100 || !std::isfinite(b.square_m) ||
      b.square_m <= 0.0 || b.square_m > 1.0) {
    return make_error("--board '" + text +
                      "': expected checkerboard:COLSxROWS:SQUARE_M, e.g. checkerboard:9x6:0.03 "
                      "(inner corners 2..100, square in metres, at most 1)");
  }
  return b;
}

}  // namespace ceilpose
