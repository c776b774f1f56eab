#include "rectify_kernels.hpp"

#include <algorithm>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#elif defined(__aarch64__)
#include <arm_neon.h>
#endif

namespace swf::frontend::rectify_detail {
namespace {

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

// Taps of pixels q .. q + 7 of a kWindow segment (portable kernel, step 1): the offset of the
// top-left tap, the window origin + dx + (dy ? stride : 0), and the weights.
[[gnu::always_inline]] inline void WindowHalfTaps(const WindowHalf& half, std::int32_t stride,
                                                  int q, std::int32_t* offset, std::int16_t* wx,
                                                  std::int16_t* wy) {
  const V4i stride4 = {stride, stride, stride, stride};
  V8s coef;
  std::memcpy(&coef, &half, sizeof(coef));
  const V8u x = EvalHalf8<0>(coef);
  const V8u y = EvalHalf8<3>(coef);
  const V8u dx = x >> kFineBits;
  const std::int32_t origin = half.row * stride + half.column;
  const V8u dy = y >> kFineBits;
  const V4i off_lo = origin + WidenLo(dx) + (-WidenLo(dy) & stride4);
  const V4i off_hi = origin + WidenHi(dx) + (-WidenHi(dy) & stride4);
  const auto ax = reinterpret_cast<V8s>((x >> kFineToWeight) & (kWeightOne - 1));
  const auto ay = reinterpret_cast<V8s>((y >> kFineToWeight) & (kWeightOne - 1));
  std::memcpy(offset + q, &off_lo, sizeof(off_lo));
  std::memcpy(offset + q + 4, &off_hi, sizeof(off_hi));
  std::memcpy(wx + q, &ax, sizeof(ax));
  std::memcpy(wy + q, &ay, sizeof(ay));
}

// Step 1 of the portable kernel: the source coordinates of output row v in 1/128 px, as the
// offset of each pixel's top-left tap and its weights. Pixels left to the per-pixel pass and
// lanes past the last pixel get a harmless tap at offset 0.
[[gnu::always_inline]] inline void PortableRowTaps(const RemapJob& job, int v, std::int32_t* offset,
                                                   std::int16_t* wx, std::int16_t* wy) {
  const std::int32_t stride = job.raw->stride;
  const V4i stride4 = {stride, stride, stride, stride};
  const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
  for (int s = 0; s < job.segments_per_row; ++s) {
    const int u0 = s * kSegment;
    const SegmentKind kind = job.kind[row + s];
    if (kind == SegmentKind::kWindow) {
      for (int h = 0; h < 2; ++h) {
        WindowHalfTaps(job.segment[row + s].half[h], stride, u0 + h * kHalf, offset, wx, wy);
      }
      continue;
    }
    if (kind != SegmentKind::kInside) {
      for (int k = 0; k < kSegment; ++k) {
        offset[u0 + k] = 0;  // the pixels are redone by the per-pixel pass
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
  for (int u = job.width; u < job.segments_per_row * kSegment; ++u) offset[u] = 0;
}

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
  const std::uint8_t* src = job.raw->data;
  const std::uint8_t* below = src + job.raw->stride;
  for (int v = 0; v < job.height; ++v) {
    // 1. Source coordinates of the row.
    PortableRowTaps(job, v, offset, wx, wy);
    // 2. Gather the two source bytes of the top and of the bottom row (one 16-bit load each,
    // straight into a vector lane) and 3. blend.
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

// The segments not entirely inside: per-pixel checks with the same arithmetic in scalar; kOutside
// segments become zeros.
void RemapBorder(const RemapJob& job) {
  const GrayView& raw = *job.raw;
  const std::int32_t stride = raw.stride;
  const int max_x = raw.width - 1;
  const int max_y = raw.height - 1;
  for (int v = 0; v < job.height; ++v) {
    if (job.row_inside[v]) continue;
    const std::size_t row = static_cast<std::size_t>(v) * job.segments_per_row;
    const Segment* segs = job.segment + row;
    const SegmentKind* kinds = job.kind + row;
    std::uint8_t* o = job.out->Row(v);
    for (int s = 0; s < job.segments_per_row; ++s) {
      if (kinds[s] == SegmentKind::kInside || kinds[s] == SegmentKind::kWindow) continue;
      const int u0 = s * kSegment;
      const int len = std::min(kSegment, job.width - u0);
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

}  // namespace

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

void Remap(RemapKernel kernel, const RemapJob& job) {
  switch (kernel) {
#if defined(__x86_64__)
    case RemapKernel::kAvx2: RemapAvx2(job); break;
    case RemapKernel::kSsse3: RemapSsse3(job); break;
#elif defined(__aarch64__)
    case RemapKernel::kNeon: RemapNeon(job); break;
#endif
    default: RemapPortable(job); break;
  }
  RemapBorder(job);
}

}  // namespace swf::frontend::rectify_detail
