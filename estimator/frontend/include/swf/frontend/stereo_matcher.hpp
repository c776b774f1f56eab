// Stereo matching along rectified rows (paper 4.1.1): zero-mean SAD patch search over the disparity
// range, a left-right consistency check, then Lucas-Kanade subpixel refinement of the disparity.
//
// Refinement (1-D LK with an additive brightness offset b): minimise over (d, b)
//   E = sum_i ( R(x_i - d, y_i) + b - L(x_i, y_i) )^2
// over the (2r+1)^2 patch, R sampled bilinearly. Linearising R(x - d - dd) ~ R(x - d) - g dd
// with g the template gradient dL/dx (Scharr: the central difference smoothed [3 10 3] / 16
// across rows), and eliminating b (centred g and centred residual e), each Gauss-Newton step is
//   dd = sum(gc * ec) / sum(gc^2).
// The fixed point, sum(gc * ec) = 0, weights the residual by the gradient: with bilinear sampling
// and noise the residual never vanishes, and the smoothed gradient weights the low frequencies,
// which bilinear sampling shifts least (measured: docs/benchmarks.md, Front end).
#pragma once

#include <cstddef>

#include "swf/core/static_vector.hpp"
#include "swf/core/status.hpp"
#include "swf/frontend/config.hpp"
#include "swf/frontend/harris.hpp"
#include "swf/frontend/image.hpp"

namespace swf::frontend {

struct StereoMatcherOptions {
  int patch_radius = 4;     // SAD patch: (2r+1)^2
  int lk_patch_radius = 5;  // LK refinement patch: 11 x 11
  int min_disparity = 0;    // pixels
  int max_disparity = 128;  // pixels, <= kMaxDisparity
  int lr_tolerance_px = 1;  // left-right check: |d_lr - d_rl| <= this
  int lk_iterations = 10;
  float lk_epsilon_px = 0.002f;
  float max_lk_shift_px = 1.5f;  // refinement may not move further from the SAD optimum
  float min_zncc = 0.8f;         // quality gate after refinement
  // Solve for an additive offset between the cameras (independent exposures). Off: constant
  // brightness (see TrackerOptions::brightness_offset).
  bool brightness_offset = true;
};

struct StereoMatch {
  float x = 0.0f;          // left column (uL)
  float y = 0.0f;          // row (v)
  float disparity = 0.0f;  // uL - uR
  float quality = 0.0f;    // zero-mean normalised cross-correlation in [-1, 1]
};

using StereoMatchList = core::StaticVector<StereoMatch, kMaxCorners>;

class StereoMatcher {
 public:
  core::Status Configure(const StereoMatcherOptions& options);
  const StereoMatcherOptions& Options() const { return options_; }

  // Integer-pixel left feature -> SAD search, left-right check, LK refinement.
  // False when rejected (out of range, inconsistent, low quality).
  bool Match(const GrayView& left, const GrayView& right, int x, int y, StereoMatch* match) const;

  // Subpixel left point (x, y): refines *disparity from its initial value with LK.
  // *quality receives the ZNCC. False when it leaves the image or fails to converge.
  bool RefineDisparity(const GrayView& left, const GrayView& right, float x, float y,
                       float* disparity, float* quality) const;

  // Matches every corner; rejected corners are left out. Never allocates.
  core::Status MatchAll(const GrayView& left, const GrayView& right, const CornerList& corners,
                        StereoMatchList* matches) const;

 private:
  // Best integer disparity of the patch at (x, y) of `from` searched in `to` at x - sign * d.
  // Returns -1 when no disparity fits; *cost_before / *cost_after are the neighbours' SADs.
  int SearchRow(const GrayView& from, const GrayView& to, int x, int y, int sign, int* best_cost,
                int* cost_before, int* cost_after) const;

  StereoMatcherOptions options_{};
  bool configured_ = false;
};

}  // namespace swf::frontend
