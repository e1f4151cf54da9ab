#include "pipeline/components.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <tuple>

#include "core/pixel_read.h"

// One sweep, row by row, runs joined into components as they are found (one
// pass over the pixels):
//   a. classify the row into a byte buffer through the fused lookup (one
//      table lookup per pixel, no colour-space conversion pass);
//   b. run-length encode it, skipping background eight bytes at a time; a
//      dark run that sits between two runs of the same colour (a dot inside
//      its rectangle) is folded into one run of that colour, counting its
//      pixels as dark; other dark runs (shadows, occluders) are dropped;
//   c. unite each run with the runs of the same colour in the previous row
//      that touch it, diagonals included (8-connectivity): run a on row y−1
//      and b on row y touch when a.x0 ≤ b.x1 + 1 and a.x1 ≥ b.x0 − 1.
// Union-find always links the larger root under the smaller, so every set's
// root is its first run; one pass in run order then numbers the components
// and sums each run's moments in closed form (Σx over x0..x1 and Σx²).
// Because a dot is always enclosed left and right by its rectangle (SPEC §2:
// margins of 1 in or more), its rows fold completely, and the rectangle's
// centroid is that of the full rectangle whatever its code.

namespace ceilpose {
namespace {

constexpr size_t kRowPadding = 8;
// Rows of classes are read eight bytes a word: a byte's value in every
// lane, and the index of a word's first non-zero byte in memory order (the
// word loaded from memory, not zero).
static_assert(std::endian::native == std::endian::little, "bytes are read as little-endian words");
constexpr uint64_t kByteOnes = 0x0101010101010101ull;
int first_set_byte(uint64_t word) { return std::countr_zero(word) >> 3; }
// Windows side by side that a sweep's span table holds without growing
// (a tracked frame has one per marker in view, a dozen).
constexpr size_t kReservedSpansPerRow = 32;
// Sampled rows a sampled sweep asks for ahead of the one it reads.
constexpr int kSampledRowsAhead = 2;

// x86-64's baseline (SSE2) has no 32-bit vector multiply, so the BT.601
// arithmetic is also compiled for AVX2 and picked at load time where the
// CPU has it (GCC function multi-versioning; the same plain loop, no
// intrinsics). arm64's baseline (NEON) multiplies in vectors already.
// Not under the sanitizers: the clones' resolver runs before the sanitizer
// runtime is set up (a TSan build crashed at start).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_THREAD__) && !defined(__SANITIZE_ADDRESS__)
#define CEILPOSE_VECTOR_CLONES [[gnu::target_clones("avx2", "default")]]
#else
#define CEILPOSE_VECTOR_CLONES
#endif

int64_t sum_squares_to(int64_t k) { return k * (k + 1) * (2 * k + 1) / 6; }

// Chroma x4 of `pairs` YUYV pixel pairs from `q` (Y0 U Y1 V each).
CEILPOSE_VECTOR_CLONES void yuyv_chroma(const uint8_t* __restrict q, int16_t* __restrict u4,
                                        int16_t* __restrict v4, int pairs) {
  for (int k = 0; k < pairs; ++k) {
    u4[k] = static_cast<int16_t>(4 * q[kYuyvPairBytes * k + kYuyvUByte]);
    v4[k] = static_cast<int16_t>(4 * q[kYuyvPairBytes * k + kYuyvVByte]);
  }
}
CEILPOSE_VECTOR_CLONES void yuyv_luma(const uint8_t* __restrict q, int16_t* __restrict luma,
                                      int n) {
  for (int i = 0; i < n; ++i) luma[i] = q[2 * i];
}
// 4:2:0 chroma x4 of `pairs` pairs: the row's own 3:1 with the neighbouring
// chroma row's, samples `step` bytes apart (NV12 2, I420 1).
CEILPOSE_VECTOR_CLONES void planar_chroma(const uint8_t* __restrict near,
                                          const uint8_t* __restrict far, int step,
                                          int16_t* __restrict c4, int pairs) {
  for (int k = 0; k < pairs; ++k)
    c4[k] = static_cast<int16_t>(kChromaOwnWeight * near[step * k] +
                                 kChromaNeighbourWeight * far[step * k]);
}
CEILPOSE_VECTOR_CLONES void planar_luma(const uint8_t* __restrict q, int16_t* __restrict luma,
                                        int n) {
  for (int i = 0; i < n; ++i) luma[i] = q[i];
}

// Chroma x16 of the 2·pairs pixels of `pairs` pixel pairs, from the pairs'
// chroma x4 with one pair of margin each side (pair4[0] is the pair before
// the first): 3:1 with the neighbouring pair on the pixel's side.
CEILPOSE_VECTOR_CLONES void interpolate_chroma(const int16_t* __restrict pair4,
                                               int16_t* __restrict px16, int pairs) {
  for (int k = 0; k < pairs; ++k) {
    const int own = kChromaOwnWeight * pair4[k + 1];
    px16[2 * k] = static_cast<int16_t>(own + kChromaNeighbourWeight * pair4[k]);
    px16[2 * k + 1] = static_cast<int16_t>(own + kChromaNeighbourWeight * pair4[k + 2]);
  }
}

// Luma and chroma x16 of every `pairs`-th pixel pair's first pixel of a
// row, with the pair's own chroma.
CEILPOSE_VECTOR_CLONES void yuyv_sampled(const uint8_t* __restrict q, int pairs,
                                         int16_t* __restrict luma, int16_t* __restrict u16,
                                         int16_t* __restrict v16, int n) {
  for (int i = 0; i < n; ++i) {
    const uint8_t* p = q + kYuyvPairBytes * pairs * i;
    luma[i] = p[0];
    u16[i] = static_cast<int16_t>(16 * p[kYuyvUByte]);
    v16[i] = static_cast<int16_t>(16 * p[kYuyvVByte]);
  }
}
// The same from 4:2:0 planes: chroma samples `step` bytes apart (NV12 2,
// I420 1), the pixel's own chroma row.
CEILPOSE_VECTOR_CLONES void planar_sampled(const uint8_t* __restrict q, int pairs,
                                           const uint8_t* __restrict u, const uint8_t* __restrict v,
                                           int step, int16_t* __restrict luma,
                                           int16_t* __restrict u16, int16_t* __restrict v16,
                                           int n) {
  for (int i = 0; i < n; ++i) {
    luma[i] = q[2 * pairs * i];
    u16[i] = static_cast<int16_t>(16 * u[step * pairs * i]);
    v16[i] = static_cast<int16_t>(16 * v[step * pairs * i]);
  }
}

// A byte x is in [lo, hi] when uint8_t(x - lo) <= hi - lo: one subtraction
// and one comparison, which vectorise.
struct BoxTest {
  explicit BoxTest(const YuvBox& b)
      : y_lo(b.y_lo),
        y_span(static_cast<uint8_t>(b.y_hi - b.y_lo)),
        u_lo(b.u_lo),
        u_span(static_cast<uint8_t>(b.u_hi - b.u_lo)),
        v_lo(b.v_lo),
        v_span(static_cast<uint8_t>(b.v_hi - b.v_lo)) {}
  // 1 or 0, not bool: callers combine tests with & to keep the loop
  // branch-free (clang warns on & between bools).
  static uint8_t within(uint8_t x, uint8_t lo, uint8_t span) {
    return static_cast<uint8_t>(static_cast<uint8_t>(x - lo) <= span);
  }
  uint8_t y(uint8_t x) const { return within(x, y_lo, y_span); }
  uint8_t u(uint8_t x) const { return within(x, u_lo, u_span); }
  uint8_t v(uint8_t x) const { return within(x, v_lo, v_span); }
  uint8_t y_lo, y_span, u_lo, u_span, v_lo, v_span;
};

// in[i] = 1 where the i-th of every `kPairs`-th YUYV pixel pair lies in
// `box`: its first pixel (own chroma) or, kBothLumas, both its lumas and
// its chroma.
template <int kPairs, bool kBothLumas>
CEILPOSE_VECTOR_CLONES void yuyv_in_box(const uint8_t* __restrict q, YuvBox box,
                                        uint8_t* __restrict in, int n) {
  const BoxTest t(box);
  for (int i = 0; i < n; ++i) {
    uint32_t w = 0;
    std::memcpy(&w, q + 4 * kPairs * i, sizeof w);
    const uint8_t second_luma = kBothLumas ? t.y(static_cast<uint8_t>(w >> 16)) : 1;
    in[i] = static_cast<uint8_t>(t.y(static_cast<uint8_t>(w)) & t.u(static_cast<uint8_t>(w >> 8)) &
                                 second_luma & t.v(static_cast<uint8_t>(w >> 24)));
  }
}

// The same from 4:2:0 planes: luma every kLumaStep bytes, chroma every
// kChromaStep bytes of its plane (NV12's interleaved U and V are one byte
// apart, I420's in planes of their own).
template <int kLumaStep, int kChromaStep>
CEILPOSE_VECTOR_CLONES void planar_in_box(const uint8_t* __restrict q, const uint8_t* __restrict u,
                                          const uint8_t* __restrict v, YuvBox box,
                                          uint8_t* __restrict in, int n) {
  const BoxTest t(box);
  for (int i = 0; i < n; ++i) {
    in[i] = static_cast<uint8_t>(t.y(q[kLumaStep * i]) & t.u(u[kChromaStep * i]) &
                                 t.v(v[kChromaStep * i]));
  }
}

// The same for 4:2:0 pairs: both lumas, and the chroma of both chroma rows
// a pixel's chroma mixes (`near`, `far`; U and V kChromaStep bytes apart
// along a row: NV12 2, I420 1).
template <int kChromaStep>
CEILPOSE_VECTOR_CLONES void planar_pairs_in_box(const uint8_t* __restrict q,
                                                const uint8_t* __restrict u_near,
                                                const uint8_t* __restrict v_near,
                                                const uint8_t* __restrict u_far,
                                                const uint8_t* __restrict v_far, YuvBox box,
                                                uint8_t* __restrict in, int n) {
  const BoxTest t(box);
  for (int k = 0; k < n; ++k) {
    in[k] = static_cast<uint8_t>(t.y(q[2 * k]) & t.y(q[2 * k + 1]) & t.u(u_near[kChromaStep * k]) &
                                 t.v(v_near[kChromaStep * k]) & t.u(u_far[kChromaStep * k]) &
                                 t.v(v_far[kChromaStep * k]));
  }
}

// Calls convert(b, e) on the stretches of [begin, end) that are not whole
// blocks of kBoxBlock samples in the box (block_in(b): the block from b
// is). A block is as long as an AVX2 vector of int16: a stretch is then
// whole vectors for the conversion, not a scalar remainder (8-sample blocks
// skipped 79 % of the samples yet saved the conversion only 31 %).
constexpr int kBoxBlock = 16;
template <typename BlockIn, typename Convert>
void convert_outside_box(int begin, int end, BlockIn&& block_in, Convert&& convert) {
  int b = begin;
  while (b < end) {
    if (block_in(b)) {
      b += kBoxBlock;
      continue;
    }
    int e = b + kBoxBlock;
    while (e < end && !block_in(e)) e += kBoxBlock;
    e = std::min(e, end);
    convert(b, e);
    b = e;
  }
}

// The same over samples flagged one by one (`in`, padded past count): a
// block is in when its 16 flags are, and the last, partial block never is.
template <typename Convert>
void outside_box(const uint8_t* in, int count, Convert&& convert) {
  auto block_in = [&](int i) {
    if (i + kBoxBlock > count) return false;
    uint64_t w[kBoxBlock / 8];
    std::memcpy(w, in + i, sizeof w);
    uint64_t all = kByteOnes;
    for (const uint64_t x : w) all &= x == kByteOnes ? kByteOnes : 0;
    return all == kByteOnes;
  };
  convert_outside_box(0, count, block_in, convert);
}

// BT.601 (video range) from luma and chroma x16 to 0..255 levels, in ints
// scaled by 2^12, and on to each pixel's lookup index under the frame's
// gains: the normalisation tables' arithmetic in vectors, not three table
// reads a pixel (callgrind: a halved 640x480 YUYV sweep's classification
// 0.91 -> 0.76 M instructions). A function of its own so that the compiler
// knows the arrays do not overlap and vectorises the loop.
CEILPOSE_VECTOR_CLONES void bt601_indices(const int16_t* __restrict luma,
                                          const int16_t* __restrict u16,
                                          const int16_t* __restrict v16,
                                          ColorClassifier::GainsQ16 gains,
                                          uint32_t* __restrict index, int n) {
  auto level = [](int v) { return std::clamp(v >> 12, 0, 255); };
  for (int i = 0; i < n; ++i) {
    const int c = 16 * (298 * (luma[i] - 16) + 128);
    const int d = u16[i] - 16 * 128, e = v16[i] - 16 * 128;
    index[i] =
        ColorClassifier::lut_index(ColorClassifier::cell_of(level(c + 409 * e), gains.r),
                                   ColorClassifier::cell_of(level(c - 100 * d - 208 * e), gains.g),
                                   ColorClassifier::cell_of(level(c + 516 * d), gains.b));
  }
}

// The fused lookup of `count` RGB (or BGR) pixels kStep bytes apart from
// `p` into out[0..count).
template <int kStep>
void lookup_rgb(const uint8_t* p, bool rgb, const ColorClassifier& classifier, uint8_t* out,
                int count) {
  const uint8_t* lut = classifier.lut();
  const uint32_t* t0 = classifier.table(rgb ? 0 : 2);
  const uint32_t* t1 = classifier.table(1);
  const uint32_t* t2 = classifier.table(rgb ? 2 : 0);
  for (int i = 0; i < count; ++i, p += kStep) out[i] = lut[t0[p[0]] | t1[p[1]] | t2[p[2]]];
}

// The classes of `count` pixels' lookup indices.
void lookup_indices(const uint32_t* index, const ColorClassifier& classifier, uint8_t* out,
                    int count) {
  const uint8_t* lut = classifier.lut();
  for (int i = 0; i < count; ++i) out[i] = lut[index[i]];
}

}  // namespace

bool PixelWindow::row_span(int y, int* lo, int* hi) const {
  if (y < y0 || y > y1) return false;
  if (!quad) {
    *lo = x0, *hi = x1;
    return true;
  }
  // Where the row's centre line crosses the quadrilateral's edges.
  float u_min = 1e30f, u_max = -1e30f;
  const float v = static_cast<float>(y);
  for (int k = 0; k < 4; ++k) {
    const float ua = qu[k], va = qv[k], ub = qu[(k + 1) % 4], vb = qv[(k + 1) % 4];
    if ((v < va && v < vb) || (v > va && v > vb)) continue;
    const float u = vb == va ? std::min(ua, ub) : ua + (v - va) * (ub - ua) / (vb - va);
    const float u_other = vb == va ? std::max(ua, ub) : u;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u_other);
  }
  if (u_max < u_min) return false;
  // Whole pixels whose centres may lie inside, one more each side.
  *lo = std::max(x0, static_cast<int>(std::floor(u_min)) - 1);
  *hi = std::min(x1, static_cast<int>(std::ceil(u_max)) + 1);
  return *lo <= *hi;
}

