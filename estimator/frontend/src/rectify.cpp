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
// kWindow coordinates (WindowHalf): 1/1024 px from the window origin, so that the integer part
// (0 .. 14) and the 1/128-px weight come out of one 16-bit lane by shifts.
constexpr int kFineBits = 10;
constexpr int kFineOne = 1 << kFineBits;
constexpr int kFineToWeight = kFineBits - kWeightBits;
constexpr int kHalf = kSegment / 2;  // pixels per WindowHalf

using rectify_detail::Quadratic;
using rectify_detail::WindowHalf;

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

// WindowHalf coordinate of pixel j (1/1024 px from the window origin, rounding offset included).
// The SIMD kernels evaluate it in 16-bit lanes: (j 2^12 c1 + 2^14) >> 15 is pmulhrsw / sqrdmulh
// of c1 by j 2^12, likewise c2 by j^2 2^9; Configure keeps every sum inside 0 .. 2^15 so that
// wrapping 16-bit adds give the same value.
constexpr int kLinearScale = 1 << 12;    // j 2^12 <= 28672
constexpr int kQuadraticScale = 1 << 9;  // j^2 2^9 <= 25088
inline int EvalHalf(const std::int16_t* c, int j) {
  return c[0] + ((j * c[1] + 4) >> 3) + ((j * j * c[2] + 32) >> 6);
}

// Source coordinates (1/128 px, rounded) of pixels q .. q + 7 of a segment.
struct Coords8 {
  V4i fx_lo;
  V4i fx_hi;
  V4i fy_lo;
  V4i fy_hi;
};

[[gnu::always_inline]] inline Coords8 SegmentCoords(const Quadratic& seg, int q) {
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
// the weights in 1/128. 16-bit lanes, exact integers: upper = p0 (128 - ax) + p1 ax (lower
// likewise), mid = upper + floor((d ay + 64) / 128) with d = lower - upper, out = (mid + 64) >> 7.
// These are two rounding multiply-highs in the SIMD kernels (pmulhrsw / sqrdmulh by ay 2^8, then
// by 2^8); here d ay is split into its high (signed) and low (unsigned) byte to stay in 16 bits.
[[gnu::always_inline]] inline V8b Blend8(V8u t, V8u b, V8s ax, V8s ay) {
  const V8s bx = kWeightOne - ax;
  const V8s upper = reinterpret_cast<V8s>(t & 0xFF) * bx + reinterpret_cast<V8s>(t >> 8) * ax;
  const V8s lower = reinterpret_cast<V8s>(b & 0xFF) * bx + reinterpret_cast<V8s>(b >> 8) * ax;
  const V8s d = lower - upper;
  const V8s mid =
      upper + (((d >> 8) * ay) << 1) + ((((d & 0xFF) * ay) + (kWeightOne / 2)) >> kWeightBits);
  const V8s result = (mid + (kWeightOne / 2)) >> kWeightBits;
  return __builtin_convertvector(result, V8b);
}

// Scalar Blend8 (the per-pixel border pass).
inline std::uint8_t Blend1(const std::uint8_t* s0, const std::uint8_t* s1, int ax, int ay) {
  const int upper = s0[0] * (kWeightOne - ax) + s0[1] * ax;
  const int lower = s1[0] * (kWeightOne - ax) + s1[1] * ax;
  const int mid = upper + (((lower - upper) * ay + kWeightOne / 2) >> kWeightBits);
  return static_cast<std::uint8_t>((mid + kWeightOne / 2) >> kWeightBits);
}

// One segment whose taps are all inside, gathered with a 16-bit load per tap pair (kInside in the
// SIMD kernels). Writes min(kSegment, count) bytes: the last segment of a row may pass its end.
[[gnu::always_inline]] inline void GatherSegment(const Quadratic& seg, const std::uint8_t* src,
                                                 std::int32_t stride, int count,
                                                 std::uint8_t* dst) {
  alignas(16) std::uint8_t bytes[kSegment];
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
    const V8b blended = Blend8(t, b, ax, ay);
    std::memcpy(bytes + q, &blended, sizeof(blended));
  }
  std::memcpy(dst, bytes, static_cast<std::size_t>(std::min(kSegment, count)));
}

