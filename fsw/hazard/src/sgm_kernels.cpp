// SGM row kernels (sgm_kernels.hpp). One template per row operation over a lane policy K; the
// AVX2 instances are compiled inside target("avx2") functions, the others for the baseline ISA.
#include "sgm_kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#if defined(__aarch64__)
#include <arm_neon.h>
#elif defined(__x86_64__)
#include <immintrin.h>  // declares the SSSE3 / AVX2 builtins used inside target("avx2") kernels
#endif

// The 256-bit helpers below are always inlined into target("avx2") functions; no 32-byte vector
// crosses a call boundary, so GCC's note about the AVX calling convention does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace swf::hazard::sgm_detail {
namespace {

using V8s [[gnu::vector_size(16)]] = std::int16_t;
using V16s [[gnu::vector_size(32)]] = std::int16_t;
using V8b [[gnu::vector_size(8)]] = std::uint8_t;
using V16b [[gnu::vector_size(16)]] = std::uint8_t;
using V32b [[gnu::vector_size(32)]] = std::uint8_t;

template <class V, class T>
[[gnu::always_inline]] inline V Load(const T* p) {
  V v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
template <class V, class T>
[[gnu::always_inline]] inline void Store(T* p, V v) {
  std::memcpy(p, &v, sizeof(v));
}
template <class V>
[[gnu::always_inline]] inline V Min(V a, V b) {
  return a < b ? a : b;
}
template <class V>
[[gnu::always_inline]] inline V Max(V a, V b) {
  return a > b ? a : b;
}

// The minimum of all lanes, in every lane (butterflies: no round trip through a scalar).
[[gnu::always_inline]] inline V8s MinAll(V8s v) {
  v = Min(v, __builtin_shufflevector(v, v, 4, 5, 6, 7, 0, 1, 2, 3));
  v = Min(v, __builtin_shufflevector(v, v, 2, 3, 0, 1, 6, 7, 4, 5));
  return Min(v, __builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6));
}

// Bits set per byte, by the SWAR steps (two bits, then four, then eight).
template <class B>
[[gnu::always_inline]] inline B PopcountBytes(B v) {
  v = v - ((v >> 1) & 0x55);
  v = (v & 0x33) + ((v >> 2) & 0x33);
  return (v + (v >> 4)) & 0x0F;
}

// Lane policies: S = 16-bit lanes of a path chunk, B = cost bytes per step.
struct Portable {
  using S = V8s;
  using B = V16b;
  static constexpr int kLanes = 8;
  [[gnu::always_inline]] static S LoadCost(const std::uint8_t* p) {
    return __builtin_convertvector(Load<V8b>(p), S);
  }
  [[gnu::always_inline]] static S MinAll(S v) { return sgm_detail::MinAll(v); }
  [[gnu::always_inline]] static B Popcount(B v) { return PopcountBytes(v); }
};

#if defined(__x86_64__)
#if !defined(__clang__)
// Bits set per byte by a table of the 16 nibbles (pshufb). The SSSE3 / AVX2 / SSE4.1 builtins
// (declared by <immintrin.h>) are expanded in the target("avx2") functions these helpers are
// inlined into. Clang checks a builtin's ISA in the function that names it, before inlining, so its
// builds (the sanitizer pass) take the generic vector code below: the same integers, slower.
using C16 [[gnu::vector_size(16)]] = char;
using C32 [[gnu::vector_size(32)]] = char;
constexpr V16b kNibbleBits = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
// Bits set in each byte's low nibble (the byte < 16), one pshufb table lookup per width.
[[gnu::always_inline]] inline V16b NibbleBits(V16b nibbles) {
  return reinterpret_cast<V16b>(
      __builtin_ia32_pshufb128(reinterpret_cast<C16>(kNibbleBits), reinterpret_cast<C16>(nibbles)));
}
[[gnu::always_inline]] inline V32b NibbleBits(V32b nibbles) {
  // vpshufb looks up within each 128-bit half: the table twice.
  const V32b table =
      __builtin_shufflevector(kNibbleBits, kNibbleBits, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12,
                              13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  return reinterpret_cast<V32b>(
      __builtin_ia32_pshufb256(reinterpret_cast<C32>(table), reinterpret_cast<C32>(nibbles)));
}
template <class B>
[[gnu::always_inline]] inline B PopcountNibbles(B v) {
  constexpr auto kLowNibble = static_cast<std::uint8_t>(0x0F);
  return NibbleBits(v & kLowNibble) + NibbleBits((v >> 4) & kLowNibble);
}

// The minimum of 16 lanes by SSE4.1's phminposuw (unsigned: every vector the kernels reduce is
// non-negative: path costs, sums, indices, the 0x7FFF filler), in every lane: 4 operations instead
// of 4 shuffles and 4 minimums.
[[gnu::always_inline]] inline V16s MinAllUnsigned(V16s v) {
  const V8s half = Min(__builtin_shufflevector(v, v, 0, 1, 2, 3, 4, 5, 6, 7),
                       __builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15));
  return V16s{} + __builtin_ia32_phminposuw128(half)[0];
}
#else
template <class B>
[[gnu::always_inline]] inline B PopcountNibbles(B v) {
  return PopcountBytes(v);
}
[[gnu::always_inline]] inline V16s MinAllUnsigned(V16s v) {
  v = Min(v, __builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7));
  v = Min(v, __builtin_shufflevector(v, v, 4, 5, 6, 7, 0, 1, 2, 3, 12, 13, 14, 15, 8, 9, 10, 11));
  v = Min(v, __builtin_shufflevector(v, v, 2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13));
  return Min(v,
             __builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14));
}
#endif