double Component::orientation_rad() const { return 0.5 * std::atan2(2.0 * mu11, mu20 - mu02); }

ComponentLabeler::ComponentLabeler(int width_px, int height_px, const DetectorParams& params)
    : params_(params) {
  resize(width_px, height_px);
}

void ComponentLabeler::resize(int width_px, int height_px) {
  width_ = std::max(0, width_px);
  height_ = std::max(0, height_px);
  const double pixels = static_cast<double>(width_) * height_;
  max_runs_ = std::max(1024, static_cast<int>(pixels * params_.max_runs_per_pixel));
  row_class_.assign(static_cast<size_t>(width_) + kRowPadding, 0);
  row_edge_.assign(static_cast<size_t>(width_) + kRowPadding, 0);
  const size_t pixels_padded = static_cast<size_t>(width_) + kRowPadding;
  const size_t pairs_padded = static_cast<size_t>(width_ / 2) + kRowPadding;
  for (auto* v : {&pair_u_, &pair_v_}) v->assign(pairs_padded, 0);
  for (auto* v : {&px_y_, &px_u_, &px_v_}) v->assign(pixels_padded, 0);
  px_index_.assign(pixels_padded, 0);
  in_box_.assign(pixels_padded, 0);
  spans_.resize(static_cast<size_t>(height_) * kReservedSpansPerRow);
  swept_.reserve(kReservedSpansPerRow);
  runs_.resize(static_cast<size_t>(max_runs_) + 1);
  parent_.resize(runs_.size());
  label_.resize(runs_.size());
  comps_.resize(runs_.size());
  sums_.resize(runs_.size());
  window_edge_.resize(runs_.size());
  run_count_ = 0;
  comp_count_ = 0;
}