// EvalHalf of pixels 0 .. 7 in 16-bit lanes without a multiply-high (portable kernel), for the
// coefficients at lanes kFirst .. kFirst + 2 of a WindowHalf loaded as a vector: with
// c1 = 8 h + l (l = c1 & 7), (j c1 + 4) >> 3 = j h + ((j l + 4) >> 3), and c2 likewise by 64, so
// that every product fits 16 bits; unsigned lanes wrap as the SIMD kernels' adds do.
template <int kFirst>
[[gnu::always_inline]] inline V8u EvalHalf8(V8s coef) {
  const V8u j = {0, 1, 2, 3, 4, 5, 6, 7};
  const V8u j2 = j * j;
  const auto c0 = reinterpret_cast<V8u>(__builtin_shufflevector(
      coef, coef, kFirst, kFirst, kFirst, kFirst, kFirst, kFirst, kFirst, kFirst));
  const V8s c1 = __builtin_shufflevector(coef, coef, kFirst + 1, kFirst + 1, kFirst + 1, kFirst + 1,
                                         kFirst + 1, kFirst + 1, kFirst + 1, kFirst + 1);
  const V8s c2 = __builtin_shufflevector(coef, coef, kFirst + 2, kFirst + 2, kFirst + 2, kFirst + 2,
                                         kFirst + 2, kFirst + 2, kFirst + 2, kFirst + 2);
  return c0 + j * reinterpret_cast<V8u>(c1 >> 3) + ((j * reinterpret_cast<V8u>(c1 & 7) + 4) >> 3) +
         j2 * reinterpret_cast<V8u>(c2 >> 6) + ((j2 * reinterpret_cast<V8u>(c2 & 63) + 32) >> 6);
}

// Lanes 0 .. 3 / 4 .. 7 of unsigned 16-bit lanes as 32-bit lanes (interleaved with zeros).
inline V4i WidenLo(V8u v) {
  const V8u zero = {};
  return reinterpret_cast<V4i>(__builtin_shufflevector(v, zero, 0, 8, 1, 9, 2, 10, 3, 11));
}
inline V4i WidenHi(V8u v) {
  const V8u zero = {};
  return reinterpret_cast<V4i>(__builtin_shufflevector(v, zero, 4, 12, 5, 13, 6, 14, 7, 15));
}

// Everything a kernel needs for one image.
struct RemapJob {
  const Segment* segment;
  const SegmentKind* kind;
  const bool* row_window;  // every segment of the row is kWindow
  int segments_per_row;
  int width;
  int height;
  const GrayView* raw;
  const MutableGrayView* out;
};

// The segment walk of the kernels that take a kWindow segment as two WindowHalfs (SSSE3, NEON):
// window_half(half, dst) writes the half's 8 output bytes; kInside segments are gathered; the
// rest is left to the per-pixel pass. Always inlined, so that window_half inlines into the
// kernel's own target.
template <class WindowHalfKernel>
[[gnu::always_inline]] inline void RemapByHalves(const RemapJob& job,
                                                 WindowHalfKernel window_half) {
  const std::uint8_t* src = job.raw->data;
  const std::int32_t stride = job.raw->stride;
  for (int v = 0; v < job.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
    std::uint8_t* o = job.out->Row(v);
    for (int s = 0; s < job.segments_per_row; ++s) {
      const Segment& seg = job.segment[row + s];
      const int u0 = s * kSegment;
      if (job.kind[row + s] == SegmentKind::kWindow) {
        window_half(seg.half[0], o + u0);
        window_half(seg.half[1], o + u0 + kHalf);
      } else if (job.kind[row + s] == SegmentKind::kInside) {
        GatherSegment(seg.quad, src, stride, job.width - u0, o + u0);
      }
    }
  }
}

// Constant vectors of the SIMD window kernels: 16 lanes of 16 bits (x86 SSSE3 uses the low 8; every
// constant repeats per 128 bits), byte values named as such.
struct alignas(32) WindowConstants {
  std::int16_t word[6][16];    // byte shuffles that broadcast word w of each 128-bit lane
  std::int16_t linear[16];     // j 2^12
  std::int16_t quadratic[16];  // j^2 2^9
  std::int16_t high_byte[16];  // byte shuffle: the high byte of every lane into both its bytes
  std::int16_t next[16];       // 0x0100: the right tap is the next byte
  std::int16_t below[16];      // 2^10 - 1: Y above it is the window's second row
  std::int16_t bias[16];       // bytes 0x80 (also the shuffle bits that give 0)
  std::int16_t frac[16];       // 127
  std::int16_t spread[16];     // 255: ax 255 + 128 = (128 - ax) | ax << 8
  std::int16_t one[16];        // 128
  std::int16_t ay_bits[16];    // 0x7F00: ay << 8 straight from Y << 5
  std::int16_t unit[16];       // 2^8: a rounding multiply-high by it is (x + 64) >> 7
};

