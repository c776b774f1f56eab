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
// Memory: every buffer is sized once by Configure() for the largest image and disparity count;
// Compute() never allocates.
#pragma once

#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/frontend/image.hpp"

namespace swf::hazard {

struct SgmOptions {
  int max_width = 1024;  // capacity: largest image Compute() accepts
  int max_height = 768;
  int max_disparities = 128;  // capacity: largest num_disparities
  int paths = 8;              // 4 or 8 aggregation directions
  int p1 = 8;                 // small-change penalty (census costs are scaled x4: 0..96)
  int p2 = 96;                // large-change penalty (divided by 1 + |dI| / 16 at edges)
  float uniqueness = 0.05f;   // second best must exceed best by this fraction
  float lr_max_diff = 1.0f;   // left-right consistency tolerance (px)
};

// Halves an image with a [1 2 1] x [1 2 1] / 16 low-pass: dst (row-major, (width + 1) / 2 x
// (height + 1) / 2, caller-owned) pixel (x, y) is centred on src pixel (2x, 2y), so a camera's
// fx, fy, cx, cy simply halve.
void HalveImage(const frontend::GrayView& src, std::uint8_t* dst);

class SgmMatcher {
 public:
  static constexpr float kInvalid = -1.0f;

  // Allocates every buffer. kInvalidArgument for sizes < 8, paths not 4 or 8, non-positive
  // penalties, p2 < p1 or disparities outside [4, 256].
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

 private:
  void Census(const frontend::GrayView& image, std::uint32_t* out) const;
  void MatchingCost(int min_disparity);
  void Aggregate(const frontend::GrayView& left);
  void SelectDisparities(int min_disparity);

  SgmOptions options_;
  bool configured_ = false;
  int width_ = 0;
  int height_ = 0;
  int num_d_ = 0;
  int num_valid_ = 0;
  std::vector<std::uint32_t> census_left_;
  std::vector<std::uint32_t> census_right_;
  std::vector<std::uint8_t> cost_;       // C(p, d): width * height * num_d
  std::vector<std::int16_t> sum_;        // S(p, d)
  std::vector<std::int16_t> path_prev_;  // previous row of L_r, one block per vertical path
  std::vector<std::int16_t> path_cur_;
  std::vector<std::int16_t> path_min_prev_;  // min_k L_r(p-r, k) for the previous row
  std::vector<std::int16_t> path_min_cur_;
  std::vector<std::int16_t> row_path_;  // horizontal paths: one pixel's L_r
  std::vector<float> disparity_;
  std::vector<float> confidence_;
  std::vector<float> right_disparity_;
};

}  // namespace swf::hazard