void ComponentLabeler::classify_yuv_span(const ImageView& frame, int y, int x0, int x1,
                                         const ColorClassifier& classifier) {
  // Chroma interpolated at each pixel as core/pixel_read.h does (the
  // pair's own chroma 3:1 with the neighbouring pair's on the pixel's side;
  // 4:2:0 also 3:1 with the neighbouring chroma row), then BT.601 to the
  // normalisation tables' levels and the fused lookup. In stages, so that
  // all but the last (four table loads a pixel, as for RGB) are arithmetic
  // the compiler vectorises; the fused one-loop form cost 3x RGB a pixel.
  const int last_pair = (frame.width - 1) >> 1;
  const int p0 = x0 >> 1, p1 = x1 >> 1;
  // pair_u_[k] holds pair p0 - 1 + k: one pair of margin each side.
  int16_t* pu = pair_u_.data();
  int16_t* pv = pair_v_.data();
  int16_t* py = px_y_.data();
  const uint8_t* row = frame.row(y);
  // Pairs p0..p1 are in the frame; the margins are clamped to its edges.
  const int pairs = p1 - p0 + 1;
  const int before = std::max(p0 - 1, 0), after = std::min(p1 + 1, last_pair);
  if (frame.format == PixelFormat::kYuyv) {
    yuyv_chroma(row + 4 * p0, pu + 1, pv + 1, pairs);
    yuyv_chroma(row + 4 * before, pu, pv, 1);
    yuyv_chroma(row + 4 * after, pu + pairs + 1, pv + pairs + 1, 1);
    yuyv_luma(row + 2 * x0, py + x0, x1 - x0 + 1);
  } else {
    const int y_other = chroma_neighbour_row(y, frame.height);
    const bool nv12 = frame.format == PixelFormat::kNv12;
    const int step = nv12 ? 2 : 1;
    const uint8_t* u_near = nv12 ? frame.uv_row(y) : frame.u_row(y);
    const uint8_t* u_far = nv12 ? frame.uv_row(y_other) : frame.u_row(y_other);
    const uint8_t* v_near = nv12 ? frame.uv_row(y) + 1 : frame.v_row(y);
    const uint8_t* v_far = nv12 ? frame.uv_row(y_other) + 1 : frame.v_row(y_other);
    for (auto [near, far, out] : {std::tuple{u_near, u_far, pu}, std::tuple{v_near, v_far, pv}}) {
      planar_chroma(near + step * p0, far + step * p0, step, out + 1, pairs);
      planar_chroma(near + step * before, far + step * before, step, out, 1);
      planar_chroma(near + step * after, far + step * after, step, out + pairs + 1, 1);
    }
    planar_luma(row + x0, py + x0, x1 - x0 + 1);
  }
  // Per pixel chroma ×16: even pixels lean on the pair before, odd ones on
  // the pair after. Pixels 2·p0 .. 2·p1 + 1 (the span and at most one more
  // each side: the buffers are a pixel wider than the frame).
  interpolate_chroma(pu, px_u_.data() + 2 * p0, pairs);
  interpolate_chroma(pv, px_v_.data() + 2 * p0, pairs);
  bt601_indices(py + x0, px_u_.data() + x0, px_v_.data() + x0, classifier.gains_q16(),
                px_index_.data() + x0, x1 - x0 + 1);
  lookup_indices(px_index_.data() + x0, classifier, row_class_.data() + x0, x1 - x0 + 1);
}

