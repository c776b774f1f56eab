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
  // Repeated texture (a rock field's look-alike rocks on one row) can give a wrong integer
  // disparity a lower SAD than the true one when the true disparity falls between integers.
  // A second SAD minimum within (1 + ambiguity_sad_ratio) x the best cost is refined and
  // left-right checked too; when it is a distinct match (more than a pixel away) whose refined
  // ZNCC is not below the best's by more than ambiguity_zncc_margin, the feature is rejected as
  // ambiguous. ambiguity_sad_ratio < 0: off.
  float ambiguity_sad_ratio = 1.0f;
  float ambiguity_zncc_margin = 0.01f;
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
  // One integer SAD minimum: its disparity, cost and the costs at disparity -1 / +1 (-1 when
  // outside the searched range).
  struct SadMinimum {
    int disparity = -1;
    int cost = 0;
    int cost_before = -1;
    int cost_after = -1;
  };
  // Best integer disparity of the patch at (x, y) of `from` searched in `to` at x - sign * d.
  // False when no disparity fits. *runner_up (when not null) receives the lowest other local
  // minimum more than one disparity from the best (disparity -1 when there is none).
  bool SearchRow(const GrayView& from, const GrayView& to, int x, int y, int sign, SadMinimum* best,
                 SadMinimum* runner_up) const;
  // Left-right check, parabola start and LK refinement of one SAD minimum; false when rejected.
  bool Verify(const GrayView& left, const GrayView& right, int x, int y, const SadMinimum& m,
              float* disparity, float* quality) const;

  StereoMatcherOptions options_{};
  bool configured_ = false;
};

}  // namespace swf::frontend
