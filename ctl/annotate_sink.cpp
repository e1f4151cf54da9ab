#include "ctl/annotate_sink.h"

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "codec/png_codec.h"
#include "core/text_file.h"
#include "pipeline/localization.h"

namespace ceilpose::ctl {
namespace {

const char* outcome_name(PairOutcome o) {
  switch (o) {
    case PairOutcome::kDecoded:
      return "decoded";
    case PairOutcome::kCut:
      return "cut by the border";
    case PairOutcome::kBlurred:
      return "too blurred";
    case PairOutcome::kUnreadable:
      return "slots outside the frame";
    case PairOutcome::kAmbiguous:
      return "ambiguous dot";
    case PairOutcome::kInconsistent:
      return "code contradicts dark area";
    case PairOutcome::kOverflow:
      return "too many markers";
  }
  return "?";
}

void outline(cv::Mat& img, const RectangleCandidate& r, const cv::Scalar& colour, int thickness) {
  const cv::RotatedRect box(
      cv::Point2f(static_cast<float>(r.cx), static_cast<float>(r.cy)),
      cv::Size2f(static_cast<float>(r.long_px), static_cast<float>(r.short_px)),
      static_cast<float>(r.axis_rad * 180.0 / M_PI));
  cv::Point2f p[4];
  box.points(p);
  for (int k = 0; k < 4; ++k) cv::line(img, p[k], p[(k + 1) % 4], colour, thickness, cv::LINE_AA);
}

void label(cv::Mat& img, const std::string& text, cv::Point at, const cv::Scalar& colour) {
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.45, colour, 1, cv::LINE_AA);
}

}  // namespace

void AnnotateSink::consume(const Localization& loc) {
  if (!error_.empty() || loc.detection == nullptr || loc.image.empty()) return;
  if (refused_only_ && loc.published.valid) return;
  const ImageView& v = loc.image;
  if (v.format == PixelFormat::kMjpeg) return;
  cv::Mat img;
  const cv::Mat src(v.height, v.width, v.format == PixelFormat::kGray8 ? CV_8UC1 : CV_8UC3,
                    const_cast<uint8_t*>(v.data), static_cast<size_t>(v.stride_bytes));
  // Drawn in BGR for imwrite.
  if (v.format == PixelFormat::kGray8)
    cv::cvtColor(src, img, cv::COLOR_GRAY2BGR);
  else if (v.format == PixelFormat::kRgb24)
    cv::cvtColor(src, img, cv::COLOR_RGB2BGR);
  else
    img = src.clone();
  const Pipeline& p = *loc.detection;
  const auto rects = p.rectangles();
  std::vector<bool> paired(rects.size(), false);
  // Every candidate thin and grey; paired ones drawn again below.
  for (const RectangleCandidate& r : rects) outline(img, r, cv::Scalar(160, 160, 160), 1);
  const cv::Scalar kOk(80, 255, 80), kBad(0, 140, 255);
  for (const MarkerPair& pair : p.pairs()) {
    const RectangleCandidate& red = rects[static_cast<size_t>(pair.red)];
    const RectangleCandidate& green = rects[static_cast<size_t>(pair.green)];
    paired[static_cast<size_t>(pair.red)] = paired[static_cast<size_t>(pair.green)] = true;
    const bool ok = pair.outcome == PairOutcome::kDecoded;
    outline(img, red, ok ? kOk : kBad, 2);
    outline(img, green, ok ? kOk : kBad, 2);
    // Red → green points West.
    cv::arrowedLine(img, cv::Point2d(red.cx, red.cy), cv::Point2d(green.cx, green.cy),
                    ok ? kOk : kBad, 1, cv::LINE_AA, 0, 0.2);
    std::string text = outcome_name(pair.outcome);
    if (ok) {
      for (const MarkerObservation& m : loc.markers)
        if (std::hypot(m.red_u_px - red.cx, m.red_v_px - red.cy) < 1e-6) {
          char code[48];
          std::snprintf(code, sizeof code, "(%d, %d)%s", m.code_i, m.code_j,
                        m.whole ? "" : " not whole");
          text = code;
        }
    }
    label(img, text,
          cv::Point(static_cast<int>(0.5 * (red.cx + green.cx)) - 20,
                    static_cast<int>(0.5 * (red.cy + green.cy)) - 8),
          ok ? kOk : kBad);
  }
  char head[256];
  const PoseEstimate& e = loc.published;
  if (e.valid) {
    std::snprintf(head, sizeof head, "frame %lld: x %.4f m  y %.4f m  yaw %.2f deg  %s, %d markers",
                  static_cast<long long>(loc.frame.index), e.pose.x_m, e.pose.y_m,
                  e.pose.yaw_rad * 180.0 / M_PI, std::string(to_string(e.mode)).c_str(), e.markers);
  } else {
    std::snprintf(head, sizeof head, "frame %lld: no pose: %s (%d decoded, %zu pairs, %zu rects)",
                  static_cast<long long>(loc.frame.index),
                  std::string(to_string(loc.refusal)).c_str(), loc.markers_decoded,
                  p.pairs().size(), rects.size());
  }
  label(img, head, cv::Point(6, 16), e.valid ? cv::Scalar(255, 255, 255) : kBad);
  char name[64];
  std::snprintf(name, sizeof name, "/frame_%06lld.png", static_cast<long long>(loc.frame.index));
  const std::string path = dir_ + name;
  // Encoded here and written by write_file, which does not follow a
  // symbolic link planted at the name (cv::imwrite would).
  const ImageView bgr{img.data,
                      img.cols,
                      img.rows,
                      static_cast<int>(img.step),
                      PixelFormat::kBgr24,
                      img.total() * img.elemSize()};
  // zlib's default level: pictures for people, where size matters more than time.
  if (auto encoded = codec::encode_png(bgr, 6, &png_); !encoded) {
    error_ = path + ": cannot encode the PNG: " + encoded.error().message;
    return;
  }
  if (auto wrote = write_file(path, png_.data(), png_.size()); !wrote)
    error_ = wrote.error().message;
  else
    ++written_;
}

}  // namespace ceilpose::ctl