void ComponentLabeler::classify_span(const ImageView& frame, int y, int x0, int x1,
                                     const ColorClassifier& classifier) {
  const uint8_t* row = frame.row(y);
  uint8_t* out = row_class_.data();
  switch (frame.format) {
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      lookup_rgb<3>(row + 3 * x0, frame.format == PixelFormat::kRgb24, classifier, out + x0,
                    x1 - x0 + 1);
      return;
    case PixelFormat::kYuyv:
    case PixelFormat::kNv12:
    case PixelFormat::kYuv420:
      classify_yuv_span_outside_box(frame, y, x0, x1, classifier);
      return;
    case PixelFormat::kGray8:
    case PixelFormat::kMjpeg:
      std::memset(out + x0, 0, static_cast<size_t>(x1 - x0 + 1));
      return;
  }
}

void ComponentLabeler::classify_yuv_span_outside_box(const ImageView& frame, int y, int x0, int x1,
                                                     const ColorClassifier& classifier) {
  const YuvBox& box = classifier.background_yuv();
  if (box.empty()) {
    classify_yuv_span(frame, y, x0, x1, classifier);
    return;
  }
  // A pixel's chroma mixes its pair's with a neighbouring pair's (4:2:0:
  // also with the neighbouring chroma row's), and lies between them: a
  // pixel is background when its pair and both neighbours (clamped to the
  // frame, as classify_yuv_span clamps) are in the box, chroma rows and all.
  const int last_pair = (frame.width - 1) >> 1;
  const int k0 = std::max((x0 >> 1) - 1, 0), k1 = std::min((x1 >> 1) + 1, last_pair);
  uint8_t* in = in_box_.data();  // in[k - k0] for pair k
  const uint8_t* row = frame.row(y);
  if (frame.format == PixelFormat::kYuyv) {
    yuyv_in_box<1, true>(row + 4 * k0, box, in, k1 - k0 + 1);
  } else {
    const int y_other = chroma_neighbour_row(y, frame.height);
    if (frame.format == PixelFormat::kNv12) {
      planar_pairs_in_box<2>(row + 2 * k0, frame.uv_row(y) + 2 * k0, frame.uv_row(y) + 2 * k0 + 1,
                             frame.uv_row(y_other) + 2 * k0, frame.uv_row(y_other) + 2 * k0 + 1,
                             box, in, k1 - k0 + 1);
    } else {
      planar_pairs_in_box<1>(row + 2 * k0, frame.u_row(y) + k0, frame.v_row(y) + k0,
                             frame.u_row(y_other) + k0, frame.v_row(y_other) + k0, box, in,
                             k1 - k0 + 1);
    }
  }
  // Blocks of kBoxBlock pixels from x0: skipped when every pair they touch
  // and those pairs' neighbours are in the box; the rest converted in
  // stretches.
  auto block_in = [&](int b) {
    const int e = std::min(b + kBoxBlock - 1, x1);
    const int lo = std::max((b >> 1) - 1, 0), hi = std::min((e >> 1) + 1, last_pair);
    uint8_t all = 1;
    for (int k = lo; k <= hi; ++k) all &= in[k - k0];
    return all != 0;
  };
  convert_outside_box(x0, x1 + 1, block_in,
                      [&](int b, int e) { classify_yuv_span(frame, y, b, e - 1, classifier); });
}

