// Temporal tracking by translation-only Lucas-Kanade (paper 4.1.2).
//
// A template T(delta) (delta: integer offsets in a (2r+1)^2 patch) is aligned in image I by the
// translation c: minimise over (c, b)
//   E = sum_i ( I(c + o_i) + b - T_i )^2,     o_i = H(p_ref + delta_i) - H(p_ref),
// with H the homography of the landmark's local plane from the reference frame to the current
// one (o_i = delta_i without geometry), I sampled bilinearly and b a brightness offset.
// Gauss-Newton with the template gradient mapped into the current image, g_i = A^-T grad T_i
// (A = dH/dp at p_ref), centred to eliminate b:
//   [sum g g^T] dc = sum g_i (e_i - mean e),     e_i = T_i - I(c + o_i).
// The fixed point, sum g_i (e_i - mean e) = 0, weights the residual by the gradient; with
// bilinear sampling and noise the residual never vanishes, so the gradient operator (Scharr,
// ScharrX below) and the brightness model (TrackerOptions::brightness_offset) set the accuracy.
//
// A warped template (TrackWarped, SearchWarped) uses the second-order form (ESM, Benhimane and
// Malis 2004) instead: g_i = (A^-T grad T_i + grad I(c + o_i)) / 2, the image's gradient taken
// by central differences at every iteration. A template seen from farther away holds less detail
// than the image it is aligned in, so its own gradient is a poor model of how the image changes
// under a shift: the iteration contracts slowly, stops on the step length while part of the start
// error is left, and the result follows the prediction that started it. On the rendered descent
// over the smooth plains, with exact predictions moved +-0.3 px along the ray from the focus of
// expansion, 5 % to 9 % of that move stayed in the result with the template's gradient alone and
// under 1 % up to m = 2 with the mean; the prediction is the filter's, so that share fed its own
// altitude error back into the measurements (docs/imu.md).
//
// Plane homography: the landmark lies on a plane with the reference camera's optical axis as
// normal, n = (0,0,1), at the landmark's depth z_ref. For p_cur = R p_ref + t (cur_T_ref) and
// n^T p_ref = z_ref:  p_cur = (R + t n^T / z_ref) p_ref, so  H = K (R + t n^T / z_ref) K^-1.
#pragma once

#include <Eigen/Core>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/frontend/config.hpp"
#include "swf/frontend/image.hpp"

namespace swf::frontend {

struct TrackerOptions {
  int patch_radius = 6;  // (2r+1)^2 template, r <= kMaxPatchRadius
  int pyramid_levels = 3;
  int max_iterations = 20;
  float epsilon_px = 0.005f;              // convergence: last step shorter than this (finest level)
  float coarse_epsilon_px = 0.03f;        // the same on coarser pyramid levels (only seed the next)
  float min_zncc = 0.75f;                 // quality gate of a tracked feature
  float max_prediction_error_px = 12.0f;  // warped tracking may not move further than this
  // Solve for an additive brightness offset per patch (independent exposures, EuRoC). Off: constant
  // brightness, as OpenCV's LK assumes; where that holds it is more accurate, because a linear
  // intensity ramp across the patch moved by a translation is indistinguishable from an offset,
  // so with the offset the patch's strongest (low-frequency) content carries no information.
  bool brightness_offset = true;
  // SearchWarped: the integer offsets within this radius of the prediction are compared
  // (search_radius_px^2 * 4 ZNCCs of the patch; <= kMaxSearchRadius).
  int search_radius_px = 5;
};

// A reference patch with its (Scharr) gradients, taken where a landmark was first
// seen.
struct PatchTemplate {
  int radius = 0;
  float ref_x = 0.0f;  // centre in the reference image (pixels)
  float ref_y = 0.0f;
  float value[kMaxPatchPixels] = {};
  float gx[kMaxPatchPixels] = {};
  float gy[kMaxPatchPixels] = {};
};

// Scharr derivative at *g of a float grid with the given row stride, scaled like a central
// difference (d/dx = (g[1] - g[-1]) / 2 for a linear ramp): [-3 0 3; -10 0 10; -3 0 3] / 32 and its
// transpose. The [3 10 3] smoothing across the derivative weights low frequencies, which bilinear
// sampling shifts least, more than the plain central difference does.
float ScharrX(const float* g, int stride);
float ScharrY(const float* g, int stride);

// Zero-mean normalized cross-correlation of two patches of `count` samples, given their means:
// the quality score of a track or a stereo match, in [-1, 1]; 0 when either patch is flat.
float Zncc(const float* a, float mean_a, const float* b, float mean_b, int count);

// H mapping reference-frame pixels to current-frame pixels for the plane through the landmark
// facing the reference camera (file comment). depth_ref_m is the landmark's z in the reference
// camera; fx, fy, cx, cy of the rectified left camera.
Eigen::Matrix3d PlaneHomography(const estimator::StereoCamera<double>& camera,
                                const estimator::Pose<double>& cur_T_ref, double depth_ref_m);

class PatchTracker {
 public:
  core::Status Configure(const TrackerOptions& options);
  const TrackerOptions& Options() const { return options_; }