constexpr WindowConstants MakeWindowConstants() {
  WindowConstants k{};
  for (int i = 0; i < 16; ++i) {
    const int j = i % kHalf;
    for (int w = 0; w < 6; ++w) k.word[w][i] = static_cast<std::int16_t>((2 * w + 1) << 8 | 2 * w);
    k.linear[i] = static_cast<std::int16_t>(j * kLinearScale);
    k.quadratic[i] = static_cast<std::int16_t>(j * j * kQuadraticScale);
    k.high_byte[i] = static_cast<std::int16_t>(((2 * j + 1) << 8) | (2 * j + 1));
    k.next[i] = 0x0100;
    k.below[i] = kFineOne - 1;
    k.bias[i] = static_cast<std::int16_t>(-0x7F80);  // 0x8080
    k.frac[i] = kWeightOne - 1;
    k.spread[i] = 0xFF;
    k.one[i] = kWeightOne;
    k.ay_bits[i] = (kWeightOne - 1) << 8;
    k.unit[i] = 1 << 8;
  }
  return k;
}

#if defined(__x86_64__)
using M128 = __m128i;
using M256 = __m256i;

template <class M>
inline const M& Vec(const std::int16_t (&lanes)[16]) {
  return *reinterpret_cast<const M*>(lanes);
}

// One WindowHalf (8 pixels) with SSSE3: the 16-bit coordinates by pmulhrsw (EvalHalf), the taps by
// pshufb from the window's three rows (index bytes with the top bit set give 0, which picks the
// row), the horizontal blend by one pmaddubsw on taps offset by -128 and the vertical one by
// pmulhrsw (Blend8; exact, see RemapAvx2). Returns the 8 output bytes in the low half.
__attribute__((target("ssse3"))) inline M128 WindowHalfSsse3(const WindowHalf& half,
                                                             const std::uint8_t* src,
                                                             std::int32_t stride,
                                                             const WindowConstants& k) {
  const M128 coef = _mm_load_si128(reinterpret_cast<const M128*>(&half));
  const M128 x = _mm_add_epi16(
      _mm_add_epi16(
          _mm_shuffle_epi8(coef, Vec<M128>(k.word[0])),
          _mm_mulhrs_epi16(_mm_shuffle_epi8(coef, Vec<M128>(k.word[1])), Vec<M128>(k.linear))),
      _mm_mulhrs_epi16(_mm_shuffle_epi8(coef, Vec<M128>(k.word[2])), Vec<M128>(k.quadratic)));
  const M128 y = _mm_add_epi16(
      _mm_add_epi16(
          _mm_shuffle_epi8(coef, Vec<M128>(k.word[3])),
          _mm_mulhrs_epi16(_mm_shuffle_epi8(coef, Vec<M128>(k.word[4])), Vec<M128>(k.linear))),
      _mm_mulhrs_epi16(_mm_shuffle_epi8(coef, Vec<M128>(k.word[5])), Vec<M128>(k.quadratic)));
  // Tap byte indices (dx, dx + 1) per lane: dx is the high byte of X >> 2.
  const M128 idx =
      _mm_add_epi16(_mm_shuffle_epi8(_mm_srli_epi16(x, kFineBits - 8), Vec<M128>(k.high_byte)),
                    Vec<M128>(k.next));
  const M128 bias = Vec<M128>(k.bias);
  const M128 ia = _mm_or_si128(idx, _mm_and_si128(_mm_cmpgt_epi16(y, Vec<M128>(k.below)), bias));
  const M128 ib = _mm_xor_si128(ia, bias);
  const std::uint8_t* p = src + static_cast<std::ptrdiff_t>(half.row) * stride + half.column;
  const M128 r0 = _mm_loadu_si128(reinterpret_cast<const M128*>(p));
  const M128 r1 = _mm_loadu_si128(reinterpret_cast<const M128*>(p + stride));
  const M128 r2 = _mm_loadu_si128(reinterpret_cast<const M128*>(p + 2 * stride));
  const M128 t =
      _mm_xor_si128(_mm_or_si128(_mm_shuffle_epi8(r0, ia), _mm_shuffle_epi8(r1, ib)), bias);
  const M128 b =
      _mm_xor_si128(_mm_or_si128(_mm_shuffle_epi8(r1, ia), _mm_shuffle_epi8(r2, ib)), bias);
  const M128 ax = _mm_and_si128(_mm_srli_epi16(x, kFineToWeight), Vec<M128>(k.frac));
  const M128 wx = _mm_add_epi16(_mm_mullo_epi16(ax, Vec<M128>(k.spread)), Vec<M128>(k.one));
  const M128 ay8 = _mm_and_si128(_mm_slli_epi16(y, 8 - kFineToWeight), Vec<M128>(k.ay_bits));
  const M128 upper = _mm_maddubs_epi16(wx, t);
  const M128 lower = _mm_maddubs_epi16(wx, b);
  const M128 mid = _mm_add_epi16(upper, _mm_mulhrs_epi16(_mm_sub_epi16(lower, upper), ay8));
  const M128 result = _mm_mulhrs_epi16(mid, Vec<M128>(k.unit));  // -128 .. 127
  return _mm_xor_si128(_mm_packs_epi16(result, result), bias);
}