struct Wide {  // 256-bit: instantiated only inside target("avx2") functions
  using S = V16s;
  using B = V32b;
  static constexpr int kLanes = 16;
  [[gnu::always_inline]] static S LoadCost(const std::uint8_t* p) {
    return __builtin_convertvector(Load<V16b>(p), S);
  }
  [[gnu::always_inline]] static S MinAll(S v) { return MinAllUnsigned(v); }
  [[gnu::always_inline]] static B Popcount(B v) { return PopcountNibbles(v); }
};

// 128-bit costs inside the AVX2 kernel (16 disparities: half a 256-bit vector of bytes).
struct WideHalf : Portable {
  [[gnu::always_inline]] static B Popcount(B v) { return PopcountNibbles(v); }
};
#endif

#if defined(__aarch64__)
struct Neon {
  using S = V8s;
  using B = V16b;
  static constexpr int kLanes = 8;
  [[gnu::always_inline]] static S LoadCost(const std::uint8_t* p) {
    return reinterpret_cast<S>(vmovl_u8(vld1_u8(p)));
  }
  [[gnu::always_inline]] static S MinAll(S v) {
    return S{} + static_cast<std::int16_t>(vminvq_s16(reinterpret_cast<int16x8_t>(v)));
  }
  [[gnu::always_inline]] static B Popcount(B v) {
    return reinterpret_cast<B>(vcntq_u8(reinterpret_cast<uint8x16_t>(v)));
  }
};
#endif

// Lanes shifted by one across two adjacent chunks: [lo's last lane, hi's lanes but the last], and
// [lo's lanes but the first, hi's first lane]. For a vector whose chunks were just stored, the
// neighbours L(d - 1) and L(d + 1) come from aligned reloads of whole stored chunks (forwarded from
// the store buffer) instead of loads that straddle two stores, which stall until both retire.
[[gnu::always_inline]] inline V8s UpOne(V8s lo, V8s hi) {
  return __builtin_shufflevector(lo, hi, 7, 8, 9, 10, 11, 12, 13, 14);
}
[[gnu::always_inline]] inline V8s DownOne(V8s lo, V8s hi) {
  return __builtin_shufflevector(lo, hi, 1, 2, 3, 4, 5, 6, 7, 8);
}
[[gnu::always_inline]] inline V16s UpOne(V16s lo, V16s hi) {
  return __builtin_shufflevector(lo, hi, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29,
                                 30);
}
[[gnu::always_inline]] inline V16s DownOne(V16s lo, V16s hi) {
  return __builtin_shufflevector(lo, hi, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16);
}