// Runs of row y between x0 and x1; the row buffer is zero outside the
// classified spans and for kRowPadding bytes past the row.
bool ComponentLabeler::encode_row(int y, int x0, int x1) {
  const uint8_t* c = row_class_.data();
  const int w = x1 + 1;
  const int row_begin = run_count_;
  constexpr auto kDark = static_cast<uint8_t>(PixelClass::kDark);
  int x = x0;
  while (x < w) {
    uint64_t word = 0;
    std::memcpy(&word, c + x, sizeof word);
    if (word == 0) {  // the padding after the row is zero, so this may look past w
      x += 8;
      continue;
    }
    x += first_set_byte(word);
    if (x >= w) break;
    const uint8_t cls = c[x];
    const int run_x0 = x;
    // Eight samples at a time: the run stops at the zero padding at the
    // latest, so a word wholly of the run ends at or before it.
    const uint64_t run_word = kByteOnes * cls;
    for (;;) {
      std::memcpy(&word, c + x, sizeof word);
      if (const uint64_t other = word ^ run_word; other != 0) {
        x += first_set_byte(other);
        break;
      }
      x += 8;
    }
    const int run_x1 = x - 1;
    const int in_row = run_count_ - row_begin;
    if (cls == kDark) {
      // Keep a dark run only while it may still be enclosed: it must start
      // right after a coloured run.
      if (in_row > 0 && runs_[run_count_ - 1].x1 + 1 == run_x0) {
        if (run_count_ >= run_budget_) return abandon();
        runs_[run_count_++] = Run{run_x0, run_x1, y, 0, PixelClass::kDark, false};
      }
      continue;
    }
    if (in_row > 0 && runs_[run_count_ - 1].cls == PixelClass::kDark) {
      const Run dark = runs_[run_count_ - 1];
      --run_count_;
      Run& left = runs_[run_count_ - 1];
      if (dark.x1 + 1 == run_x0 && static_cast<uint8_t>(left.cls) == cls) {
        left.dark_px += dark.x1 - dark.x0 + 1;
        left.x1 = run_x1;
        left.window_edge = left.window_edge || row_edge_[dark.x0] != 0 || row_edge_[run_x1] != 0;
        continue;
      }
    }
    if (run_count_ >= run_budget_) return abandon();
    runs_[run_count_] = Run{run_x0,
                            run_x1,
                            y,
                            0,
                            static_cast<PixelClass>(cls),
                            row_edge_[run_x0] != 0 || row_edge_[run_x1] != 0};
    parent_[run_count_] = run_count_;
    ++run_count_;
  }
  if (run_count_ > row_begin && runs_[run_count_ - 1].cls == PixelClass::kDark) --run_count_;
  return true;
}

bool ComponentLabeler::abandon() {
  run_count_ = 0;
  return false;
}

void ComponentLabeler::join_row(int cur_begin, int* prev_begin, int* prev_end) {
  join_rows(*prev_begin, *prev_end, cur_begin, run_count_);
  *prev_begin = cur_begin;
  *prev_end = run_count_;
}