// SSSE3 kernel: kWindow segments by shuffles, kInside by 16-bit gathers; the rest is left to the
// per-pixel pass.
__attribute__((target("ssse3"))) void RemapSsse3(RemapJob job) {  // a copy: o aliases anything
  const std::uint8_t* src = job.raw->data;
  const std::int32_t stride = job.raw->stride;
  WindowConstants k = MakeWindowConstants();
  asm("" : : "r"(&k) : "memory");  // constants stay memory operands (RemapAvx2)
  // The lambda names the kernel's target itself: a lambda does not inherit its function's.
  RemapByHalves(
      job, [&](const WindowHalf& half, std::uint8_t* dst) __attribute__((target("ssse3"))) {
        _mm_storel_epi64(reinterpret_cast<M128*>(dst), WindowHalfSsse3(half, src, stride, k));
      });
}

// vpblendvb: a where the mask byte's top bit is clear, b where it is set. In asm because GCC
// rewrites the intrinsic as a select on (mask < 0) and, for a mask from a 16-bit compare,
// recomputes that with a byte compare.
__attribute__((target("avx2"))) inline M256 BlendBytes(M256 a, M256 b, M256 mask) {
  M256 out;
  asm("vpblendvb %3, %2, %1, %0" : "=x"(out) : "x"(a), "x"(b), "x"(mask));
  return out;
}

// One kWindow segment with AVX2, 16 lanes; 128-bit half h of every register is the segment's
// WindowHalf h, as the in-lane byte shuffles need. Returns the output in 16-bit lanes, 128 lower.
// kMadd: the windows' offsets row * stride + column by one pmaddwd of the loaded entry (stride
// < 2^15, `madd` holds 1 and the stride at words 6 and 7 of each 128 bits) instead of scalar code.
template <bool kMadd>
__attribute__((target("avx2"), always_inline)) inline M256 WindowSegmentAvx2(
    const Segment& seg, const std::uint8_t* src, const std::uint8_t* src1, const std::uint8_t* src2,
    std::int32_t stride, const M256& madd, const WindowConstants& k) {
  const M256 coef = _mm256_load_si256(reinterpret_cast<const M256*>(&seg));
  // EvalHalf in 16-bit lanes.
  const M256 x = _mm256_add_epi16(
      _mm256_add_epi16(_mm256_shuffle_epi8(coef, Vec<M256>(k.word[0])),
                       _mm256_mulhrs_epi16(_mm256_shuffle_epi8(coef, Vec<M256>(k.word[1])),
                                           Vec<M256>(k.linear))),
      _mm256_mulhrs_epi16(_mm256_shuffle_epi8(coef, Vec<M256>(k.word[2])), Vec<M256>(k.quadratic)));
  const M256 y = _mm256_add_epi16(
      _mm256_add_epi16(_mm256_shuffle_epi8(coef, Vec<M256>(k.word[3])),
                       _mm256_mulhrs_epi16(_mm256_shuffle_epi8(coef, Vec<M256>(k.word[4])),
                                           Vec<M256>(k.linear))),
      _mm256_mulhrs_epi16(_mm256_shuffle_epi8(coef, Vec<M256>(k.word[5])), Vec<M256>(k.quadratic)));
  // Tap byte indices (dx, dx + 1) per lane (dx: the high byte of X >> 2); where Y is in the
  // window's second row the taps come from rows 1 and 2 (a byte blend) instead of 0 and 1.
  const M256 idx = _mm256_add_epi16(
      _mm256_shuffle_epi8(_mm256_srli_epi16(x, kFineBits - 8), Vec<M256>(k.high_byte)),
      Vec<M256>(k.next));
  const M256 second = _mm256_cmpgt_epi16(y, Vec<M256>(k.below));
  // Window offsets from the image; the rows below are read through `src + stride` and
  // `src + 2 stride` as bases (no per-segment address arithmetic).
  std::size_t o0;
  std::size_t o1;
  if constexpr (kMadd) {
    const M256 offsets = _mm256_madd_epi16(coef, madd);
    o0 = static_cast<std::uint32_t>(_mm256_extract_epi32(offsets, 3));
    o1 = static_cast<std::uint32_t>(_mm256_extract_epi32(offsets, 7));
  } else {
    o0 = static_cast<std::size_t>(seg.half[0].row) * stride + seg.half[0].column;
    o1 = static_cast<std::size_t>(seg.half[1].row) * stride + seg.half[1].column;
  }
  const M256 r0 = _mm256_loadu2_m128i(reinterpret_cast<const M128*>(src + o1),
                                      reinterpret_cast<const M128*>(src + o0));
  const M256 r1 = _mm256_loadu2_m128i(reinterpret_cast<const M128*>(src1 + o1),
                                      reinterpret_cast<const M128*>(src1 + o0));
  const M256 r2 = _mm256_loadu2_m128i(reinterpret_cast<const M128*>(src2 + o1),
                                      reinterpret_cast<const M128*>(src2 + o0));
  const M256 s1 = _mm256_shuffle_epi8(r1, idx);
  // Tap pairs with 128 subtracted (x ^ 0x80: signed bytes), so that the horizontal blend is one
  // unsigned-by-signed byte multiply-add: upper' = p0' (128 - ax) + p1' ax = upper - 2^14 in
  // [-2^14, 2^14 - 128]. The vertical step is Blend8's: pmulhrsw(d, ay 2^8) is
  // floor((d ay + 64) / 128) (d = lower - upper is unchanged), and pmulhrsw(mid', 2^8) =
  // (mid' + 64) >> 7 is the result 128 lower, as 2^14 / 2^7 = 128.
  const M256& bias = Vec<M256>(k.bias);
  const M256 t = _mm256_xor_si256(BlendBytes(_mm256_shuffle_epi8(r0, idx), s1, second), bias);
  const M256 b = _mm256_xor_si256(BlendBytes(s1, _mm256_shuffle_epi8(r2, idx), second), bias);
  const M256 ax = _mm256_and_si256(_mm256_srli_epi16(x, kFineToWeight), Vec<M256>(k.frac));
  // Weight bytes (128 - ax, ax) per pixel: ax 255 + 128.
  const M256 wx = _mm256_add_epi16(_mm256_mullo_epi16(ax, Vec<M256>(k.spread)), Vec<M256>(k.one));
  const M256 ay8 = _mm256_and_si256(_mm256_slli_epi16(y, 8 - kFineToWeight), Vec<M256>(k.ay_bits));
  const M256 upper = _mm256_maddubs_epi16(wx, t);
  const M256 lower = _mm256_maddubs_epi16(wx, b);
  const M256 mid =
      _mm256_add_epi16(upper, _mm256_mulhrs_epi16(_mm256_sub_epi16(lower, upper), ay8));
  return _mm256_mulhrs_epi16(mid, Vec<M256>(k.unit));  // -128 .. 127
}

