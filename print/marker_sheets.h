#pragma once
// Printable marker sheets (SPEC §10), drawn with cairo at exact 1:1 scale in
// millimetres: one sheet per marker, and the plan of the whole ceiling. Both
// show the marker as the camera sees it from below with North at the top of
// the sheet — red on the left, the most significant bit at the top — because
// the printed face is the one that faces down.
#include <string>

#include "core/ceiling_layout.h"
#include "core/result.h"

namespace ceilpose {

enum class SheetFormat { kSvg, kPdf };

// The sheet: A3 portrait (297 x 420 mm) or larger when the marker needs it;
// the marker centred, its code and a North arrow above it, outside the
// outline, centre ticks on the shared edge and the centre line for gluing
// it on its rail intersection.
struct SheetGeometry {
  double page_width_mm = 0.0;
  double page_height_mm = 0.0;
  double centre_x_mm = 0.0;  // the marker centre on the page, from the top-left corner
  double centre_y_mm = 0.0;
};
SheetGeometry marker_sheet_geometry(const CeilingLayout& layout);

// Writes the sheet of marker (i, j) to `path`. Errors name the file.
Result<void> write_marker_sheet(const std::string& path, const CeilingLayout& layout, int i, int j,
                                SheetFormat format);

// The plan of the whole ceiling from below, North up (so East is on the
// left), at 1:`scale` (SVG): rails, every marker at its place with its code.
Result<void> write_ceiling_plan(const std::string& path, const CeilingLayout& layout,
                                double scale = 20.0);

}  // namespace ceilpose
