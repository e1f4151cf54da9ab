#include "sim/photometry.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sim/ceiling_scene.h"

namespace ceilpose::sim {
namespace {

constexpr int kEncodeSize = 1 << 16;
constexpr int kNormalTableBits = 16;
constexpr int kMaxBlurRadius = 64;
constexpr int kBloomDownsample = 4;
// Bloom spreads over about 2% of the image width, as lens glare does.
constexpr double kBloomSigmaPerWidth = 0.02;
// What an occluder (a hand, a cable, a passing box) reflects, linear light.
constexpr float kOccluderRadiance = 0.015f;

double linear_to_srgb_level(double v) {
  const double c = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return 255.0 * c;
}

// Acklam's rational approximation of the standard normal quantile (relative
// error < 1.2e-9), refined by one Halley step.
double normal_quantile(double p) {
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                                 -2.759285104469687e+02, 1.383577518672690e+02,
                                 -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                                 -1.556989798598866e+02, 6.680131188771972e+01,
                                 -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                                 -2.400758277161838e+00, -2.549732539343734e+00,
                                 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                                 2.445134137142996e+00, 3.754408661907416e+00};
  double x = 0.0;
  if (p < 0.02425) {
    const double q = std::sqrt(-2 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else if (p > 1 - 0.02425) {
    const double q = std::sqrt(-2 * std::log(1 - p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else {
    const double q = p - 0.5, r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
  }
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = e * std::sqrt(2 * 3.141592653589793) * std::exp(x * x / 2);
  return x - u / (1 + x * u / 2);
}

// xorshift64*: fast, deterministic, good enough for sensor noise.
struct FastRng {
  uint64_t s;
  explicit FastRng(uint64_t seed) : s(mix64(seed) | 1u) {}
  uint64_t next() {
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return s * 0x2545F4914F6CDD1Dull;
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
};

}  // namespace

Photometry::Photometry() : encode_u8_(kEncodeSize), encode_f_(kEncodeSize) {
  for (int i = 0; i < kEncodeSize; ++i) {
    const double level = linear_to_srgb_level(static_cast<double>(i) / (kEncodeSize - 1));
    encode_f_[i] = static_cast<float>(level);
    encode_u8_[i] = static_cast<uint8_t>(std::clamp(std::lround(level), 0L, 255L));
  }
  // Quantiles at evenly spaced probabilities: indexing the table with uniform
  // random bits draws from a 65536-point discretization of N(0, 1).
  const int n = 1 << kNormalTableBits;
  normal_table_.resize(n);
  for (int i = 0; i < n; ++i) normal_table_[i] = static_cast<float>(normal_quantile((i + 0.5) / n));
}

void Photometry::resize(int width_px, int height_px) {
  width_px_ = width_px;
  height_px_ = height_px;
  scratch_.assign(static_cast<size_t>(width_px) * height_px * 3, 0.0f);
  const int sw = (width_px + kBloomDownsample - 1) / kBloomDownsample;
  const int sh = (height_px + kBloomDownsample - 1) / kBloomDownsample;
  small_.assign(static_cast<size_t>(sw) * sh * 3, 0.0f);
  small_scratch_.assign(small_.size(), 0.0f);
}

void Photometry::apply(const Effects& e, uint64_t rng_seed, float* linear, Image* out) {
  if (out->width() != width_px_ || out->height() != height_px_ ||
      out->format() != PixelFormat::kRgb24)
    out->resize(width_px_, height_px_, PixelFormat::kRgb24);
  if (e.occlusion_fraction > 0.0) add_occluder(e.occlusion_fraction, rng_seed, linear);
  // Optics first (they act on scene radiance), then the sensor.
  if (e.defocus_sigma_px > 0.0)
    gaussian_blur(linear, scratch_.data(), width_px_, height_px_, e.defocus_sigma_px);
  if (e.motion_blur_px > 0.0) motion_blur(linear, e.motion_blur_px, e.motion_blur_angle_rad);
  if (e.bloom > 0.0) add_bloom(linear, e.bloom);
  encode(e, rng_seed, linear, out);
  if (e.jpeg_quality > 0) jpeg_round_trip(std::min(e.jpeg_quality, 100), out);
}

void Photometry::add_occluder(double fraction, uint64_t rng_seed, float* linear) const {
  // A dark blob: an ellipse of the requested area whose radius wobbles with
  // angle, placed at random with its centre inside the image.
  FastRng rng(rng_seed ^ 0x0CC1u);
  const double w = width_px_, h = height_px_;
  const double aspect = 0.5 + 0.5 * rng.uniform();
  const double a = std::sqrt(std::clamp(fraction, 0.0, 1.0) * w * h / (3.141592653589793 * aspect));
  const double b = a * aspect;
  const double cx = w * (0.15 + 0.7 * rng.uniform()), cy = h * (0.15 + 0.7 * rng.uniform());
  const double th = rng.uniform() * 3.141592653589793;
  const double ct = std::cos(th), st = std::sin(th);
  const double p1 = rng.uniform() * 6.283185307179586, p2 = rng.uniform() * 6.283185307179586;
  const double reach = 1.25 * a;
  const int x0 = std::max(0, static_cast<int>(cx - reach)),
            x1 = std::min(width_px_ - 1, static_cast<int>(cx + reach));
  const int y0 = std::max(0, static_cast<int>(cy - reach)),
            y1 = std::min(height_px_ - 1, static_cast<int>(cy + reach));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const double dx = x - cx, dy = y - cy;
      const double pa = dx * ct + dy * st, pb = -dx * st + dy * ct;
      const double ang = std::atan2(pb * a, pa * b);
      const double wobble = 1.0 + 0.12 * std::sin(3 * ang + p1) + 0.06 * std::sin(5 * ang + p2);
      const double q = std::sqrt((pa * pa) / (a * a) + (pb * pb) / (b * b)) / wobble;
      // Signed distance to the outline, to first order, for an anti-aliased edge.
      const double dist_px = (q - 1.0) * std::min(a, b) * wobble;
      const double cover = std::clamp(0.5 - dist_px, 0.0, 1.0);
      if (cover <= 0.0) continue;
      float* p = linear + (static_cast<size_t>(y) * width_px_ + x) * 3;
      for (int c = 0; c < 3; ++c)
        p[c] = static_cast<float>(p[c] * (1.0 - cover) + kOccluderRadiance * cover);
    }
  }
}

void Photometry::gaussian_blur(float* img, float* tmp, int w, int h, double sigma_px) const {
  const int radius = std::clamp(static_cast<int>(std::ceil(3.0 * sigma_px)), 1, kMaxBlurRadius);
  std::array<float, 2 * kMaxBlurRadius + 1> kernel{};
  double sum = 0.0;
  for (int t = -radius; t <= radius; ++t) {
    const double v = std::exp(-0.5 * t * t / (sigma_px * sigma_px));
    kernel[t + radius] = static_cast<float>(v);
    sum += v;
  }
  for (int t = 0; t <= 2 * radius; ++t) kernel[t] = static_cast<float>(kernel[t] / sum);
  // Horizontal pass into tmp (edge pixels repeated), vertical pass back.
  for (int y = 0; y < h; ++y) {
    const float* src = img + static_cast<size_t>(y) * w * 3;
    float* dst = tmp + static_cast<size_t>(y) * w * 3;
    for (int x = 0; x < w; ++x) {
      float r = 0, g = 0, b = 0;
      for (int t = -radius; t <= radius; ++t) {
        const int sx = std::clamp(x + t, 0, w - 1);
        const float k = kernel[t + radius];
        r += k * src[sx * 3];
        g += k * src[sx * 3 + 1];
        b += k * src[sx * 3 + 2];
      }
      dst[x * 3] = r;
      dst[x * 3 + 1] = g;
      dst[x * 3 + 2] = b;
    }
  }
  const int row = w * 3;
  for (int y = 0; y < h; ++y) {
    float* dst = img + static_cast<size_t>(y) * row;
    std::fill(dst, dst + row, 0.0f);
    for (int t = -radius; t <= radius; ++t) {
      const float* src = tmp + static_cast<size_t>(std::clamp(y + t, 0, h - 1)) * row;
      const float k = kernel[t + radius];
      for (int i = 0; i < row; ++i) dst[i] += k * src[i];
    }
  }
}

void Photometry::motion_blur(float* linear, double length_px, double angle_rad) {
  // Average of the image sampled at evenly spaced points along the motion
  // segment. A constant shift has the same bilinear weights at every pixel,
  // so each tap is four shifted, weighted copies of the image.
  const int taps = std::max(2, static_cast<int>(std::ceil(length_px)) + 1);
  const double dx = length_px * std::cos(angle_rad), dy = length_px * std::sin(angle_rad);
  const int w = width_px_, h = height_px_;
  std::fill(scratch_.begin(), scratch_.end(), 0.0f);
  for (int k = 0; k < taps; ++k) {
    const double s = static_cast<double>(k) / (taps - 1) - 0.5;
    const double ox = s * dx, oy = s * dy;
    const int ix = static_cast<int>(std::floor(ox)), iy = static_cast<int>(std::floor(oy));
    const float fx = static_cast<float>(ox - ix), fy = static_cast<float>(oy - iy);
    const float wt = 1.0f / taps;
    const float w00 = wt * (1 - fx) * (1 - fy), w10 = wt * fx * (1 - fy);
    const float w01 = wt * (1 - fx) * fy, w11 = wt * fx * fy;
    for (int y = 0; y < h; ++y) {
      const float* s0 = linear + static_cast<size_t>(std::clamp(y + iy, 0, h - 1)) * w * 3;
      const float* s1 = linear + static_cast<size_t>(std::clamp(y + iy + 1, 0, h - 1)) * w * 3;
      float* dst = scratch_.data() + static_cast<size_t>(y) * w * 3;
      for (int x = 0; x < w; ++x) {
        const int c0 = std::clamp(x + ix, 0, w - 1) * 3, c1 = std::clamp(x + ix + 1, 0, w - 1) * 3;
        for (int c = 0; c < 3; ++c)
          dst[x * 3 + c] +=
              w00 * s0[c0 + c] + w10 * s0[c1 + c] + w01 * s1[c0 + c] + w11 * s1[c1 + c];
      }
    }
  }
  std::copy(scratch_.begin(), scratch_.end(), linear);
}

void Photometry::add_bloom(float* linear, double strength) {
  // Glare around saturated fixtures: the radiance above sensor white, blurred
  // wide at a quarter of the resolution and added back.
  const int f = kBloomDownsample;
  const int sw = (width_px_ + f - 1) / f, sh = (height_px_ + f - 1) / f;
  std::fill(small_.begin(), small_.end(), 0.0f);
  for (int y = 0; y < height_px_; ++y) {
    const float* src = linear + static_cast<size_t>(y) * width_px_ * 3;
    float* dst = small_.data() + static_cast<size_t>(y / f) * sw * 3;
    for (int x = 0; x < width_px_; ++x)
      for (int c = 0; c < 3; ++c) dst[(x / f) * 3 + c] += std::max(0.0f, src[x * 3 + c] - 1.0f);
  }
  const float norm = 1.0f / (f * f);
  for (float& v : small_) v *= norm;
  gaussian_blur(small_.data(), small_scratch_.data(), sw, sh, kBloomSigmaPerWidth * width_px_ / f);
  // Bilinear upsampling; sample centres of the small image sit at
  // f * (i + 0.5) - 0.5 in full-resolution pixels.
  const float k = static_cast<float>(strength);
  for (int y = 0; y < height_px_; ++y) {
    float* dst = linear + static_cast<size_t>(y) * width_px_ * 3;
    const float sy = std::clamp((y + 0.5f) / f - 0.5f, 0.0f, static_cast<float>(sh - 1));
    const int y0 = static_cast<int>(sy), y1 = std::min(y0 + 1, sh - 1);
    const float fy = sy - y0;
    const float* r0 = small_.data() + static_cast<size_t>(y0) * sw * 3;
    const float* r1 = small_.data() + static_cast<size_t>(y1) * sw * 3;
    for (int x = 0; x < width_px_; ++x) {
      const float sx = std::clamp((x + 0.5f) / f - 0.5f, 0.0f, static_cast<float>(sw - 1));
      const int x0 = static_cast<int>(sx), x1 = std::min(x0 + 1, sw - 1);
      const float fx = sx - x0;
      for (int c = 0; c < 3; ++c) {
        const float top = r0[x0 * 3 + c] + (r0[x1 * 3 + c] - r0[x0 * 3 + c]) * fx;
        const float bottom = r1[x0 * 3 + c] + (r1[x1 * 3 + c] - r1[x0 * 3 + c]) * fx;
        dst[x * 3 + c] += k * (top + (bottom - top) * fy);
      }
    }
  }
}

void Photometry::encode(const Effects& e, uint64_t rng_seed, const float* linear,
                        Image* out) const {
  // Illumination gradient, exposure gain and white balance multiply radiance;
  // the sensor clips at white, the camera encodes sRGB, noise is added in
  // 8-bit levels (read noise plus signal-dependent shot noise).
  const double half_diag = 0.5 * std::hypot(width_px_, height_px_);
  const double gu = e.gradient_amplitude * std::cos(e.gradient_angle_rad) / half_diag;
  const double gv = e.gradient_amplitude * std::sin(e.gradient_angle_rad) / half_diag;
  const double cu = 0.5 * (width_px_ - 1), cv = 0.5 * (height_px_ - 1);
  const bool noisy = e.read_noise_sigma > 0.0 || e.shot_noise_scale > 0.0;
  const float read_var = static_cast<float>(e.read_noise_sigma * e.read_noise_sigma);
  const float shot = static_cast<float>(e.shot_noise_scale);
  const float lut_scale = kEncodeSize - 1;
  FastRng rng(rng_seed ^ 0x5E45u);
  uint64_t bits = 0;
  int bits_left = 0;
  for (int y = 0; y < height_px_; ++y) {
    const float* src = linear + static_cast<size_t>(y) * width_px_ * 3;
    uint8_t* dst = out->row(y);
    const double row_gain = 1.0 + gv * (y - cv) - gu * cu;
    for (int x = 0; x < width_px_; ++x) {
      const double illum = std::max(0.0, row_gain + gu * x) * e.gain;
      for (int c = 0; c < 3; ++c) {
        const float v =
            std::clamp(static_cast<float>(src[x * 3 + c] * illum * e.white_balance[c]), 0.0f, 1.0f);
        const int idx = static_cast<int>(v * lut_scale + 0.5f);
        if (!noisy) {
          dst[x * 3 + c] = encode_u8_[idx];
          continue;
        }
        const float level = encode_f_[idx];
        if (bits_left == 0) {
          bits = rng.next();
          bits_left = 64 / kNormalTableBits;
        }
        const float z = normal_table_[bits & ((1u << kNormalTableBits) - 1)];
        bits >>= kNormalTableBits;
        --bits_left;
        const float noisy_level = level + z * std::sqrt(read_var + shot * level);
        dst[x * 3 + c] = static_cast<uint8_t>(std::clamp(noisy_level + 0.5f, 0.0f, 255.0f));
      }
    }
  }
}

void Photometry::jpeg_round_trip(int quality, Image* out) {
  // 4:2:0 chroma from RGB, as a camera's encoder does. A codec failure here
  // is a simulator defect, not a property of the scene.
  const auto encoded = jpeg_.encode(out->view(), quality, &jpeg_bytes_);
  if (!encoded) throw std::runtime_error("simulated JPEG compression: " + encoded.error().message);
  const auto decoded = jpeg_.decode_fixed(jpeg_bytes_.data(), jpeg_bytes_.size(), out);
  if (!decoded) throw std::runtime_error("simulated JPEG compression: " + decoded.error().message);
}

}  // namespace ceilpose::sim
