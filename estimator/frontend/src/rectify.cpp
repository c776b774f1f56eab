#include "swf/frontend/rectify.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#elif defined(__aarch64__)
#include <arm_neon.h>
#endif

namespace swf::frontend {

using core::Status;
using estimator::Mat3;
using estimator::Vec3;

namespace {

using rectify_detail::Segment;
using rectify_detail::SegmentKind;
constexpr int kSegment = rectify_detail::kSegment;

// Fixed point of the source coordinates and bilinear weights: 1/128 px.
constexpr int kWeightBits = 7;
constexpr int kWeightOne = 1 << kWeightBits;
constexpr float kWeightOneF = static_cast<float>(kWeightOne);

// GCC vector extensions (SSE2 / NEON).
using V4f [[gnu::vector_size(16)]] = float;
using V4i [[gnu::vector_size(16)]] = std::int32_t;
using V8s [[gnu::vector_size(16)]] = std::int16_t;
using V8u [[gnu::vector_size(16)]] = std::uint16_t;
using V8b [[gnu::vector_size(8)]] = std::uint8_t;

// Low 16 bits of 8 int32 lanes.
inline V8s Narrow(V4i lo, V4i hi) {
  return __builtin_shufflevector(reinterpret_cast<V8s>(lo), reinterpret_cast<V8s>(hi), 0, 2, 4, 6,
                                 8, 10, 12, 14);
}

inline std::uint16_t Load16(const std::uint8_t* p) {
  std::uint16_t v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// The segment's quadratic; the vector code of every kernel performs the same float operations
// (the library is built with -ffp-contract=off, and no kernel enables FMA).
inline float EvalSegment(const float* c, float k) { return c[0] + k * (c[1] + k * c[2]); }

// Source coordinates (1/128 px, rounded) of pixels q .. q + 7 of a segment.
struct Coords8 {
  V4i fx_lo;
  V4i fx_hi;
  V4i fy_lo;
  V4i fy_hi;
};

[[gnu::always_inline]] inline Coords8 SegmentCoords(const Segment& seg, int q) {
  const V4f lane = {0.0f, 1.0f, 2.0f, 3.0f};
  const V4f x0 = {seg.x[0], seg.x[0], seg.x[0], seg.x[0]};
  const V4f x1 = {seg.x[1], seg.x[1], seg.x[1], seg.x[1]};
  const V4f x2 = {seg.x[2], seg.x[2], seg.x[2], seg.x[2]};
  const V4f y0 = {seg.y[0], seg.y[0], seg.y[0], seg.y[0]};
  const V4f y1 = {seg.y[1], seg.y[1], seg.y[1], seg.y[1]};
  const V4f y2 = {seg.y[2], seg.y[2], seg.y[2], seg.y[2]};
  const V4f k_lo = lane + static_cast<float>(q);
  const V4f k_hi = k_lo + 4.0f;
  // The same operations as EvalSegment, 4 lanes at a time; truncation rounds.
  return {__builtin_convertvector(x0 + k_lo * (x1 + k_lo * x2), V4i),
          __builtin_convertvector(x0 + k_hi * (x1 + k_hi * x2), V4i),
          __builtin_convertvector(y0 + k_lo * (y1 + k_lo * y2), V4i),
          __builtin_convertvector(y0 + k_hi * (y1 + k_hi * y2), V4i)};
}

// Bilinear blend of 8 pixels: t / b hold the top / bottom tap pairs (low byte: left tap), ax / ay
// the weights in 1/128. 16-bit lanes, exact (file comment).
[[gnu::always_inline]] inline V8b Blend8(V8u t, V8u b, V8s ax, V8s ay) {
  const V8s bx = kWeightOne - ax;
  const V8s upper = reinterpret_cast<V8s>(t & 0xFF) * bx + reinterpret_cast<V8s>(t >> 8) * ax;
  const V8s lower = reinterpret_cast<V8s>(b & 0xFF) * bx + reinterpret_cast<V8s>(b >> 8) * ax;
  // upper + (lower - upper) ay / 128 with 16-bit products: split the difference into its
  // high (signed) and low (unsigned) byte.
  const V8s d = lower - upper;
  const V8s mid = upper + (((d >> 8) * ay) << 1) + (((d & 0xFF) * ay) >> kWeightBits);
  const V8s result = (mid + (kWeightOne / 2)) >> kWeightBits;
  return __builtin_convertvector(result, V8b);
}

// One segment whose taps are all inside, gathered with a 16-bit load per tap pair (kInside in the
// SIMD kernels). Writes kSegment bytes.
[[gnu::always_inline]] inline void GatherSegment(const Segment& seg, const std::uint8_t* src,
                                                 std::int32_t stride, std::uint8_t* dst) {
  const V4i stride4 = {stride, stride, stride, stride};
  for (int q = 0; q < kSegment; q += 8) {
    const Coords8 c = SegmentCoords(seg, q);
    const V4i off_lo = (c.fy_lo >> kWeightBits) * stride4 + (c.fx_lo >> kWeightBits);
    const V4i off_hi = (c.fy_hi >> kWeightBits) * stride4 + (c.fx_hi >> kWeightBits);
    V8u t;
    V8u b;
    for (int i = 0; i < 4; ++i) {
      t[i] = Load16(src + off_lo[i]);
      b[i] = Load16(src + stride + off_lo[i]);
      t[i + 4] = Load16(src + off_hi[i]);
      b[i + 4] = Load16(src + stride + off_hi[i]);
    }
    const V8s ax = Narrow(c.fx_lo, c.fx_hi) & (kWeightOne - 1);
    const V8s ay = Narrow(c.fy_lo, c.fy_hi) & (kWeightOne - 1);
    const V8b bytes = Blend8(t, b, ax, ay);
    std::memcpy(dst + q, &bytes, sizeof(bytes));
  }
}

// Shuffle-index arithmetic of a window half (kWindow): dx = column - base (0 .. 14) and dy = row -
// top row (0 or 1) per 16-bit lane. Returns the byte indices into row r (idx_a) and row r + 1
// (idx_b): lane bytes dx, dx + 1, with the top bit set (lookup gives 0) where the other row holds
// the taps. The top taps are shuffle(row r, idx_a) | shuffle(row r + 1, idx_b), the bottom taps
// shuffle(row r + 1, idx_a) | shuffle(row r + 2, idx_b).
template <class V>
[[gnu::always_inline]] inline void WindowIndices(V dx, V dy, V* idx_a, V* idx_b) {
  const V idx = dx * 257 + 256;
  const V m = dy * 0x8080;
  *idx_a = idx | m;
  *idx_b = idx | (m ^ 0x8080);
}

// Everything a kernel needs for one image.
struct RemapJob {
  const Segment* segment;
  const SegmentKind* kind;
  int segments_per_row;
  int width;
  int height;
  const GrayView* raw;
  const MutableGrayView* out;
};

#if defined(__x86_64__)
using M128 = __m128i;

// One 8-pixel half of a kWindow segment with SSSE3 byte shuffles.
__attribute__((target("ssse3"))) inline V8b WindowHalfSsse3(const Coords8& c, int base, int row,
                                                            const std::uint8_t* src,
                                                            std::int32_t stride) {
  // Lanes fit 16 bits (raw sides < 2^15): the saturating pack is exact.
  const auto cx =
      reinterpret_cast<V8u>(_mm_packs_epi32(reinterpret_cast<M128>(c.fx_lo >> kWeightBits),
                                            reinterpret_cast<M128>(c.fx_hi >> kWeightBits)));
  const auto cy =
      reinterpret_cast<V8u>(_mm_packs_epi32(reinterpret_cast<M128>(c.fy_lo >> kWeightBits),
                                            reinterpret_cast<M128>(c.fy_hi >> kWeightBits)));
  V8u idx_a;
  V8u idx_b;
  WindowIndices(cx - static_cast<std::uint16_t>(base), cy - static_cast<std::uint16_t>(row), &idx_a,
                &idx_b);
  const std::uint8_t* p = src + static_cast<std::ptrdiff_t>(row) * stride + base;
  const M128 r0 = _mm_loadu_si128(reinterpret_cast<const M128*>(p));
  const M128 r1 = _mm_loadu_si128(reinterpret_cast<const M128*>(p + stride));
  const M128 r2 = _mm_loadu_si128(reinterpret_cast<const M128*>(p + 2 * stride));
  const auto ia = reinterpret_cast<M128>(idx_a);
  const auto ib = reinterpret_cast<M128>(idx_b);
  // Blend8 with the horizontal step as one byte multiply-add on taps offset by -128 (exact; the
  // AVX2 kernel's comment).
  const M128 bias = _mm_set1_epi8(static_cast<char>(0x80));
  const M128 t =
      _mm_xor_si128(_mm_or_si128(_mm_shuffle_epi8(r0, ia), _mm_shuffle_epi8(r1, ib)), bias);
  const M128 b =
      _mm_xor_si128(_mm_or_si128(_mm_shuffle_epi8(r1, ia), _mm_shuffle_epi8(r2, ib)), bias);
  const M128 ax = _mm_packs_epi32(reinterpret_cast<M128>(c.fx_lo & (kWeightOne - 1)),
                                  reinterpret_cast<M128>(c.fx_hi & (kWeightOne - 1)));
  const auto ay =
      reinterpret_cast<V8s>(_mm_packs_epi32(reinterpret_cast<M128>(c.fy_lo & (kWeightOne - 1)),
                                            reinterpret_cast<M128>(c.fy_hi & (kWeightOne - 1))));
  const M128 wx =
      _mm_or_si128(_mm_sub_epi16(_mm_set1_epi16(kWeightOne), ax), _mm_slli_epi16(ax, 8));
  const auto upper = reinterpret_cast<V8s>(_mm_maddubs_epi16(wx, t));
  const auto lower = reinterpret_cast<V8s>(_mm_maddubs_epi16(wx, b));
  const V8s d = lower - upper;
  const V8s mid = upper + (((d >> 8) * ay) << 1) + (((d & 0xFF) * ay) >> kWeightBits);
  const V8s result = (mid + (kWeightOne / 2)) >> kWeightBits;  // -128 .. 127
  const M128 bytes = _mm_xor_si128(
      _mm_packs_epi16(reinterpret_cast<M128>(result), reinterpret_cast<M128>(result)), bias);
  V8b out;
  std::memcpy(&out, &bytes, sizeof(out));
  return out;
}

// SSSE3 kernel: kWindow segments by shuffles, kInside by 16-bit gathers; the rest is left to the
// per-pixel pass.
__attribute__((target("ssse3"))) void RemapSsse3(RemapJob job) {  // a copy: o aliases anything
  const std::uint8_t* src = job.raw->data;
  const std::int32_t stride = job.raw->stride;
  for (int v = 0; v < job.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
    std::uint8_t* o = job.out->Row(v);
    for (int s = 0; s < job.segments_per_row; ++s) {
      const Segment& seg = job.segment[row + s];
      const int u0 = s * kSegment;
      if (job.kind[row + s] == SegmentKind::kWindow) {
        for (int q = 0; q < kSegment; q += 8) {
          const V8b bytes = WindowHalfSsse3(SegmentCoords(seg, q), seg.window[q / 8],
                                            seg.window[2 + q / 8], src, stride);
          std::memcpy(o + u0 + q, &bytes, sizeof(bytes));
        }
      } else if (job.kind[row + s] == SegmentKind::kInside) {
        alignas(16) std::uint8_t bytes[kSegment];
        GatherSegment(seg, src, stride, bytes);
        std::memcpy(o + u0, bytes, static_cast<std::size_t>(std::min(kSegment, job.width - u0)));
      }
    }
  }
}

using V8f [[gnu::vector_size(32)]] = float;
using V8i [[gnu::vector_size(32)]] = std::int32_t;
using V16s [[gnu::vector_size(32)]] = std::int16_t;
using V16u [[gnu::vector_size(32)]] = std::uint16_t;
using M256 = __m256i;

// AVX2 kernel: a kWindow segment in one pass of 16 lanes (128-bit half h of each register holds
// pixels 8h .. 8h + 7, as the in-lane byte shuffle and pack need).
__attribute__((target("avx2"))) void RemapAvx2(RemapJob job) {  // a copy: o aliases anything
  const std::uint8_t* src = job.raw->data;
  const std::int32_t stride = job.raw->stride;
  // Pixel index of each lane: the pack of (lo, hi) interleaves 128-bit halves.
  const V8f k_lo = {0.0f, 1.0f, 2.0f, 3.0f, 8.0f, 9.0f, 10.0f, 11.0f};
  const V8f k_hi = {4.0f, 5.0f, 6.0f, 7.0f, 12.0f, 13.0f, 14.0f, 15.0f};
  // Byte selectors of the segment's window origin (Segment::window, broadcast to every 64-bit
  // lane): the column / row of half h in 128-bit lane h.
  const M256 column_of = _mm256_setr_epi8(0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 2, 3, 2,
                                          3, 2, 3, 2, 3, 2, 3, 2, 3, 2, 3, 2, 3);
  // Constants kept in memory: GCC otherwise rebuilds each broadcast constant inside the loop
  // (mov, vmovd, vpbroadcast) for lack of registers; the empty asm hides their values, so they stay
  // memory operands.
  alignas(32) M256 bytes_of[3] = {_mm256_set1_epi8(static_cast<char>(0x80)),
                                  _mm256_set1_epi32(kWeightOne - 1), _mm256_set1_epi16(kWeightOne)};
  alignas(32) V16s signed_of[2] = {V16s{} + 0xFF, V16s{} + kWeightOne / 2};
  alignas(32) V16u unsigned_of[2] = {V16u{} + 0x8080, V16u{} + 256};
  asm("" : : "r"(bytes_of), "r"(signed_of), "r"(unsigned_of) : "memory");
  const M256& bias = bytes_of[0];
  const M256& frac = bytes_of[1];
  const M256& one = bytes_of[2];
  const V16s& low_byte = signed_of[0];
  const V16s& half = signed_of[1];
  const V16u& select = unsigned_of[0];
  const V16u& next = unsigned_of[1];
  const M256 row_of = _mm256_setr_epi8(4, 5, 4, 5, 4, 5, 4, 5, 4, 5, 4, 5, 4, 5, 4, 5, 6, 7, 6, 7,
                                       6, 7, 6, 7, 6, 7, 6, 7, 6, 7, 6, 7);
  for (int v = 0; v < job.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
    std::uint8_t* o = job.out->Row(v);
    for (int s = 0; s < job.segments_per_row; ++s) {
      const Segment& seg = job.segment[row + s];
      const int u0 = s * kSegment;
      if (job.kind[row + s] == SegmentKind::kWindow) {
        const V8f x0 = {seg.x[0], seg.x[0], seg.x[0], seg.x[0],
                        seg.x[0], seg.x[0], seg.x[0], seg.x[0]};
        const V8f x1 = {seg.x[1], seg.x[1], seg.x[1], seg.x[1],
                        seg.x[1], seg.x[1], seg.x[1], seg.x[1]};
        const V8f x2 = {seg.x[2], seg.x[2], seg.x[2], seg.x[2],
                        seg.x[2], seg.x[2], seg.x[2], seg.x[2]};
        const V8f y0 = {seg.y[0], seg.y[0], seg.y[0], seg.y[0],
                        seg.y[0], seg.y[0], seg.y[0], seg.y[0]};
        const V8f y1 = {seg.y[1], seg.y[1], seg.y[1], seg.y[1],
                        seg.y[1], seg.y[1], seg.y[1], seg.y[1]};
        const V8f y2 = {seg.y[2], seg.y[2], seg.y[2], seg.y[2],
                        seg.y[2], seg.y[2], seg.y[2], seg.y[2]};
        // The same operations as EvalSegment; truncation rounds.
        const V8i fx_lo = __builtin_convertvector(x0 + k_lo * (x1 + k_lo * x2), V8i);
        const V8i fx_hi = __builtin_convertvector(x0 + k_hi * (x1 + k_hi * x2), V8i);
        const V8i fy_lo = __builtin_convertvector(y0 + k_lo * (y1 + k_lo * y2), V8i);
        const V8i fy_hi = __builtin_convertvector(y0 + k_hi * (y1 + k_hi * y2), V8i);
        const auto cx = reinterpret_cast<V16u>(
            _mm256_packs_epi32(reinterpret_cast<M256>(fx_lo >> kWeightBits),
                               reinterpret_cast<M256>(fx_hi >> kWeightBits)));
        const auto cy = reinterpret_cast<V16u>(
            _mm256_packs_epi32(reinterpret_cast<M256>(fy_lo >> kWeightBits),
                               reinterpret_cast<M256>(fy_hi >> kWeightBits)));
        std::int64_t origin;
        std::memcpy(&origin, seg.window, sizeof(origin));
        const M256 origins = _mm256_set1_epi64x(origin);
        const auto cx0 = reinterpret_cast<V16u>(_mm256_shuffle_epi8(origins, column_of));
        const auto cy0 = reinterpret_cast<V16u>(_mm256_shuffle_epi8(origins, row_of));
        // WindowIndices with the constants above.
        const V16u dx = cx - cx0;
        const V16u idx_a = ((dx << 8) + dx + next) | ((cy - cy0) * select);
        const V16u idx_b = idx_a ^ select;
        const std::uint8_t* p0 =
            src + static_cast<std::ptrdiff_t>(seg.window[2]) * stride + seg.window[0];
        const std::uint8_t* p1 =
            src + static_cast<std::ptrdiff_t>(seg.window[3]) * stride + seg.window[1];
        const M256 r0 = _mm256_loadu2_m128i(reinterpret_cast<const M128*>(p1),
                                            reinterpret_cast<const M128*>(p0));
        const M256 r1 = _mm256_loadu2_m128i(reinterpret_cast<const M128*>(p1 + stride),
                                            reinterpret_cast<const M128*>(p0 + stride));
        const M256 r2 = _mm256_loadu2_m128i(reinterpret_cast<const M128*>(p1 + 2 * stride),
                                            reinterpret_cast<const M128*>(p0 + 2 * stride));
        const auto ia = reinterpret_cast<M256>(idx_a);
        const auto ib = reinterpret_cast<M256>(idx_b);
        // Tap pairs with 128 subtracted (x ^ 0x80: signed bytes), so that the horizontal blend is
        // one unsigned-by-signed byte multiply-add: upper' = p0' (128 - ax) + p1' ax = upper - 2^14
        // in [-2^14, 2^14 - 128]; the vertical step of Blend8 is exact on these (|d| unchanged,
        // floor division by arithmetic shifts), and the result comes out 128 lower.
        const M256 t = _mm256_xor_si256(
            _mm256_or_si256(_mm256_shuffle_epi8(r0, ia), _mm256_shuffle_epi8(r1, ib)), bias);
        const M256 b = _mm256_xor_si256(
            _mm256_or_si256(_mm256_shuffle_epi8(r1, ia), _mm256_shuffle_epi8(r2, ib)), bias);
        const M256 ax = _mm256_packs_epi32(_mm256_and_si256(reinterpret_cast<M256>(fx_lo), frac),
                                           _mm256_and_si256(reinterpret_cast<M256>(fx_hi), frac));
        const auto ay = reinterpret_cast<V16s>(
            _mm256_packs_epi32(_mm256_and_si256(reinterpret_cast<M256>(fy_lo), frac),
                               _mm256_and_si256(reinterpret_cast<M256>(fy_hi), frac)));
        // Weight bytes (128 - ax, ax) per pixel.
        const M256 wx = _mm256_or_si256(_mm256_sub_epi16(one, ax), _mm256_slli_epi16(ax, 8));
        const auto upper = reinterpret_cast<V16s>(_mm256_maddubs_epi16(wx, t));
        const auto lower = reinterpret_cast<V16s>(_mm256_maddubs_epi16(wx, b));
        const V16s d = lower - upper;
        const V16s mid = upper + (((d >> 8) * ay) << 1) + (((d & low_byte) * ay) >> kWeightBits);
        const V16s result = (mid + half) >> kWeightBits;  // -128 .. 127
        const M256 bytes = _mm256_xor_si256(
            _mm256_permute4x64_epi64(
                _mm256_packs_epi16(reinterpret_cast<M256>(result), reinterpret_cast<M256>(result)),
                0x08),
            bias);
        _mm_storeu_si128(reinterpret_cast<M128*>(o + u0), _mm256_castsi256_si128(bytes));
      } else if (job.kind[row + s] == SegmentKind::kInside) {
        alignas(16) std::uint8_t bytes[kSegment];
        GatherSegment(seg, src, stride, bytes);
        std::memcpy(o + u0, bytes, static_cast<std::size_t>(std::min(kSegment, job.width - u0)));
      }
    }
  }
}
#endif  // __x86_64__

#if defined(__aarch64__)
// NEON kernel: the SSSE3 kernel's window halves with TBL (indices >= 16 give 0).
void RemapNeon(RemapJob job) {  // a copy: o aliases anything
  const std::uint8_t* src = job.raw->data;
  const std::int32_t stride = job.raw->stride;
  for (int v = 0; v < job.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
    std::uint8_t* o = job.out->Row(v);
    for (int s = 0; s < job.segments_per_row; ++s) {
      const Segment& seg = job.segment[row + s];
      const int u0 = s * kSegment;
      if (job.kind[row + s] == SegmentKind::kWindow) {
        for (int q = 0; q < kSegment; q += 8) {
          const Coords8 c = SegmentCoords(seg, q);
          const int base = seg.window[q / 8];
          const int top = seg.window[2 + q / 8];
          const auto cx =
              reinterpret_cast<V8u>(Narrow(c.fx_lo >> kWeightBits, c.fx_hi >> kWeightBits));
          const auto cy =
              reinterpret_cast<V8u>(Narrow(c.fy_lo >> kWeightBits, c.fy_hi >> kWeightBits));
          V8u idx_a;
          V8u idx_b;
          WindowIndices(cx - static_cast<std::uint16_t>(base), cy - static_cast<std::uint16_t>(top),
                        &idx_a, &idx_b);
          const std::uint8_t* p = src + static_cast<std::ptrdiff_t>(top) * stride + base;
          const uint8x16_t r0 = vld1q_u8(p);
          const uint8x16_t r1 = vld1q_u8(p + stride);
          const uint8x16_t r2 = vld1q_u8(p + 2 * stride);
          const auto ia = vreinterpretq_u8_u16(reinterpret_cast<uint16x8_t>(idx_a));
          const auto ib = vreinterpretq_u8_u16(reinterpret_cast<uint16x8_t>(idx_b));
          const auto t = reinterpret_cast<V8u>(vorrq_u8(vqtbl1q_u8(r0, ia), vqtbl1q_u8(r1, ib)));
          const auto b = reinterpret_cast<V8u>(vorrq_u8(vqtbl1q_u8(r1, ia), vqtbl1q_u8(r2, ib)));
          const V8s ax = Narrow(c.fx_lo, c.fx_hi) & (kWeightOne - 1);
          const V8s ay = Narrow(c.fy_lo, c.fy_hi) & (kWeightOne - 1);
          const V8b bytes = Blend8(t, b, ax, ay);
          std::memcpy(o + u0 + q, &bytes, sizeof(bytes));
        }
      } else if (job.kind[row + s] == SegmentKind::kInside) {
        alignas(16) std::uint8_t bytes[kSegment];
        GatherSegment(seg, src, stride, bytes);
        std::memcpy(o + u0, bytes, static_cast<std::size_t>(std::min(kSegment, job.width - u0)));
      }
    }
  }
}
#endif  // __aarch64__

// Portable kernel (any GCC target): per row, the coordinates of every fast-path pixel, then
// 16-bit gathers lane by lane and the blend, 8 pixels at a time.
void RemapPortable(const RemapJob& job) {
  constexpr int kRow = kMaxImageWidth + kSegment;
  alignas(16) std::int32_t offset[kRow];
  alignas(16) std::int16_t wx[kRow];
  alignas(16) std::int16_t wy[kRow];
  alignas(16) std::uint8_t blended[kRow];
  const int w = job.width;
  const int padded = job.segments_per_row * kSegment;
  const std::int32_t stride = job.raw->stride;
  const V4i stride4 = {stride, stride, stride, stride};
  for (int v = 0; v < job.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
    // 1. Source coordinates of the row in 1/128 px: offset of the top-left tap and the weights.
    for (int s = 0; s < job.segments_per_row; ++s) {
      const int u0 = s * kSegment;
      const SegmentKind kind = job.kind[row + s];
      if (kind != SegmentKind::kInside && kind != SegmentKind::kWindow) {
        for (int k = 0; k < kSegment; ++k) {
          offset[u0 + k] = 0;  // a harmless tap; the pixels are redone by the per-pixel pass
          wx[u0 + k] = 0;
          wy[u0 + k] = 0;
        }
        continue;
      }
      for (int q = 0; q < kSegment; q += 8) {
        const Coords8 c = SegmentCoords(job.segment[row + s], q);
        const V4i off_lo = (c.fy_lo >> kWeightBits) * stride4 + (c.fx_lo >> kWeightBits);
        const V4i off_hi = (c.fy_hi >> kWeightBits) * stride4 + (c.fx_hi >> kWeightBits);
        const V8s ax = Narrow(c.fx_lo, c.fx_hi) & (kWeightOne - 1);
        const V8s ay = Narrow(c.fy_lo, c.fy_hi) & (kWeightOne - 1);
        std::memcpy(offset + u0 + q, &off_lo, sizeof(off_lo));
        std::memcpy(offset + u0 + q + 4, &off_hi, sizeof(off_hi));
        std::memcpy(wx + u0 + q, &ax, sizeof(ax));
        std::memcpy(wy + u0 + q, &ay, sizeof(ay));
      }
    }
    for (int u = w; u < padded; ++u) offset[u] = 0;  // lanes past the last pixel
    // 2. Gather the two source bytes of the top and of the bottom row (one 16-bit load each,
    // straight into a vector lane) and 3. blend.
    const std::uint8_t* src = job.raw->data;
    const std::uint8_t* below = src + stride;
    for (int u = 0; u < padded; u += 8) {
      const std::int32_t* off = offset + u;
      V8u t;
      V8u b;
      for (int i = 0; i < 8; ++i) {  // unrolled: one 16-bit lane insert per load
        t[i] = Load16(src + off[i]);
        b[i] = Load16(below + off[i]);
      }
      V8s ax;
      V8s ay;
      std::memcpy(&ax, wx + u, sizeof(ax));
      std::memcpy(&ay, wy + u, sizeof(ay));
      const V8b bytes = Blend8(t, b, ax, ay);
      std::memcpy(blended + u, &bytes, sizeof(bytes));
    }
    std::memcpy(job.out->Row(v), blended, static_cast<std::size_t>(w));
  }
}

bool KernelSupported(RemapKernel kernel) {
  switch (kernel) {
    case RemapKernel::kPortable: return true;
#if defined(__x86_64__)
    case RemapKernel::kSsse3: __builtin_cpu_init(); return __builtin_cpu_supports("ssse3") != 0;
    case RemapKernel::kAvx2: __builtin_cpu_init(); return __builtin_cpu_supports("avx2") != 0;
#elif defined(__aarch64__)
    case RemapKernel::kNeon: return true;
#endif
    default: return false;
  }
}

RemapKernel BestKernel() {
  for (const RemapKernel k : {RemapKernel::kAvx2, RemapKernel::kNeon, RemapKernel::kSsse3}) {
    if (KernelSupported(k)) return k;
  }
  return RemapKernel::kPortable;
}

bool ValidCalibration(const CameraCalibration& c) {
  return c.width > 1 && c.height > 1 && c.fx > 0.0 && c.fy > 0.0 && std::isfinite(c.cx) &&
         std::isfinite(c.cy) && std::isfinite(c.k1) && std::isfinite(c.k2) && std::isfinite(c.p1) &&
         std::isfinite(c.p2) && std::isfinite(c.k3);
}

// True when each 8-pixel half of an all-inside segment finds its taps in a 16 x 3 window inside
// the raw image (SegmentKind::kWindow); the window's top-left pixel, the smaller column and row of
// the top-left taps of the half's first and last pixel, is stored in seg->window.
bool WindowSegment(Segment* seg, int raw_width, int raw_height) {
  auto column = [&](int k) {
    return static_cast<int>(EvalSegment(seg->x, static_cast<float>(k))) >> kWeightBits;
  };
  auto row = [&](int k) {
    return static_cast<int>(EvalSegment(seg->y, static_cast<float>(k))) >> kWeightBits;
  };
  for (int h = 0; h < 2; ++h) {
    const int first = h * 8;
    const int base = std::min(column(first), column(first + 7));
    const int top = std::min(row(first), row(first + 7));
    if (base + 15 > raw_width - 1 || top + 2 > raw_height - 1) return false;
    for (int k = first; k < first + 8; ++k) {
      const int dx = column(k) - base;
      const int dy = row(k) - top;
      if (dx < 0 || dx > 14 || dy < 0 || dy > 1) return false;
    }
    seg->window[h] = static_cast<std::int16_t>(base);  // raw sides < 2^15
    seg->window[2 + h] = static_cast<std::int16_t>(top);
  }
  return true;
}

}  // namespace

bool StereoRectifier::RawPixel(int camera, double u, double v, double* raw_u, double* raw_v) const {
  const CameraCalibration& c = calib_[camera];
  const Vec3<double> ray((u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0);
  const Vec3<double> p = rect_from_cam_[camera].transpose() * ray;
  if (!(p.z() > 1e-6)) return false;
  const double x = p.x() / p.z();
  const double y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
  const double xd = x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y;
  *raw_u = c.fx * xd + c.cx;
  *raw_v = c.fy * yd + c.cy;
  return true;
}

Status StereoRectifier::Configure(const CameraCalibration& left, const CameraCalibration& right,
                                  const RectifyOptions& options) {
  configured_ = false;
  if (!ValidCalibration(left) || !ValidCalibration(right) || !(options.focal_scale > 0.0)) {
    return Status::kInvalidArgument;
  }
  const RemapKernel kernel = options.kernel == RemapKernel::kAuto ? BestKernel() : options.kernel;
  if (!KernelSupported(kernel)) return Status::kInvalidArgument;
  kernel_ = kernel;
  const int w = options.width > 0 ? options.width : left.width;
  const int h = options.height > 0 ? options.height : left.height;
  // Raw sizes are bounded so that source offsets fit 32 bits.
  constexpr int kMaxRawSide = 1 << 15;
  if (w > kMaxImageWidth || h > kMaxImageHeight || left.width >= kMaxRawSide ||
      right.width >= kMaxRawSide || left.height >= kMaxRawSide || right.height >= kMaxRawSide) {
    return Status::kInvalidArgument;
  }
  calib_[0] = left;
  calib_[1] = right;
  const estimator::Pose<double> left_T_right = left.body_T_camera.Inverse() * right.body_T_camera;
  const Vec3<double> t = left_T_right.t;
  const double baseline = t.norm();
  if (!(baseline > 1e-6)) return Status::kInvalidArgument;
  const Mat3<double> left_R_mid =
      estimator::ExpSO3<double>(0.5 * estimator::LogSO3<double>(left_T_right.R));
  const Vec3<double> e1 = t / baseline;
  Vec3<double> e2 = left_R_mid.col(2).cross(e1);
  if (!(e2.norm() > 1e-6)) return Status::kInvalidArgument;  // baseline along the optical axis
  e2.normalize();
  const Vec3<double> e3 = e1.cross(e2);
  Mat3<double> rect_R_left;
  rect_R_left.row(0) = e1.transpose();
  rect_R_left.row(1) = e2.transpose();
  rect_R_left.row(2) = e3.transpose();
  rect_from_cam_[0] = rect_R_left;
  rect_from_cam_[1] = rect_R_left * left_T_right.R;

  // Shared intrinsics: the mean focal length, and a principal point that keeps the mean of the
  // two raw principal rays at the mean of the raw principal points (scaled to the output size).
  const double f = options.focal_scale * 0.25 * (left.fx + left.fy + right.fx + right.fy);
  double ray_x = 0.0;
  double ray_y = 0.0;
  for (int c = 0; c < 2; ++c) {
    const Vec3<double> axis = rect_from_cam_[c].col(2);
    ray_x += 0.5 * axis.x() / axis.z();
    ray_y += 0.5 * axis.y() / axis.z();
  }
  const double sx = static_cast<double>(w) / left.width;
  const double sy = static_cast<double>(h) / left.height;
  camera_.fx = f;
  camera_.fy = f;
  camera_.cx = 0.5 * (left.cx + right.cx) * sx - f * ray_x;
  camera_.cy = 0.5 * (left.cy + right.cy) * sy - f * ray_y;
  camera_.baseline_m = baseline;
  estimator::Pose<double> left_T_rect;
  left_T_rect.R = rect_R_left.transpose();
  rectified_in_body_ = left.body_T_camera * left_T_rect;
  width_ = w;
  height_ = h;
  segments_per_row_ = (w + kSegment - 1) / kSegment;

  max_table_error_px_ = 0.0;
  std::size_t windows = 0;
  identity_ = left.width == w && left.height == h && right.width == w && right.height == h;
  for (int c = 0; c < 2; ++c) {
    const CameraCalibration& cal = calib_[c];
    Table& table = table_[c];
    // Fixed-point limits (1/128 px): the fast path needs both taps inside (X <= (w-1)*128 - 1);
    // a pixel has a source when 0 <= X <= (w-1)*128.
    const auto fast_x = static_cast<float>((cal.width - 1) * kWeightOne);
    const auto fast_y = static_cast<float>((cal.height - 1) * kWeightOne);
    for (int v = 0; v < h; ++v) {
      table.row_inside[v] = true;
      for (int s = 0; s < segments_per_row_; ++s) {
        const std::size_t index = static_cast<std::size_t>(v) * segments_per_row_ + s;
        Segment& seg = table.segment[index];
        const int u0 = s * kSegment;
        const int len = std::min(kSegment, w - u0);
        double ex[kSegment] = {};
        double ey[kSegment] = {};
        bool visible = true;
        for (int k = 0; k < len; ++k) visible = visible && RawPixel(c, u0 + k, v, &ex[k], &ey[k]);
        const double last = len - 1;
        const double mid = 0.5 * last;
        double mx = 0.0;
        double my = 0.0;
        visible = visible && RawPixel(c, u0 + mid, v, &mx, &my);
        if (!visible) {  // part of the segment is behind the camera: no source at all
          seg = Segment{};
          table.kind[index] = SegmentKind::kOutside;
          table.row_inside[v] = false;
          identity_ = false;
          continue;
        }
        // Quadratic through k = 0, last / 2, last (Newton form converted to monomials).
        auto fit = [&](double f0, double fm, double fl, float* coef) {
          double c1 = 0.0;
          double c2 = 0.0;
          if (len > 1) {
            const double slope_m = (fm - f0) / mid;
            const double slope_l = (fl - f0) / last;
            c2 = (slope_l - slope_m) / (last - mid);
            c1 = slope_m - c2 * mid;
          }
          // Stored in 1/128 px with the rounding offset folded in: truncation rounds.
          coef[0] = static_cast<float>(f0 * kWeightOne + 0.5);
          coef[1] = static_cast<float>(c1 * kWeightOne);
          coef[2] = static_cast<float>(c2 * kWeightOne);
        };
        fit(ex[0], mx, ex[len - 1], seg.x);
        fit(ey[0], my, ey[len - 1], seg.y);
        bool all_fast = true;
        bool any_source = false;
        for (int k = 0; k < len; ++k) {
          const float fx = EvalSegment(seg.x, static_cast<float>(k));
          const float fy = EvalSegment(seg.y, static_cast<float>(k));
          const double tx = (fx - 0.5) / kWeightOne;
          const double ty = (fy - 0.5) / kWeightOne;
          const bool source = fx >= 0.0f && fy >= 0.0f && fx < fast_x + 1.0f && fy < fast_y + 1.0f;
          all_fast = all_fast && fx >= 0.0f && fy >= 0.0f && fx < fast_x && fy < fast_y;
          any_source = any_source || source;
          identity_ = identity_ && source && static_cast<int>(fx) == (u0 + k) * kWeightOne &&
                      static_cast<int>(fy) == v * kWeightOne;
          if (ex[k] >= 0.0 && ey[k] >= 0.0 && ex[k] <= cal.width - 1 && ey[k] <= cal.height - 1) {
            max_table_error_px_ = std::max(max_table_error_px_, std::hypot(tx - ex[k], ty - ey[k]));
          }
        }
        table.kind[index] = all_fast     ? SegmentKind::kInside
                            : any_source ? SegmentKind::kMixed
                                         : SegmentKind::kOutside;
        table.row_inside[v] = table.row_inside[v] && all_fast;
        if (all_fast && len == kSegment && WindowSegment(&seg, cal.width, cal.height)) {
          table.kind[index] = SegmentKind::kWindow;
          ++windows;
        }
      }
    }
  }
  window_fraction_ =
      static_cast<double>(windows) / (2.0 * static_cast<double>(h) * segments_per_row_);
  configured_ = true;
  return Status::kOk;
}

bool StereoRectifier::TablePixel(int camera, int u, int v, float* raw_u, float* raw_v) const {
  if (!configured_ || camera < 0 || camera > 1 || u < 0 || v < 0 || u >= width_ || v >= height_) {
    return false;
  }
  const std::size_t index = static_cast<std::size_t>(v) * segments_per_row_ + u / kSegment;
  if (table_[camera].kind[index] == SegmentKind::kOutside) return false;
  const Segment& seg = table_[camera].segment[index];
  const auto k = static_cast<float>(u % kSegment);
  const float fx = EvalSegment(seg.x, k);
  const float fy = EvalSegment(seg.y, k);
  *raw_u = (fx - 0.5f) / kWeightOneF;
  *raw_v = (fy - 0.5f) / kWeightOneF;
  return fx >= 0.0f && fy >= 0.0f &&
         fx < static_cast<float>((calib_[camera].width - 1) * kWeightOne) + 1.0f &&
         fy < static_cast<float>((calib_[camera].height - 1) * kWeightOne) + 1.0f;
}

void StereoRectifier::RemapOne(const GrayView& raw, const Table& table,
                               const MutableGrayView& out) const {
  const RemapJob job{table.segment, table.kind, segments_per_row_, width_, height_, &raw, &out};
  switch (kernel_) {
#if defined(__x86_64__)
    case RemapKernel::kAvx2: RemapAvx2(job); break;
    case RemapKernel::kSsse3: RemapSsse3(job); break;
#elif defined(__aarch64__)
    case RemapKernel::kNeon: RemapNeon(job); break;
#endif
    default: RemapPortable(job); break;
  }
  const int w = width_;
  const std::int32_t stride = raw.stride;
  const int max_x = raw.width - 1;
  const int max_y = raw.height - 1;
  for (int v = 0; v < height_; ++v) {
    if (table.row_inside[v]) continue;
    const std::size_t row = static_cast<std::size_t>(v) * segments_per_row_;
    const Segment* segs = table.segment + row;
    const SegmentKind* kinds = table.kind + row;
    std::uint8_t* o = out.Row(v);
    // Segments not entirely inside: per-pixel checks with the same arithmetic in scalar.
    for (int s = 0; s < segments_per_row_; ++s) {
      if (kinds[s] == SegmentKind::kInside || kinds[s] == SegmentKind::kWindow) continue;
      const int u0 = s * kSegment;
      const int len = std::min(kSegment, w - u0);
      if (kinds[s] == SegmentKind::kOutside) {
        std::memset(o + u0, 0, static_cast<std::size_t>(len));
        continue;
      }
      for (int k = 0; k < len; ++k) {
        const float fx = EvalSegment(segs[s].x, static_cast<float>(k));
        const float fy = EvalSegment(segs[s].y, static_cast<float>(k));
        if (!(fx >= 0.0f && fy >= 0.0f && fx < static_cast<float>(max_x * kWeightOne) + 1.0f &&
              fy < static_cast<float>(max_y * kWeightOne) + 1.0f)) {
          o[u0 + k] = 0;
          continue;
        }
        const int ix = static_cast<int>(fx);
        const int iy = static_cast<int>(fy);
        // The last row/column is reached with the full weight on the second tap.
        const int cx = std::min(ix >> kWeightBits, max_x - 1);
        const int cy = std::min(iy >> kWeightBits, max_y - 1);
        const int ax = ix - cx * kWeightOne;
        const int ay = iy - cy * kWeightOne;
        const std::uint8_t* s0 = raw.Row(cy) + cx;
        const std::uint8_t* s1 = s0 + stride;
        const int upper = s0[0] * (kWeightOne - ax) + s0[1] * ax;
        const int lower = s1[0] * (kWeightOne - ax) + s1[1] * ax;
        o[u0 + k] = static_cast<std::uint8_t>(
            (upper * (kWeightOne - ay) + lower * ay + kWeightOne * kWeightOne / 2) >>
            (2 * kWeightBits));
      }
    }
  }
}

Status StereoRectifier::Rectify(const GrayView& left_raw, const GrayView& right_raw,
                                const MutableGrayView& left_out,
                                const MutableGrayView& right_out) const {
  if (!configured_) return Status::kNotConfigured;
  if (!left_raw.Valid() || !right_raw.Valid() || left_raw.width != calib_[0].width ||
      left_raw.height != calib_[0].height || right_raw.width != calib_[1].width ||
      right_raw.height != calib_[1].height || left_out.width != width_ ||
      left_out.height != height_ || right_out.width != width_ || right_out.height != height_ ||
      left_out.data == nullptr || right_out.data == nullptr) {
    return Status::kInvalidArgument;
  }
  if (identity_) {  // already rectified: the table would return every source pixel unchanged
    for (int v = 0; v < height_; ++v) {
      std::memcpy(left_out.Row(v), left_raw.Row(v), static_cast<std::size_t>(width_));
      std::memcpy(right_out.Row(v), right_raw.Row(v), static_cast<std::size_t>(width_));
    }
    return Status::kOk;
  }
  RemapOne(left_raw, table_[0], left_out);
  RemapOne(right_raw, table_[1], right_out);
  return Status::kOk;
}

}  // namespace swf::frontend