template <bool kMadd>
__attribute__((target("avx2"))) void RemapAvx2Rows(const RemapJob& job, const M256& madd,
                                                   const WindowConstants& k) {
  const std::uint8_t* src = job.raw->data;
  const std::int32_t stride = job.raw->stride;
  const std::uint8_t* src1 = src + stride;
  const std::uint8_t* src2 = src1 + stride;
  const M256& bias = Vec<M256>(k.bias);
  for (int v = 0; v < job.height; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
    const Segment* seg = job.segment + row;
    std::uint8_t* o = job.out->Row(v);
    int s = 0;
    if (job.row_window[v]) {
      // Every segment of the row is kWindow (and full): two per pass, one pack and 32-byte store.
      for (; s + 2 <= job.segments_per_row; s += 2) {
        const M256 a = WindowSegmentAvx2<kMadd>(seg[s], src, src1, src2, stride, madd, k);
        const M256 c = WindowSegmentAvx2<kMadd>(seg[s + 1], src, src1, src2, stride, madd, k);
        const M256 bytes =
            _mm256_xor_si256(_mm256_permute4x64_epi64(_mm256_packs_epi16(a, c), 0xD8), bias);
        _mm256_storeu_si256(reinterpret_cast<M256*>(o + s * kSegment), bytes);
      }
    }
    for (; s < job.segments_per_row; ++s) {
      const int u0 = s * kSegment;
      if (job.kind[row + s] == SegmentKind::kWindow) {
        const M256 a = WindowSegmentAvx2<kMadd>(seg[s], src, src1, src2, stride, madd, k);
        const M256 bytes =
            _mm256_xor_si256(_mm256_permute4x64_epi64(_mm256_packs_epi16(a, a), 0x08), bias);
        _mm_storeu_si128(reinterpret_cast<M128*>(o + u0), _mm256_castsi256_si128(bytes));
      } else if (job.kind[row + s] == SegmentKind::kInside) {
        GatherSegment(seg[s].quad, src, stride, job.width - u0, o + u0);
      }
    }
  }
}