template <class V>
[[gnu::always_inline]] inline V Iota() {
  V v{};
  for (int i = 0; i < static_cast<int>(sizeof(V) / sizeof(v[0])); ++i) v[i] = i;
  return v;
}

template <class K>
[[gnu::always_inline]] inline void CostRowT(const CostRowJob& j) {
  using B = typename K::B;
  constexpr int kBytes = sizeof(B);
  const B lane = Iota<B>();
  const int w = j.width;
  for (int x = 0; x < w; ++x) {
    std::uint8_t* out = j.cost + static_cast<std::ptrdiff_t>(x) * j.cost_stride;
    const int limit = x - j.min_disparity + 1;      // d < limit: the right pixel is in the image
    const int first = w - 1 - x + j.min_disparity;  // reversed index of the right pixel at d = 0
    const B l0 = B{} + j.left[0][x];
    const B l1 = B{} + j.left[1][x];
    const B l2 = B{} + j.left[2][x];
    for (int d0 = 0; d0 < j.padded_d; d0 += kBytes) {
      if (d0 >= limit) {
        Store(out + d0, B{} + static_cast<std::uint8_t>(kMaxCost));
        continue;
      }
      const B bits = K::Popcount(l0 ^ Load<B>(j.right[0] + first + d0)) +
                     K::Popcount(l1 ^ Load<B>(j.right[1] + first + d0)) +
                     K::Popcount(l2 ^ Load<B>(j.right[2] + first + d0));
      B cost = bits * static_cast<std::uint8_t>(kCostScale);
      if (d0 + kBytes > limit) {
        const B inside = B{} + static_cast<std::uint8_t>(limit - d0);
        cost = lane < inside ? cost : B{} + static_cast<std::uint8_t>(kMaxCost);
      }
      Store(out + d0, cost);
    }
  }
}

// Predecessor of one path at one pixel: its vector, min_k L and min_k L + P2 (zeros where the
// path starts: then L = C exactly).
template <class S>
struct Predecessor {
  const std::int16_t* l;
  S min;
  S big;
};

template <class S>
[[gnu::always_inline]] inline Predecessor<S> PredecessorOf(const std::int16_t* l, S min, int p2) {
  return {l, min, min + static_cast<std::int16_t>(p2)};
}