int32_t ComponentLabeler::find(int32_t i) {
  while (parent_[i] != i) {
    parent_[i] = parent_[parent_[i]];
    i = parent_[i];
  }
  return i;
}

void ComponentLabeler::unite(int32_t a, int32_t b) {
  const int32_t ra = find(a), rb = find(b);
  if (ra == rb) return;
  if (ra < rb) {
    parent_[rb] = ra;
  } else {
    parent_[ra] = rb;
  }
}

void ComponentLabeler::join_rows(int prev_begin, int prev_end, int cur_begin, int cur_end) {
  int p = prev_begin;
  for (int i = cur_begin; i < cur_end; ++i) {
    const Run& cur = runs_[i];
    while (p < prev_end && runs_[p].x1 + 1 < cur.x0) ++p;
    for (int q = p; q < prev_end && runs_[q].x0 <= cur.x1 + 1; ++q) {
      if (runs_[q].cls == cur.cls) unite(q, i);
    }
  }
}

void ComponentLabeler::accumulate(int width, int height) {
  comp_count_ = 0;
  for (int i = 0; i < run_count_; ++i) {
    const Run& run = runs_[i];
    const int32_t root = find(i);
    int32_t k = 0;
    if (root == i) {
      k = static_cast<int32_t>(comp_count_++);
      Component& c = comps_[k];
      c = Component{};
      c.cls = run.cls;
      c.x_min = run.x0;
      c.x_max = run.x1;
      c.y_min = c.y_max = run.y;
      sums_[k] = {};
      window_edge_[k] = 0;
    } else {
      k = label_[root];
    }
    label_[i] = k;
    Component& c = comps_[k];
    const int64_t n = run.x1 - run.x0 + 1;
    const double sx = 0.5 * static_cast<double>(run.x0 + run.x1) * static_cast<double>(n);
    const double sxx = static_cast<double>(sum_squares_to(run.x1) - sum_squares_to(run.x0 - 1));
    const double y = run.y;
    auto& s = sums_[k];
    s[0] += sx;
    s[1] += y * static_cast<double>(n);
    s[2] += sxx;
    s[3] += y * sx;
    s[4] += y * y * static_cast<double>(n);
    c.area_px += static_cast<int>(n);
    c.dark_px += run.dark_px;
    window_edge_[k] = static_cast<uint8_t>(window_edge_[k] | (run.window_edge ? 1 : 0));
    c.x_min = std::min(c.x_min, run.x0);
    c.x_max = std::max(c.x_max, run.x1);
    c.y_min = std::min(c.y_min, run.y);
    c.y_max = std::max(c.y_max, run.y);
  }
  for (size_t k = 0; k < comp_count_; ++k) {
    Component& c = comps_[k];
    const auto& s = sums_[k];
    const double a = c.area_px;
    c.cx = s[0] / a;
    c.cy = s[1] / a;
    c.mu20 = s[2] / a - c.cx * c.cx;
    c.mu11 = s[3] / a - c.cx * c.cy;
    c.mu02 = s[4] / a - c.cy * c.cy;
    const bool frame_edge =
        c.x_min == 0 || c.y_min == 0 || c.x_max == width - 1 || c.y_max == height - 1;
    c.touches_border = frame_edge || window_edge_[k] != 0;
    if (window_edge_[k] != 0 && c.cls != PixelClass::kDark &&
        4 * c.area_px >= params_.min_rect_area_px) {
      ++window_cuts_;
    }
  }
}

bool ComponentLabeler::label(const ImageView& frame, const ColorClassifier& classifier) {
  const PixelWindow whole{0, 0, width_ - 1, height_ - 1};
  run_budget_ = max_runs_;
  plan_spans(frame, std::span<const PixelWindow>(&whole, 1), false);
  return sweep_rows(frame, classifier);
}

bool ComponentLabeler::label(const ImageView& frame, const ColorClassifier& classifier,
                             std::span<const PixelWindow> windows) {
  auto refuse = [&] {
    run_count_ = 0;
    comp_count_ = 0;
    return false;
  };
  int64_t pixels = 0;
  for (size_t i = 0; i < windows.size(); ++i) {
    const PixelWindow& w = windows[i];
    if (w.empty() || w.x0 < 0 || w.y0 < 0 || w.x1 >= width_ || w.y1 >= height_) return refuse();
    // Boxes apart, as merge_windows leaves them: each row's spans are then
    // apart and in the order of the boxes' left edges.
    for (size_t j = 0; j < i; ++j) {
      const PixelWindow& o = windows[j];
      if (w.x0 <= o.x1 + 1 && o.x0 <= w.x1 + 1 && w.y0 <= o.y1 + 1 && o.y0 <= w.y1 + 1)
        return refuse();
    }
    pixels += w.area_px();
  }
  run_budget_ = std::min(max_runs_, std::max(1024, static_cast<int>(static_cast<double>(pixels) *
                                                                    params_.max_runs_per_pixel)));
  plan_spans(frame, windows, true);
  return sweep_rows(frame, classifier);
}