// AVX2 kernel: kWindow segments by WindowSegmentAvx2, kInside by 16-bit gathers; the rest is left
// to the per-pixel pass.
__attribute__((target("avx2"))) void RemapAvx2(RemapJob job) {  // a copy: o aliases anything
  // Constants kept in memory: GCC otherwise rebuilds broadcast constants inside the loop (mov,
  // vmovd, vpbroadcast) for lack of registers; the empty asm hides their values, so they stay
  // memory operands.
  WindowConstants k = MakeWindowConstants();
  asm("" : : "r"(&k) : "memory");
  const std::int32_t stride = job.raw->stride;
  if (stride < (1 << 15)) {
    const M256 madd = _mm256_setr_epi16(0, 0, 0, 0, 0, 0, 1, static_cast<std::int16_t>(stride), 0,
                                        0, 0, 0, 0, 0, 1, static_cast<std::int16_t>(stride));
    RemapAvx2Rows<true>(job, madd, k);
  } else {
    RemapAvx2Rows<false>(job, _mm256_setzero_si256(), k);
  }
}
#endif  // __x86_64__

// Shuffle-index arithmetic of a window half (NEON): dx = column - window column (0 .. 14) and dy =
// row - window row (0 or 1) per 16-bit lane. Returns the byte indices into row r (idx_a) and row
// r + 1 (idx_b): lane bytes dx, dx + 1, with the top bit set (lookup gives 0) where the other row
// holds the taps. The top taps are lookup(row r, idx_a) | lookup(row r + 1, idx_b), the bottom
// taps lookup(row r + 1, idx_a) | lookup(row r + 2, idx_b).
template <class V>
[[gnu::always_inline]] inline void WindowIndices(V dx, V dy, V* idx_a, V* idx_b) {
  const V idx = dx * 257 + 256;
  const V m = dy * 0x8080;
  *idx_a = idx | m;
  *idx_b = idx | (m ^ 0x8080);
}

#if defined(__aarch64__)
// One WindowHalf (8 pixels) with NEON: sqrdmulh (= pmulhrsw) coordinates and TBL taps (indices
// >= 16 give 0), blended by Blend8.
[[gnu::always_inline]] inline V8b WindowHalfNeon(const WindowHalf& half, const std::uint8_t* src,
                                                 std::int32_t stride, int16x8_t linear,
                                                 int16x8_t quadratic) {
  int16x8_t coef;
  std::memcpy(&coef, &half, sizeof(coef));
  const int16x8_t x =
      vaddq_s16(vaddq_s16(vdupq_laneq_s16(coef, 0), vqrdmulhq_laneq_s16(linear, coef, 1)),
                vqrdmulhq_laneq_s16(quadratic, coef, 2));
  const int16x8_t y =
      vaddq_s16(vaddq_s16(vdupq_laneq_s16(coef, 3), vqrdmulhq_laneq_s16(linear, coef, 4)),
                vqrdmulhq_laneq_s16(quadratic, coef, 5));
  const auto xs = reinterpret_cast<V8s>(x);
  const auto ys = reinterpret_cast<V8s>(y);
  V8u idx_a;
  V8u idx_b;
  WindowIndices(reinterpret_cast<V8u>(xs >> kFineBits), reinterpret_cast<V8u>(ys >> kFineBits),
                &idx_a, &idx_b);
  const std::uint8_t* p = src + static_cast<std::ptrdiff_t>(half.row) * stride + half.column;
  const uint8x16_t r0 = vld1q_u8(p);
  const uint8x16_t r1 = vld1q_u8(p + stride);
  const uint8x16_t r2 = vld1q_u8(p + 2 * stride);
  const auto ia = vreinterpretq_u8_u16(reinterpret_cast<uint16x8_t>(idx_a));
  const auto ib = vreinterpretq_u8_u16(reinterpret_cast<uint16x8_t>(idx_b));
  const auto t = reinterpret_cast<V8u>(vorrq_u8(vqtbl1q_u8(r0, ia), vqtbl1q_u8(r1, ib)));
  const auto b = reinterpret_cast<V8u>(vorrq_u8(vqtbl1q_u8(r1, ia), vqtbl1q_u8(r2, ib)));
  const V8s ax = (xs >> kFineToWeight) & (kWeightOne - 1);
  const V8s ay = (ys >> kFineToWeight) & (kWeightOne - 1);
  return Blend8(t, b, ax, ay);
}