// kPaths paths of one pass (num_vertical + 1).
template <class K, int kPaths, bool kAddSum>
[[gnu::always_inline]] inline void PassRowT(const PassRowJob& j) {
  using S = typename K::S;
  constexpr int kN = K::kLanes;
  constexpr int kNumVertical = kPaths - 1;
  static constexpr int kDx[3] = {0, -1, 1};  // predecessor at x + kDx * dir on the previous row
  const int w = j.width;
  const int dp = j.padded_d;
  const int ps = j.path_stride;
  const int dir = j.forward ? 1 : -1;
  const S p1 = S{} + j.p1;
  const int padded_from = dp - kDisparityUnit;  // padding lanes are among the last 16
  const S highest = S{} + static_cast<std::int16_t>(0x7FFF);
  const std::int16_t* start = j.start + kLead;
  std::int16_t* h_cur = j.horizontal + kLead;
  std::int16_t* h_prev = j.horizontal + ps + kLead;
  S h_min{};
  for (int i = 0; i < w; ++i) {
    const int x = j.forward ? i : w - 1 - i;
    const int ix = j.image[x];
    Predecessor<S> pred[kPaths]{};
    std::int16_t* dst[kPaths]{};
    for (int k = 0; k < kNumVertical; ++k) {
      const std::ptrdiff_t block = static_cast<std::ptrdiff_t>(k) * w;
      const int xp = x + kDx[k] * dir;
      dst[k] = j.cur_rows + (block + x) * ps + kLead;
      if (j.image_prev == nullptr || xp < 0 || xp >= w) {
        pred[k] = PredecessorOf<S>(start, S{}, 0);
      } else {
        pred[k] =
            PredecessorOf<S>(j.prev_rows + (block + xp) * ps + kLead, S{} + j.prev_mins[block + xp],
                             j.p2_table[std::abs(ix - j.image_prev[xp])]);
      }
    }
    dst[kNumVertical] = h_cur;
    pred[kNumVertical] =
        i == 0 ? PredecessorOf<S>(start, S{}, 0)
               : PredecessorOf<S>(h_prev, h_min, j.p2_table[std::abs(ix - j.image[x - dir])]);
    S path_min[kPaths];
    for (int k = 0; k < kPaths; ++k) path_min[k] = highest;
    const std::uint8_t* cost = j.cost + static_cast<std::ptrdiff_t>(x) * j.cost_stride;
    const std::ptrdiff_t sum_at = static_cast<std::ptrdiff_t>(x) * dp;
    // The horizontal predecessor was stored by the previous pixel: its chunks below, at and above
    // d0 roll through registers.
    const std::int16_t* h = pred[kNumVertical].l;
    S h_below = Load<S>(h - kN);
    S h_at = Load<S>(h);
    for (int d0 = 0; d0 < dp; d0 += kN) {
      const S c = K::LoadCost(cost + d0);
      S sum = kAddSum ? Load<S>(j.sum_in + sum_at + d0) : S{};
      const S h_above = Load<S>(h + d0 + kN);
      for (int k = 0; k < kPaths; ++k) {
        // L = C + min(L(d), min(L(d - 1), L(d + 1)) + P1, min + P2) - min.
        S at;
        S t;
        if (k == kNumVertical) {
          at = h_at;
          t = Min(UpOne(h_below, h_at), DownOne(h_at, h_above));
        } else {
          const std::int16_t* p = pred[k].l + d0;
          at = Load<S>(p);
          t = Min(Load<S>(p - 1), Load<S>(p + 1));
        }
        t = Min(Min(t + p1, at), pred[k].big);
        S l = c + (t - pred[k].min);
        if (d0 >= padded_from) l = Max(l, Load<S>(j.pad_floor + d0));
        Store(dst[k] + d0, l);
        sum += l;
        path_min[k] = Min(path_min[k], l);
      }
      Store(j.sum_out + sum_at + d0, sum);
      h_below = h_at;
      h_at = h_above;
    }
    for (int k = 0; k < kNumVertical; ++k) {
      j.cur_mins[static_cast<std::ptrdiff_t>(k) * w + x] = K::MinAll(path_min[k])[0];
    }
    h_min = K::MinAll(path_min[kNumVertical]);
    std::swap(h_cur, h_prev);
  }
}

template <class K>
[[gnu::always_inline]] inline void PassRowDispatch(const PassRowJob& j) {
  if (j.num_vertical == 3) {
    if (j.sum_in != nullptr) {
      PassRowT<K, 4, true>(j);
    } else {
      PassRowT<K, 4, false>(j);
    }
  } else if (j.sum_in != nullptr) {
    PassRowT<K, 2, true>(j);
  } else {
    PassRowT<K, 2, false>(j);
  }
}

