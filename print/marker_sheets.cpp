#include "print/marker_sheets.h"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

namespace ceilpose {
namespace {

constexpr double kPointsPerMm = 72.0 / 25.4;
constexpr double kA3WidthMm = 297.0, kA3HeightMm = 420.0;
constexpr double kMarginMm = 15.0;  // around the marker, at least
constexpr double kHeaderMm = 45.0;  // code and North arrow above the marker

struct SurfaceCloser {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextCloser {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceCloser>;
using Context = std::unique_ptr<cairo_t, ContextCloser>;

void set_colour(cairo_t* cr, Rgb c) {
  cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

// A page of width x height mm and a context that draws in millimetres. PDF
// pages are sized in points; an SVG document in millimetres takes its size
// in the document unit, so its user unit is the millimetre.
std::pair<Surface, Context> make_page(const std::string& path, double width_mm, double height_mm,
                                      SheetFormat format) {
  Surface s(format == SheetFormat::kPdf
                ? cairo_pdf_surface_create(path.c_str(), width_mm * kPointsPerMm,
                                           height_mm * kPointsPerMm)
                : cairo_svg_surface_create(path.c_str(), width_mm, height_mm));
  if (format == SheetFormat::kSvg && cairo_surface_status(s.get()) == CAIRO_STATUS_SUCCESS)
    cairo_svg_surface_set_document_unit(s.get(), CAIRO_SVG_UNIT_MM);
  Context c(cairo_create(s.get()));
  if (format == SheetFormat::kPdf) cairo_scale(c.get(), kPointsPerMm, kPointsPerMm);
  return {std::move(s), std::move(c)};
}

// Finishes the surface (writes the file) and reports what cairo says.
Result<void> finish(const std::string& path, cairo_t* cr, cairo_surface_t* surface) {
  cairo_status_t status = cairo_status(cr);
  cairo_surface_finish(surface);
  if (status == CAIRO_STATUS_SUCCESS) status = cairo_surface_status(surface);
  if (status != CAIRO_STATUS_SUCCESS)
    return make_error(path + ": cannot write: " + cairo_status_to_string(status));
  return {};
}

// The marker at (x, y) mm on the page, `scale` mm per marker mm, as seen
// from below with North up: marker East is page left.
void draw_marker(cairo_t* cr, const CeilingLayout& l, int i, int j, double x_mm, double y_mm,
                 double scale) {
  const double mm = 1000.0 * scale;  // page mm per metre of marker
  const double w = l.rect_width_m * mm, h = l.rect_height_m * mm;
  // Red (East of the shared edge) is to the left of the centre on the page.
  set_colour(cr, l.red);
  cairo_rectangle(cr, x_mm - w, y_mm - 0.5 * h, w, h);
  cairo_fill(cr);
  set_colour(cr, l.green);
  cairo_rectangle(cr, x_mm, y_mm - 0.5 * h, w, h);
  cairo_fill(cr);
  set_colour(cr, l.dot);
  for (int k = 0; k < l.bits; ++k) {
    // Slot k's North coordinate; page y grows downwards (South).
    const double slot_y = y_mm - l.slot_n_m(k) * mm;
    for (bool red : {true, false}) {
      if (!l.slot_bit(red ? i : j, k)) continue;
      const double cx = x_mm - (red ? l.red_centre_e_m() : l.green_centre_e_m()) * mm;
      const double rx = 0.5 * (red ? l.red_dot_e_m : l.green_dot_e_m) * mm;
      const double ry = 0.5 * (red ? l.red_dot_n_m : l.green_dot_n_m) * mm;
      cairo_save(cr);
      cairo_translate(cr, cx, slot_y);
      cairo_scale(cr, rx, ry);
      cairo_arc(cr, 0.0, 0.0, 1.0, 0.0, 2.0 * M_PI);
      cairo_restore(cr);
      cairo_fill(cr);
    }
  }
}

void centred_text(cairo_t* cr, const char* text, double x_mm, double baseline_mm, double size_mm) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
  cairo_set_font_size(cr, size_mm);
  cairo_text_extents_t e;
  cairo_text_extents(cr, text, &e);
  cairo_move_to(cr, x_mm - 0.5 * e.width - e.x_bearing, baseline_mm);
  cairo_show_text(cr, text);
}

void north_arrow(cairo_t* cr, double x_mm, double top_mm, double length_mm) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1.0);
  cairo_move_to(cr, x_mm, top_mm + length_mm);
  cairo_line_to(cr, x_mm, top_mm + 4.0);
  cairo_stroke(cr);
  cairo_move_to(cr, x_mm, top_mm);
  cairo_line_to(cr, x_mm - 3.0, top_mm + 6.0);
  cairo_line_to(cr, x_mm + 3.0, top_mm + 6.0);
  cairo_close_path(cr);
  cairo_fill(cr);
  cairo_set_font_size(cr, 5.0);
  cairo_move_to(cr, x_mm + 4.0, top_mm + 6.0);
  cairo_show_text(cr, "N");
}

}  // namespace

SheetGeometry marker_sheet_geometry(const CeilingLayout& l) {
  SheetGeometry g;
  const double marker_w_mm = 2000.0 * l.rect_width_m, marker_h_mm = 1000.0 * l.rect_height_m;
  g.page_width_mm = std::max(kA3WidthMm, marker_w_mm + 2.0 * kMarginMm);
  g.page_height_mm = std::max(kA3HeightMm, marker_h_mm + kHeaderMm + 2.0 * kMarginMm);
  g.centre_x_mm = 0.5 * g.page_width_mm;
  g.centre_y_mm = kMarginMm + kHeaderMm + 0.5 * marker_h_mm;
  return g;
}

Result<void> write_marker_sheet(const std::string& path, const CeilingLayout& l, int i, int j,
                                SheetFormat format) {
  const SheetGeometry g = marker_sheet_geometry(l);
  auto [surface, ctx] = make_page(path, g.page_width_mm, g.page_height_mm, format);
  cairo_t* cr = ctx.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  draw_marker(cr, l, i, j, g.centre_x_mm, g.centre_y_mm, 1.0);
  // Outside the outline: code, North arrow, and ticks marking the centre
  // (the shared edge's midpoint) to set on the rail intersection.
  const double half_w = 1000.0 * l.rect_width_m, half_h = 500.0 * l.rect_height_m;
  cairo_set_source_rgb(cr, 0, 0, 0);
  char code[64];
  std::snprintf(code, sizeof code, "(%d, %d)", i, j);
  centred_text(cr, code, g.centre_x_mm, g.centre_y_mm - half_h - 20.0, 14.0);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  char info[160];
  std::snprintf(info, sizeof info,
                "ceilpose marker: x code %d (red), y code %d (green). Print at 100%%; this face "
                "faces down, top edge North",
                i, j);
  cairo_set_font_size(cr, 4.0);
  cairo_text_extents_t e;
  cairo_text_extents(cr, info, &e);
  cairo_move_to(cr, g.centre_x_mm - 0.5 * e.width, g.centre_y_mm - half_h - 8.0);
  cairo_show_text(cr, info);
  north_arrow(cr, g.centre_x_mm + half_w - 10.0, g.centre_y_mm - half_h - 40.0, 28.0);
  cairo_set_line_width(cr, 0.3);
  for (double sign : {-1.0, 1.0}) {
    // On the shared edge's line, above and below the marker...
    cairo_move_to(cr, g.centre_x_mm, g.centre_y_mm + sign * (half_h + 2.0));
    cairo_line_to(cr, g.centre_x_mm, g.centre_y_mm + sign * (half_h + 8.0));
    // ... and on the centre line, left and right of it.
    cairo_move_to(cr, g.centre_x_mm + sign * (half_w + 2.0), g.centre_y_mm);
    cairo_line_to(cr, g.centre_x_mm + sign * (half_w + 8.0), g.centre_y_mm);
  }
  cairo_stroke(cr);
  return finish(path, cr, surface.get());
}

Result<void> write_ceiling_plan(const std::string& path, const CeilingLayout& l, double scale) {
  const double s = 1000.0 / scale;  // page mm per metre of ceiling
  const int n = l.codes();
  const double span_mm = (n - 1) * l.grid_m * s;
  const double margin_mm = 0.6 * l.grid_m * s + 10.0;
  const double w_mm = span_mm + 2.0 * margin_mm, h_mm = span_mm + 2.0 * margin_mm + 15.0;
  auto [surface, ctx] = make_page(path, w_mm, h_mm, SheetFormat::kSvg);
  cairo_t* cr = ctx.get();
  set_colour(cr, l.tile);
  cairo_paint(cr);
  // Seen from below with North up, world x (East) runs to the left.
  auto page_x = [&](double x_m) { return w_mm - margin_mm - x_m * s; };
  auto page_y = [&](double y_m) { return 15.0 + margin_mm + span_mm - y_m * s; };
  set_colour(cr, l.rail);
  cairo_set_line_width(cr, std::max(0.2, l.rail_width_m * s));
  for (int k = -1; k <= n; ++k) {
    cairo_move_to(cr, page_x(k * l.grid_m), 15.0);
    cairo_line_to(cr, page_x(k * l.grid_m), h_mm);
    cairo_move_to(cr, 0.0, page_y(k * l.grid_m));
    cairo_line_to(cr, w_mm, page_y(k * l.grid_m));
  }
  cairo_stroke(cr);
  char text[160];
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = page_x(i * l.grid_m), y = page_y(j * l.grid_m);
      draw_marker(cr, l, i, j, x, y, 1.0 / scale);
      cairo_set_source_rgb(cr, 0, 0, 0);
      std::snprintf(text, sizeof text, "%d,%d", i, j);
      cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
      centred_text(cr, text, x, y + 0.5 * l.rect_height_m * s + 4.0, 3.0);
    }
  cairo_set_source_rgb(cr, 0, 0, 0);
  std::snprintf(text, sizeof text,
                "ceiling plan seen from below, North up (East is on the left), 1:%.0f; grid %.4f m",
                scale, l.grid_m);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 4.0);
  cairo_move_to(cr, 5.0, 8.0);
  cairo_show_text(cr, text);
  north_arrow(cr, w_mm - 12.0, 1.0, 12.0);
  return finish(path, cr, surface.get());
}

}  // namespace ceilpose