void ComponentLabeler::plan_spans(const ImageView& frame, std::span<const PixelWindow> windows,
                                  bool prefetch) {
  swept_.clear();
  size_t span_count = 0;
  for (const PixelWindow& w : windows) {
    // Left edges in increasing order (windows are few: insertion).
    auto at = swept_.begin();
    while (at != swept_.end() && at->x0 < w.x0) ++at;
    swept_.insert(at, SweptWindow{w.x0, w.y0, w.y1, static_cast<int32_t>(&w - windows.data()), 0});
    span_count += static_cast<size_t>(w.y1 - w.y0 + 1);
  }
  if (spans_.size() < span_count) spans_.resize(span_count);  // more windows than reserved
  // A camera's frame arrives in memory, not in cache, and a window's span
  // (a few hundred bytes a row, a dozen places a row) is too short a stream
  // for the hardware prefetcher: asked for all at once, before the sweep,
  // the windows' pixels cost a tracked 640x480 RGB frame 60-85 us less
  // (docs/pipeline_speed.md). A whole sweep reads in address order and
  // needs no help.
  const bool ask = prefetch && frame.width == width_ && frame.height == height_ && !frame.empty() &&
                   frame.format != PixelFormat::kGray8;
  int32_t first = 0;
  for (SweptWindow& sw : swept_) {
    const PixelWindow& w = windows[static_cast<size_t>(sw.window)];
    sw.first_span = first;
    for (int y = sw.y0; y <= sw.y1; ++y) {
      RowSpan& span = spans_[static_cast<size_t>(first++)];
      if (!w.row_span(y, &span.x0, &span.x1)) {
        span = RowSpan{};
        continue;
      }
      if (ask) prefetch_pixels(frame, y, span.x0, span.x1);
    }
  }
}

ComponentLabeler::SweepStart ComponentLabeler::begin_sweep(const ImageView& frame) {
  run_count_ = 0;
  comp_count_ = 0;
  window_cuts_ = 0;
  swept_px_ = 0;
  if (frame.width != width_ || frame.height != height_ || frame.empty())
    return SweepStart::kRefused;
  // Grey frames carry no colour: nothing can be red or green.
  if (frame.format == PixelFormat::kGray8 || frame.format == PixelFormat::kMjpeg)
    return SweepStart::kNoColour;
  return SweepStart::kSweep;
}

bool ComponentLabeler::sweep_rows(const ImageView& frame, const ColorClassifier& classifier) {
  const SweepStart start = begin_sweep(frame);
  if (start != SweepStart::kSweep) return start == SweepStart::kNoColour;
  int y_begin = height_, y_end = -1;
  for (const SweptWindow& w : swept_) {
    y_begin = std::min(y_begin, w.y0);
    y_end = std::max(y_end, w.y1);
  }
  int prev_begin = 0, prev_end = 0;
  for (int y = y_begin; y <= y_end; ++y) {
    const int cur_begin = run_count_;
    for (const SweptWindow& w : swept_) {
      if (y < w.y0 || y > w.y1) continue;
      const RowSpan span = spans_[static_cast<size_t>(w.first_span + (y - w.y0))];
      if (span.x1 < span.x0) continue;
      const int x0 = span.x0, x1 = span.x1;
      const size_t n = static_cast<size_t>(x1 - x0 + 1);
      classify_span(frame, y, x0, x1, classifier);
      swept_px_ += x1 - x0 + 1;
      // A run that starts or ends on a window's edge may continue beyond it
      // (the frame's own edges are accumulate()'s): row_edge_ marks those
      // pixels, and the whole span on a window's first and last row. A
      // quadrilateral's first and last rows are its box's (plan_tracking
      // makes the box from it); a blob at its pointed ends also meets its
      // slanted sides, which the span's ends mark.
      const bool cap = (y == w.y0 && y > 0) || (y == w.y1 && y < height_ - 1);
      if (cap) {
        std::memset(row_edge_.data() + x0, 1, n);
      } else {
        for (const int x : {x0, x1})
          if (x > 0 && x < width_ - 1) row_edge_[x] = 1;
      }
      // Spans are apart (boxes apart): each is encoded alone, in x order.
      const bool ok = encode_row(y, x0, x1);
      // Outside the spans the buffers stay zero (encode_row relies on it).
      std::memset(row_class_.data() + x0, 0, n);
      if (cap) {
        std::memset(row_edge_.data() + x0, 0, n);
      } else {
        row_edge_[x0] = 0;
        row_edge_[x1] = 0;
      }
      if (!ok) return false;
    }
    join_row(cur_begin, &prev_begin, &prev_end);
  }
  accumulate(width_, height_);
  return true;
}