// Right-image winners d_R(xr) = argmin_d S(xr + min + d, d), the first on ties, by a window that
// slides along the row: after pixel x, lane d holds the best so far for xr = x - min - d (and its
// d). Moving to x + 1 shifts the lanes up by one and offers S(x + 1, d) to lane d. Lane num_d - 1
// is then complete.
template <class K>
[[gnu::always_inline]] inline void RightWinnersT(const SelectRowJob& j) {
  using S = typename K::S;
  constexpr int kN = K::kLanes;
  const int dp = j.padded_d;
  const int n = j.num_d;
  const int w = j.width;
  std::int16_t* cost = j.window + kDisparityUnit;
  std::int16_t* index = j.window + dp + 3 * kDisparityUnit;
  std::fill(cost - 1, cost + dp, static_cast<std::int16_t>(0x7FFF));
  std::fill(index - 1, index + dp, static_cast<std::int16_t>(0));
  std::fill(j.right, j.right + w, SgmMatcher::kInvalid);
  const S lane = Iota<S>();
  if (dp == kN) {
    // One chunk: the window stays in registers (the pass over a row is then one dependency chain
    // of a shuffle, a compare and a blend per pixel, no memory round trip).
    const S highest = S{} + static_cast<std::int16_t>(0x7FFF);
    S window_cost = highest;
    S window_index{};
    for (int x = 0; x < w; ++x) {
      const S old_cost = UpOne(highest, window_cost);
      const S old_index = UpOne(S{}, window_index);
      const S v = Load<S>(j.sum + static_cast<std::ptrdiff_t>(x) * dp);
      const auto take = v < old_cost;
      window_cost = take ? v : old_cost;
      window_index = take ? lane : old_index;
      const int xr = x - j.min_disparity - (n - 1);
      if (xr >= 0) j.right[xr] = static_cast<float>(window_index[n - 1] + j.min_disparity);
    }
    Store(index, window_index);
  }
  for (int x = 0; x < w && dp > kN; ++x) {
    const std::int16_t* s = j.sum + static_cast<std::ptrdiff_t>(x) * dp;
    // From the top chunk down: chunk d0 reads [d0 - 1, d0 + kN - 1) before chunk d0 - kN writes
    // (whole chunks, see UpOne).
    S cost_at = Load<S>(cost + dp - kN);
    S index_at = Load<S>(index + dp - kN);
    for (int d0 = dp - kN; d0 >= 0; d0 -= kN) {
      const S cost_below = Load<S>(cost + d0 - kN);
      const S index_below = Load<S>(index + d0 - kN);
      const S old_cost = UpOne(cost_below, cost_at);
      const S old_index = UpOne(index_below, index_at);
      const S v = Load<S>(s + d0);
      const auto take = v < old_cost;
      Store(cost + d0, take ? v : old_cost);
      Store(index + d0, take ? lane + static_cast<std::int16_t>(d0) : old_index);
      cost_at = cost_below;
      index_at = index_below;
    }
    const int xr = x - j.min_disparity - (n - 1);
    if (xr >= 0) j.right[xr] = static_cast<float>(index[n - 1] + j.min_disparity);
  }
  for (int d = 0; d + 1 < n; ++d) {  // the last pixels' candidates are all in
    const int xr = w - 1 - j.min_disparity - d;
    if (xr >= 0) j.right[xr] = static_cast<float>(index[d] + j.min_disparity);
  }
}

// std::lround of a float in int range, inline (the library call costs more than the select).
// v - trunc(v) is exact in float, so the comparisons with 0.5 decide as lround does.
[[gnu::always_inline]] inline int RoundHalfAway(float v) {
  const int t = static_cast<int>(v);
  const float fraction = v - static_cast<float>(t);
  return t + (fraction >= 0.5f ? 1 : 0) - (fraction <= -0.5f ? 1 : 0);
}