  // Samples the template around (x, y). False when the patch leaves the image.
  bool ExtractTemplate(const GrayView& image, float x, float y, PatchTemplate* tmpl) const;
  // Same with the border replicated (never fails); for coarse pyramid levels.
  void ExtractTemplateClamped(const GrayView& image, float x, float y, PatchTemplate* tmpl) const;

  // Pyramidal LK without geometry (flow): the patch at p_prev in prev is searched in cur starting
  // at *p_cur (in: initial guess, out: result). *quality = ZNCC. False when lost.
  bool TrackFlow(const Pyramid& prev, const Pyramid& cur, float prev_x, float prev_y, float* cur_x,
                 float* cur_y, float* quality) const;

  // Warped LK at full resolution: aligns `tmpl` in `image` under homography starting from the
  // prediction (*cur_x, *cur_y). False when lost or when the result moved further than
  // max_prediction_error_px from the prediction.
  bool TrackWarped(const GrayView& image, const PatchTemplate& tmpl,
                   const Eigen::Matrix3d& homography, float* cur_x, float* cur_y,
                   float* quality) const;

  // Recovery when TrackWarped lost the track (paper 4.1.1: patch matching before LK): the warped
  // template's ZNCC at every whole-pixel offset within search_radius_px of the prediction
  // (*cur_x, *cur_y), the best one, if its ZNCC reaches min_zncc, refined by the same warped LK.
  // False when nothing in the window matches, LK fails from there or ends more than
  // search_radius_px + 1 from the prediction. The window's samples share their bilinear weights,
  // so the cost is (2 search_radius_px + 1)^2 patch correlations of 4 loads per pixel.
  bool SearchWarped(const GrayView& image, const PatchTemplate& tmpl,
                    const Eigen::Matrix3d& homography, float* cur_x, float* cur_y,
                    float* quality) const;

 private:
  // Core Gauss-Newton alignment (file comment). offsets: 2 * count floats.
  // grid_radius >= 0: offsets are the unwarped integer grid (fast sampling); clamped: replicate
  // the border instead of failing when the patch leaves the image; second_order: the ESM
  // Jacobian (file comment) for a warped template.
  bool Align(const GrayView& image, const float* value, const float* gx, const float* gy,
             const float* offsets, int count, int grid_radius, bool clamped, bool second_order,
             float epsilon, float* cx, float* cy, float* quality) const;
  // The template under homography: offsets (2 per pixel) of its pixels around the centre's image
  // and its gradients mapped by A^-T (file comment). False for a degenerate warp.
  bool WarpTemplate(const PatchTemplate& tmpl, const Eigen::Matrix3d& homography, float* offsets,
                    float* gx, float* gy) const;

  TrackerOptions options_{};
  bool configured_ = false;
};

}  // namespace swf::frontend
