// Dense stereo for hazard mapping: semi-global matching (Hirschmueller 2008) on a rectified pair.
//
// Matching cost: Hamming distance of 5x5 census signatures (24 bits), robust to the gain and
// exposure differences between the two cameras. Aggregation: the SGM recursion
//   L_r(p, d) = C(p, d) + min(L_r(p-r, d), L_r(p-r, d+-1) + P1, min_k L_r(p-r, k) + P2)
//               - min_k L_r(p-r, k)
// along 4 (horizontal, vertical) or 8 (plus diagonals) paths, summed into S(p, d). Disparity:
// winner-take-all over S, refined to subpixel by a parabola through the three costs around the
// minimum. Right-image disparities come from the same S (d_R(x) = argmin_d S(x + d, d)); a pixel
// survives the left-right check when |d_L(x) - d_R(x - d_L)| <= lr_max_diff. Confidence in [0, 1]
// combines the uniqueness margin (second best outside +-1 vs best) and the left-right agreement.
// Disparities are searched in [min_disparity, min_disparity + num_disparities).
//
// Implementation: census planes of the whole pair, then two passes over the rows. The forward pass
// (top-down, left to right) runs the paths that come from above and from the left and stores their
// sum; the backward pass runs the others, adds the stored sum and selects the row's disparities at
// once, so the path vectors are never a full volume. The forward pass computes each row's costs
// (1 byte per disparity) and keeps them for the backward pass. Every pixel's path vectors are
// 16-bit lanes, padded to a multiple of 16 disparities; the kernels (SgmKernel) compute the same
// integers in the same order and give bit-identical results (tested against a plain scalar SGM).
//
// Memory: every buffer is sized once by Configure() for the largest image and disparity count
// (about 3 bytes per pixel and padded disparity: the forward sum and the costs); Compute() never
// allocates.
#pragma once

#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/frontend/image.hpp"

namespace swf::hazard {

// Instruction-set kernel of the matcher: every kernel gives the same bits. kPortable: 128-bit GCC
// vector extensions (SSE2 on x86-64, NEON on AArch64); kAvx2: 256-bit (x86-64 with AVX2, picked at
// run time); kNeon: 128-bit with NEON's horizontal minimum and byte popcount (AArch64). kAuto:
// the fastest the CPU supports.
enum class SgmKernel : std::uint8_t { kAuto, kPortable, kAvx2, kNeon };

// True when this build and CPU can run `kernel` (kAuto: always).
bool SgmKernelSupported(SgmKernel kernel);

struct SgmOptions {
  int max_width = 1024;  // capacity: largest image Compute() accepts
  int max_height = 768;
  int max_disparities = 128;  // capacity: largest num_disparities
  int paths = 8;              // 4 or 8 aggregation directions
  int p1 = 8;                 // small-change penalty (census costs are scaled x4: 0..96)
  int p2 = 96;                // large-change penalty (divided by 1 + |dI| / 16 at edges)
  float uniqueness = 0.05f;   // second best must exceed best by this fraction
  float lr_max_diff = 1.0f;   // left-right consistency tolerance (px)
  SgmKernel kernel = SgmKernel::kAuto;
};

// Halves an image with a [1 2 1] x [1 2 1] / 16 low-pass: dst (row-major, (width + 1) / 2 x
// (height + 1) / 2, caller-owned) pixel (x, y) is centred on src pixel (2x, 2y), so a camera's
// fx, fy, cx, cy simply halve.
void HalveImage(const frontend::GrayView& src, std::uint8_t* dst);

class SgmMatcher {
 public:
  static constexpr float kInvalid = -1.0f;

  // Allocates every buffer. kInvalidArgument for sizes < 8, paths not 4 or 8, non-positive
  // penalties, p2 < p1 or p2 > 1000, disparities outside [4, 256] or a kernel this CPU cannot run.
  core::Status Configure(const SgmOptions& options);

  // Matches a rectified pair (same size, at most the configured capacity, width > min + num
  // disparities). kNotConfigured before Configure(); kInvalidArgument for bad views or range.
  core::Status Compute(const frontend::GrayView& left, const frontend::GrayView& right,
                       int min_disparity, int num_disparities);

  int Width() const { return width_; }
  int Height() const { return height_; }
  // Left-image disparity (px, subpixel) or kInvalid; row-major Width() x Height().
  const float* Disparity() const { return disparity_.data(); }
  // Per-pixel confidence in [0, 1] (0 for invalid pixels).
  const float* Confidence() const { return confidence_.data(); }
  float DisparityAt(int x, int y) const {
    return disparity_[static_cast<std::size_t>(y) * width_ + x];
  }
  float ConfidenceAt(int x, int y) const {
    return confidence_[static_cast<std::size_t>(y) * width_ + x];
  }
  // Pixels with a valid disparity after the last Compute().
  int NumValid() const { return num_valid_; }
  const SgmOptions& Options() const { return options_; }
  // The kernel Configure() picked (never kAuto once configured).
  SgmKernel Kernel() const { return kernel_; }

 private:
  void CensusPair(const frontend::GrayView& left, const frontend::GrayView& right);
  void CostRow(int y, int min_disparity);
  std::uint8_t* CostsOfRow(int y);
  void PassRow(int y, bool forward, bool first_row, const frontend::GrayView& left);
  void SelectRow(int y, int min_disparity);

  SgmOptions options_;
  SgmKernel kernel_ = SgmKernel::kPortable;
  bool configured_ = false;
  int width_ = 0;
  int height_ = 0;
  int num_d_ = 0;
  int padded_d_ = 0;       // num_d_ rounded up to 16: the lanes of every path vector
  int path_stride_ = 0;    // int16 per pixel in the path rows: padded_d_ + 2 * 16 of sentinels
  int census_stride_ = 0;  // bytes per row of a census plane: capacity width + 16 of padding
  int num_valid_ = 0;
  std::vector<std::int16_t> p2_table_;         // adaptive P2 by |dI| (0..255)
  std::vector<std::uint8_t> census_left_;      // 3 planes of 8 bits per pixel
  std::vector<std::uint8_t> census_right_;     // the same, each row reversed (x -> w - 1 - x)
  std::vector<std::uint8_t> cost_volume_;      // C(x, d) of every row: height * width * stride
  std::vector<std::int16_t> forward_sum_;      // S of the forward paths: height * width * padded_d
  std::vector<std::int16_t> row_sum_;          // S of one row (backward pass): width * padded_d
  std::vector<std::int16_t> path_rows_;        // L_r of the vertical paths: previous and current
  std::vector<std::int16_t> path_mins_;        // min_k L_r per pixel of those rows
  std::vector<std::int16_t> path_horizontal_;  // L_r of the horizontal path: two pixels
  std::vector<std::int16_t> path_start_;       // zeros: the 'previous' vector where a path starts
  std::vector<std::int16_t> pad_floor_;        // 0 for d < num_d, the sentinel in padding lanes
  std::vector<std::int16_t> right_window_;     // right-image winners: sliding costs and indices
  std::vector<float> disparity_;
  std::vector<float> confidence_;
  std::vector<float> right_disparity_;
};

}  // namespace swf::hazard