template <class K>
[[gnu::always_inline]] inline void SelectRowT(SelectRowJob* job) {
  using S = typename K::S;
  constexpr int kN = K::kLanes;
  const SelectRowJob& j = *job;
  RightWinnersT<K>(j);
  const int dp = j.padded_d;
  const int n = j.num_d;
  const int w = j.width;
  const S lane = Iota<S>();
  const S highest = S{} + static_cast<std::int16_t>(0x7FFF);
  int valid = 0;
  for (int x = 0; x < w; ++x) {
    j.disparity[x] = SgmMatcher::kInvalid;
    j.confidence[x] = 0.0f;
    // Only pixels whose whole search range lies in the right image (as OpenCV's SGBM). Padding
    // lanes hold sums of sentinels, above every real sum.
    if (x - j.min_disparity - (n - 1) < 0) continue;
    const std::int16_t* s = j.sum + static_cast<std::ptrdiff_t>(x) * dp;
    // Per lane: the smallest sum and its first d; then the lanes' best and its first d.
    S m = highest;
    S m_d = highest;
    for (int d0 = 0; d0 < dp; d0 += kN) {
      const S v = Load<S>(s + d0);
      const auto lower = v < m;
      m = lower ? v : m;
      m_d = lower ? lane + static_cast<std::int16_t>(d0) : m_d;
    }
    const S best_v = K::MinAll(m);
    const std::int16_t best = best_v[0];
    const int best_d = K::MinAll(m == best_v ? m_d : highest)[0];
    if (best_d == 0 || best_d == n - 1) continue;  // at the search limit: unreliable
    const S lo = S{} + static_cast<std::int16_t>(best_d - 1);
    const S hi = S{} + static_cast<std::int16_t>(best_d + 1);
    S others = highest;
    for (int d0 = 0; d0 < dp; d0 += kN) {
      const S idx = lane + static_cast<std::int16_t>(d0);
      others = Min(others, ((idx >= lo) & (idx <= hi)) ? highest : Load<S>(s + d0));
    }
    const int second = K::MinAll(others)[0];
    const float margin =
        static_cast<float>(second - best) / static_cast<float>(std::max<int>(best, 1));
    if (margin <= j.uniqueness) continue;
    const float sm = s[best_d - 1];
    const float s0 = s[best_d];
    const float sp = s[best_d + 1];
    const float denom = sm - 2.0f * s0 + sp;
    const float offset = denom > 0.0f ? 0.5f * (sm - sp) / denom : 0.0f;
    const float disparity = static_cast<float>(best_d + j.min_disparity) + offset;
    const int xr = RoundHalfAway(static_cast<float>(x) - disparity);
    if (xr < 0 || xr >= w) continue;
    const float dr = j.right[xr];
    if (dr == SgmMatcher::kInvalid) continue;
    const float lr = std::fabs(dr - disparity);
    if (lr > j.lr_max_diff + 0.5f) continue;
    j.disparity[x] = disparity;
    const float unique_conf = std::min(1.0f, margin / 0.5f);
    const float lr_conf = 1.0f - lr / (j.lr_max_diff + 1.0f);
    j.confidence[x] = unique_conf * lr_conf;
    ++valid;
  }
  job->num_valid = valid;
}

void CostRowPortable(const CostRowJob& j) { CostRowT<Portable>(j); }
void PassRowPortable(const PassRowJob& j) { PassRowDispatch<Portable>(j); }
void SelectRowPortable(SelectRowJob* j) { SelectRowT<Portable>(j); }

#if defined(__x86_64__)
[[gnu::target("avx2")]] void CostRowAvx2(const CostRowJob& j) {
  // 16 disparities fill half a 256-bit byte vector: 128-bit steps do half the work.
  if (j.padded_d < static_cast<int>(sizeof(Wide::B))) {
    CostRowT<WideHalf>(j);
  } else {
    CostRowT<Wide>(j);
  }
}
[[gnu::target("avx2")]] void PassRowAvx2(const PassRowJob& j) { PassRowDispatch<Wide>(j); }
[[gnu::target("avx2")]] void SelectRowAvx2(SelectRowJob* j) { SelectRowT<Wide>(j); }
#endif

#if defined(__aarch64__)
void CostRowNeon(const CostRowJob& j) { CostRowT<Neon>(j); }
void PassRowNeon(const PassRowJob& j) { PassRowDispatch<Neon>(j); }
void SelectRowNeon(SelectRowJob* j) { SelectRowT<Neon>(j); }
#endif