// NEON kernel: kWindow segments by WindowHalfNeon, kInside by 16-bit gathers; the rest is left to
// the per-pixel pass.
void RemapNeon(RemapJob job) {  // a copy: o aliases anything
  const std::uint8_t* src = job.raw->data;
  const std::int32_t stride = job.raw->stride;
  constexpr WindowConstants kConstants = MakeWindowConstants();
  const int16x8_t linear = vld1q_s16(kConstants.linear);
  const int16x8_t quadratic = vld1q_s16(kConstants.quadratic);
  RemapByHalves(job, [&](const WindowHalf& half, std::uint8_t* dst) {
    const V8b bytes = WindowHalfNeon(half, src, stride, linear, quadratic);
    std::memcpy(dst, &bytes, sizeof(bytes));
  });
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
      if (kind == SegmentKind::kWindow) {
        for (int h = 0; h < 2; ++h) {
          const WindowHalf& half = job.segment[row + s].half[h];
          V8s coef;
          std::memcpy(&coef, &half, sizeof(coef));
          const V8u x = EvalHalf8<0>(coef);
          const V8u y = EvalHalf8<3>(coef);
          // Top-left tap: the window origin + dx + (dy ? stride : 0).
          const V8u dx = x >> kFineBits;
          const std::int32_t origin = half.row * stride + half.column;
          const V8u dy = y >> kFineBits;
          const V4i off_lo = origin + WidenLo(dx) + (-WidenLo(dy) & stride4);
          const V4i off_hi = origin + WidenHi(dx) + (-WidenHi(dy) & stride4);
          const auto ax = reinterpret_cast<V8s>((x >> kFineToWeight) & (kWeightOne - 1));
          const auto ay = reinterpret_cast<V8s>((y >> kFineToWeight) & (kWeightOne - 1));
          const int q = u0 + h * kHalf;
          std::memcpy(offset + q, &off_lo, sizeof(off_lo));
          std::memcpy(offset + q + 4, &off_hi, sizeof(off_hi));
          std::memcpy(wx + q, &ax, sizeof(ax));
          std::memcpy(wy + q, &ay, sizeof(ay));
        }
        continue;
      }
      if (kind != SegmentKind::kInside) {
        for (int k = 0; k < kSegment; ++k) {
          offset[u0 + k] = 0;  // a harmless tap; the pixels are redone by the per-pixel pass
          wx[u0 + k] = 0;
          wy[u0 + k] = 0;
        }
        continue;
      }
      for (int q = 0; q < kSegment; q += 8) {
        const Coords8 c = SegmentCoords(job.segment[row + s].quad, q);
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

// One coordinate of a WindowHalf: the quadratic through the exact raw coordinate f0, fm, f7 at
// j = 0, 3.5, 7, in 1/1024 px from `origin` with the 1/256-px rounding offset folded in (so that
// X >> 3 rounds to 1/128 px). False when a coefficient does not fit its 16-bit lane.
bool FitHalf(double f0, double fm, double f7, int origin, std::int16_t* c) {
  const double c2 = ((f7 - f0) / 7.0 - (fm - f0) / 3.5) / 3.5;
  const double c1 = (fm - f0) / 3.5 - c2 * 3.5;
  const double coef[3] = {(f0 - origin) * kFineOne + (1 << (kFineToWeight - 1)),
                          c1 * kFineOne * (1 << 3), c2 * kFineOne * (1 << 6)};
  for (int i = 0; i < 3; ++i) {
    const double r = std::round(coef[i]);
    if (!(std::fabs(r) <= 32767.0)) return false;
    c[i] = static_cast<std::int16_t>(r);
  }
  return true;
}

// Makes `half` the WindowHalf of pixels whose exact raw coordinates are (ex[j], ey[j]), j = 0 .. 7
// (mx, my at j = 3.5): the window's column / row is the smallest tap column / row (or one less),
// and every pixel's X must stay in 0 .. 15 px (taps dx, dx + 1 <= 15), Y in 0 .. 2 px, the window
// inside the raw image. False when no origin works.
bool FitWindowHalf(const double* ex, const double* ey, double mx, double my, int raw_width,
                   int raw_height, WindowHalf* half) {
  const int column = static_cast<int>(std::floor(std::min(ex[0], ex[kHalf - 1])));
  const int row = static_cast<int>(std::floor(std::min(ey[0], ey[kHalf - 1])));
  for (int dc = 0; dc < 2; ++dc) {
    for (int dr = 0; dr < 2; ++dr) {
      const int c = column - dc;
      const int r = row - dr;
      if (c < 0 || r < 0 || c + 15 > raw_width - 1 || r + 2 > raw_height - 1) continue;
      if (!FitHalf(ex[0], mx, ex[kHalf - 1], c, half->x) ||
          !FitHalf(ey[0], my, ey[kHalf - 1], r, half->y)) {
        return false;
      }
      bool ok = true;
      for (int j = 0; j < kHalf; ++j) {
        const int x = EvalHalf(half->x, j);
        const int y = EvalHalf(half->y, j);
        ok = ok && x >= 0 && x < 15 * kFineOne && y >= 0 && y < 2 * kFineOne;
      }
      if (ok) {
        half->column = static_cast<std::int16_t>(c);  // raw sides < 2^15
        half->row = static_cast<std::int16_t>(r);
        return true;
      }
    }
  }
  return false;
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
      table.row_window[v] = true;
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
          table.row_window[v] = false;
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
        Quadratic quad;
        fit(ex[0], mx, ex[len - 1], quad.x);
        fit(ey[0], my, ey[len - 1], quad.y);
        bool all_fast = true;
        bool any_source = false;
        double error = 0.0;  // of what Rectify samples, over the pixels with an exact source
        auto inside = [&](int k) {
          return ex[k] >= 0.0 && ey[k] >= 0.0 && ex[k] <= cal.width - 1 && ey[k] <= cal.height - 1;
        };
        for (int k = 0; k < len; ++k) {
          const float fx = EvalSegment(quad.x, static_cast<float>(k));
          const float fy = EvalSegment(quad.y, static_cast<float>(k));
          const double tx = (fx - 0.5) / kWeightOne;
          const double ty = (fy - 0.5) / kWeightOne;
          const bool source = fx >= 0.0f && fy >= 0.0f && fx < fast_x + 1.0f && fy < fast_y + 1.0f;
          all_fast = all_fast && fx >= 0.0f && fy >= 0.0f && fx < fast_x && fy < fast_y;
          any_source = any_source || source;
          identity_ = identity_ && source && static_cast<int>(fx) == (u0 + k) * kWeightOne &&
                      static_cast<int>(fy) == v * kWeightOne;
          if (inside(k)) error = std::max(error, std::hypot(tx - ex[k], ty - ey[k]));
        }
        seg.quad = quad;
        table.kind[index] = all_fast     ? SegmentKind::kInside
                            : any_source ? SegmentKind::kMixed
                                         : SegmentKind::kOutside;
        table.row_inside[v] = table.row_inside[v] && all_fast;
        // Window halves: their own quadratics through the exact map (j = 0, 3.5, 7).
        WindowHalf halves[2];
        bool window = all_fast && len == kSegment;
        for (int hh = 0; hh < 2 && window; ++hh) {
          const int k0 = hh * kHalf;
          double hx = 0.0;
          double hy = 0.0;
          window = RawPixel(c, u0 + k0 + 3.5, v, &hx, &hy) &&
                   FitWindowHalf(ex + k0, ey + k0, hx, hy, cal.width, cal.height, &halves[hh]);
        }
        if (window) {
          error = 0.0;
          for (int k = 0; k < kSegment; ++k) {
            const WindowHalf& half = halves[k / kHalf];
            const double tx = half.column + (EvalHalf(half.x, k % kHalf) - 4.0) / kFineOne;
            const double ty = half.row + (EvalHalf(half.y, k % kHalf) - 4.0) / kFineOne;
            if (inside(k)) error = std::max(error, std::hypot(tx - ex[k], ty - ey[k]));
          }
          seg.half[0] = halves[0];
          seg.half[1] = halves[1];
          table.kind[index] = SegmentKind::kWindow;
          ++windows;
        } else {
          table.row_window[v] = false;
        }
        max_table_error_px_ = std::max(max_table_error_px_, error);
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
  if (table_[camera].kind[index] == SegmentKind::kWindow) {  // inside by construction
    const WindowHalf& half = seg.half[(u % kSegment) / kHalf];
    const int j = u % kHalf;
    constexpr float kRounding = 1 << (kFineToWeight - 1);
    *raw_u = half.column + (static_cast<float>(EvalHalf(half.x, j)) - kRounding) / kFineOne;
    *raw_v = half.row + (static_cast<float>(EvalHalf(half.y, j)) - kRounding) / kFineOne;
    return true;
  }
  const auto k = static_cast<float>(u % kSegment);
  const float fx = EvalSegment(seg.quad.x, k);
  const float fy = EvalSegment(seg.quad.y, k);
  *raw_u = (fx - 0.5f) / kWeightOneF;
  *raw_v = (fy - 0.5f) / kWeightOneF;
  return fx >= 0.0f && fy >= 0.0f &&
         fx < static_cast<float>((calib_[camera].width - 1) * kWeightOne) + 1.0f &&
         fy < static_cast<float>((calib_[camera].height - 1) * kWeightOne) + 1.0f;
}

void StereoRectifier::RemapOne(const GrayView& raw, const Table& table,
                               const MutableGrayView& out) const {
  const RemapJob job{
      table.segment, table.kind, table.row_window, segments_per_row_, width_, height_, &raw, &out};
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
        const float fx = EvalSegment(segs[s].quad.x, static_cast<float>(k));
        const float fy = EvalSegment(segs[s].quad.y, static_cast<float>(k));
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
        o[u0 + k] = Blend1(s0, s0 + stride, ax, ay);
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