void ComponentLabeler::classify_sampled_row(const ImageView& frame, int y, int step_px, int count,
                                            const ColorClassifier& classifier) {
  const uint8_t* row = frame.row(y);
  uint8_t* out = row_class_.data();
  const bool rgb = frame.format == PixelFormat::kRgb24;
  const int pairs = step_px / 2;
  switch (frame.format) {
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      if (step_px == 4) {
        lookup_rgb<12>(row, rgb, classifier, out, count);
      } else {
        lookup_rgb<6>(row, rgb, classifier, out, count);
      }
      return;
    case PixelFormat::kYuyv:
    case PixelFormat::kNv12:
    case PixelFormat::kYuv420: {
      int16_t* py = px_y_.data();
      int16_t* pu = px_u_.data();
      int16_t* pv = px_v_.data();
      const bool nv12 = frame.format == PixelFormat::kNv12;
      // Each sample's chroma: YUYV's in its pair, 4:2:0's in its chroma row
      // (NV12's U and V interleaved, I420's in planes).
      const int chroma_step = nv12 ? 2 : 1;
      const uint8_t* u = frame.format == PixelFormat::kYuyv ? nullptr
                         : nv12                             ? frame.uv_row(y)
                                                            : frame.u_row(y);
      const uint8_t* v = frame.format == PixelFormat::kYuyv ? nullptr
                         : nv12                             ? frame.uv_row(y) + 1
                                                            : frame.v_row(y);
      auto convert = [&](int b, int e) {
        if (frame.format == PixelFormat::kYuyv) {
          yuyv_sampled(row + kYuyvPairBytes * pairs * b, pairs, py + b, pu + b, pv + b, e - b);
        } else {
          const int c = chroma_step * pairs * b;
          planar_sampled(row + 2 * pairs * b, pairs, u + c, v + c, chroma_step, py + b, pu + b,
                         pv + b, e - b);
        }
        bt601_indices(py + b, pu + b, pv + b, classifier.gains_q16(), px_index_.data() + b, e - b);
        lookup_indices(px_index_.data() + b, classifier, out + b, e - b);
      };
      const YuvBox& box = classifier.background_yuv();
      if (box.empty()) {
        convert(0, count);
        return;
      }
      uint8_t* in = in_box_.data();
      const bool two = pairs == 2;
      if (frame.format == PixelFormat::kYuyv) {
        (two ? yuyv_in_box<2, false> : yuyv_in_box<1, false>)(row, box, in, count);
      } else if (nv12) {
        (two ? planar_in_box<4, 4> : planar_in_box<2, 2>)(row, u, v, box, in, count);
      } else {
        (two ? planar_in_box<4, 2> : planar_in_box<2, 1>)(row, u, v, box, in, count);
      }
      outside_box(in, count, convert);
      return;
    }
    case PixelFormat::kGray8:
    case PixelFormat::kMjpeg:
      std::memset(out, 0, static_cast<size_t>(count));
      return;
  }
}

bool ComponentLabeler::label_sampled(const ImageView& frame, const ColorClassifier& classifier,
                                     int step_px) {
  swept_.clear();
  if (step_px != 2 && step_px != 4) {
    begin_sweep(frame);
    return false;
  }
  const SweepStart start = begin_sweep(frame);
  if (start != SweepStart::kSweep) return start == SweepStart::kNoColour;
  const int s = step_px;
  const int columns = (width_ + s - 1) / s, rows = (height_ + s - 1) / s;
  run_budget_ =
      std::min(max_runs_, std::max(1024, static_cast<int>(static_cast<double>(columns) * rows *
                                                          params_.max_runs_per_pixel)));
  // Rows apart are separate streams to the hardware prefetcher, which
  // restarts at each: the rows ahead are asked for while this one is read.
  for (int j = 0; j < std::min(rows, kSampledRowsAhead); ++j)
    prefetch_pixels(frame, s * j, 0, width_ - 1);
  int prev_begin = 0, prev_end = 0;
  for (int j = 0; j < rows; ++j) {
    const int cur_begin = run_count_;
    if (j + kSampledRowsAhead < rows)
      prefetch_pixels(frame, s * (j + kSampledRowsAhead), 0, width_ - 1);
    classify_sampled_row(frame, s * j, s, columns, classifier);
    swept_px_ += columns;
    const bool ok = encode_row(j, 0, columns - 1);
    std::memset(row_class_.data(), 0, static_cast<size_t>(columns));
    if (!ok) return false;
    join_row(cur_begin, &prev_begin, &prev_end);
  }
  accumulate(columns, rows);
  // A lattice of step s holds (s² - 1)/12 px² less variance per axis than
  // the frame's pixels of the region it samples.
  const double lattice_var_px2 = (s * s - 1) / 12.0;
  for (size_t k = 0; k < comp_count_; ++k) {
    Component& c = comps_[k];
    c.area_px *= s * s;
    c.dark_px *= s * s;
    c.x_min *= s;
    c.y_min *= s;
    c.x_max = std::min(s * c.x_max + s - 1, width_ - 1);
    c.y_max = std::min(s * c.y_max + s - 1, height_ - 1);
    c.cx *= s;
    c.cy *= s;
    c.mu20 = s * s * c.mu20 + lattice_var_px2;
    c.mu11 = s * s * c.mu11;
    c.mu02 = s * s * c.mu02 + lattice_var_px2;
  }
  return true;
}

int merge_windows(std::span<PixelWindow> windows, int count) {
  // Windows that overlap or touch (diagonals included: a blob could join
  // them) become their bounding box, until none do.
  auto touch = [](const PixelWindow& a, const PixelWindow& b) {
    return a.x0 <= b.x1 + 1 && b.x0 <= a.x1 + 1 && a.y0 <= b.y1 + 1 && b.y0 <= a.y1 + 1;
  };
  bool merged = true;
  while (merged) {
    merged = false;
    for (int i = 0; i < count && !merged; ++i) {
      for (int j = i + 1; j < count; ++j) {
        if (!touch(windows[i], windows[j])) continue;
        PixelWindow& a = windows[i];
        const PixelWindow& b = windows[j];
        a = PixelWindow{std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1),
                        std::max(a.y1, b.y1)};  // a box: the quadrilaterals are dropped
        windows[j] = windows[--count];
        merged = true;
        break;
      }
    }
  }
  return count;
}

}  // namespace ceilpose
