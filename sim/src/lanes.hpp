// Four-lane helpers shared by the vectorized renderer, terrain and texture code (GCC vector
// extensions: SSE2 on x86-64, NEON on aarch64, plain scalar code elsewhere). Internal to sim/.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <xmmintrin.h>
#elif defined(__ARM_NEON) && defined(__aarch64__)
#include <arm_neon.h>
#endif

namespace swf::sim::lanes {

using V4f [[gnu::vector_size(16)]] = float;
using V4i [[gnu::vector_size(16)]] = std::int32_t;

inline V4f SqrtLanes(V4f x) {
#if defined(__SSE2__)
  return _mm_sqrt_ps(x);
#elif defined(__ARM_NEON) && defined(__aarch64__)
  return vsqrtq_f32(x);
#else
  return V4f{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])};
#endif
}

// The four corners of one bilinear cell per lane: lane k's cell starts at base + offset[k] in a
// row-major float grid with the given row stride. Per lane the pairs (v00, v10) and (v01, v11)
// are adjacent floats, so they come as 8-byte loads into the halves of 16-byte registers (as
// doubles, bit-cast back) and are then de-interleaved: 4 loads and 4 shuffles per row pair
// instead of 16 scalar loads.
struct CellCorners4 {
  V4f v00, v10, v01, v11;
};

inline CellCorners4 GatherCellCorners4(const float* base, V4i offset, std::int32_t stride) {
  using V2d [[gnu::vector_size(16)]] = double;
  auto pair = [&](int lane, std::int32_t row) {
    double q = 0.0;
    std::memcpy(&q, base + offset[lane] + row, sizeof(q));
    return q;
  };
  const auto low01 = reinterpret_cast<V4f>(V2d{pair(0, 0), pair(1, 0)});
  const auto low23 = reinterpret_cast<V4f>(V2d{pair(2, 0), pair(3, 0)});
  const auto high01 = reinterpret_cast<V4f>(V2d{pair(0, stride), pair(1, stride)});
  const auto high23 = reinterpret_cast<V4f>(V2d{pair(2, stride), pair(3, stride)});
  return {__builtin_shufflevector(low01, low23, 0, 2, 4, 6),
          __builtin_shufflevector(low01, low23, 1, 3, 5, 7),
          __builtin_shufflevector(high01, high23, 0, 2, 4, 6),
          __builtin_shufflevector(high01, high23, 1, 3, 5, 7)};
}

}  // namespace swf::sim::lanes