// Census of pixel x with the window clamped to the image.
void CensusClamped(const frontend::GrayView& image, int x, int y, std::uint8_t out[kCensusPlanes]) {
  const int c = image.At(x, y);
  out[0] = out[1] = out[2] = 0;
  int k = 0;
  for (int dy = -2; dy <= 2; ++dy) {
    const std::uint8_t* row = image.Row(std::clamp(y + dy, 0, image.height - 1));
    for (int dx = -2; dx <= 2; ++dx) {
      if (dx == 0 && dy == 0) continue;
      if (row[std::clamp(x + dx, 0, image.width - 1)] < c) {
        out[k >> 3] = static_cast<std::uint8_t>(out[k >> 3] | (0x80 >> (k & 7)));
      }
      ++k;
    }
  }
}

}  // namespace

void CensusRow(const frontend::GrayView& image, int y, bool reversed, std::uint8_t* const* plane) {
  const int w = image.width;
  const auto put = [&](int x, const std::uint8_t* bits) {
    const int at = reversed ? w - 1 - x : x;
    for (int p = 0; p < kCensusPlanes; ++p) plane[p][at] = bits[p];
  };
  int x = 0;
  if (y >= 2 && y < image.height - 2) {
    // Interior: 16 pixels at a time, no clamping.
    for (; x < 2; ++x) {
      std::uint8_t bits[kCensusPlanes];
      CensusClamped(image, x, y, bits);
      put(x, bits);
    }
    // The last block overlaps the one before it (the same bits again) rather than leaving up to
    // 15 pixels to the clamped scalar census.
    const int last_block = w - 2 - 16;
    for (; x <= last_block + 15 && last_block >= 2; x += 16) {
      x = std::min(x, last_block);
      const V16b c = Load<V16b>(image.Row(y) + x);
      V16b bits[kCensusPlanes] = {};
      int k = 0;
      for (int dy = -2; dy <= 2; ++dy) {
        const std::uint8_t* row = image.Row(y + dy) + x;
        for (int dx = -2; dx <= 2; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const auto darker = reinterpret_cast<V16b>(Load<V16b>(row + dx) < c);
          bits[k >> 3] |= darker & static_cast<std::uint8_t>(0x80 >> (k & 7));
          ++k;
        }
      }
      for (int p = 0; p < kCensusPlanes; ++p) {
        if (reversed) {
          Store(plane[p] + (w - 16 - x),
                __builtin_shufflevector(bits[p], bits[p], 15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4,
                                        3, 2, 1, 0));
        } else {
          Store(plane[p] + x, bits[p]);
        }
      }
    }
  }
  for (; x < w; ++x) {
    std::uint8_t bits[kCensusPlanes];
    CensusClamped(image, x, y, bits);
    put(x, bits);
  }
}

SgmKernel Resolve(SgmKernel kernel) {
  if (kernel != SgmKernel::kAuto) return kernel;
  for (const SgmKernel k : {SgmKernel::kAvx2, SgmKernel::kNeon}) {
    if (SgmKernelSupported(k)) return k;
  }
  return SgmKernel::kPortable;
}

Kernels KernelsOf(SgmKernel kernel) {
  switch (kernel) {
#if defined(__x86_64__)
    case SgmKernel::kAvx2: return {CostRowAvx2, PassRowAvx2, SelectRowAvx2};
#endif
#if defined(__aarch64__)
    case SgmKernel::kNeon: return {CostRowNeon, PassRowNeon, SelectRowNeon};
#endif
    default: return {CostRowPortable, PassRowPortable, SelectRowPortable};
  }
}

}  // namespace swf::hazard::sgm_detail

namespace swf::hazard {

bool SgmKernelSupported(SgmKernel kernel) {
  switch (kernel) {
    case SgmKernel::kAuto:
    case SgmKernel::kPortable: return true;
#if defined(__x86_64__)
    case SgmKernel::kAvx2: __builtin_cpu_init(); return __builtin_cpu_supports("avx2") != 0;
#elif defined(__aarch64__)
    case SgmKernel::kNeon: return true;
#endif
    default: return false;
  }
}

}  // namespace swf::hazard
