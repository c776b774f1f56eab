// The per-frame half of StereoRectifier (rectify_kernels.cpp): the remap kernels of every
// instruction set and the per-pixel pass for segments not entirely inside, and the fixed-point
// formats they share with the table fitting in rectify.cpp. Internal to the front end.
#pragma once

#include <cstdint>

#include "swf/frontend/image.hpp"
#include "swf/frontend/rectify.hpp"

namespace swf::frontend::rectify_detail {

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

// Everything a kernel needs for one image.
struct RemapJob {
  const Segment* segment;
  const SegmentKind* kind;
  const bool* row_inside;  // every segment of the row is kInside or kWindow
  const bool* row_window;  // every segment of the row is kWindow
  int segments_per_row;
  int width;
  int height;
  const GrayView* raw;
  const MutableGrayView* out;
};

// True when this CPU runs `kernel` (never for kAuto).
bool KernelSupported(RemapKernel kernel);

// The fastest kernel this CPU supports.
RemapKernel BestKernel();

// Remaps job.raw into job.out: `kernel` (one KernelSupported accepts) for the kInside and kWindow
// segments, then per-pixel checks with the same arithmetic for the rest.
void Remap(RemapKernel kernel, const RemapJob& job);

}  // namespace swf::frontend::rectify_detail
