// Renderer: rectified stereo images of the terrain by ray casting the height field, with exact
// per-pixel truth.
//
// For each pixel centre (u, v) of camera c (0 left, 1 right at +baseline along camera x) the ray
// world_R_c * ((u - cx) / fx, (v - cy) / fy, 1) from the camera centre is intersected with the
// bilinear height field (closed-form roots per cell, as Terrain::Intersect). Pixels go in 8x8
// tiles: the tile's corner rays and the min/max pyramid bound the heights where any of its rays can
// first hit (refined a few rounds), so each ray only solves the one or two cells of that stretch
// (Terrain::IntersectSpan; longer stretches walk the pyramid).
// The hit's radiance (Appearance::Radiance, bilinear, band-limited by the pixel footprint
// range / fx) becomes DN = exposure_dn * radiance; with samples_per_pixel = 4 the radiance is
// averaged over a rotated 2x2 grid of sub-pixel rays (geometric anti-aliasing). Photometric noise
// in DN: sigma^2 = (read_noise_e / e_per_dn)^2 + DN / e_per_dn (read + shot noise), Gaussian
// values from a fixed 4096-entry Box-Muller table indexed by a hash of (seed, frame, camera,
// pixel), then rounding and clamping to 8 bits. Truth for the left image: depth = camera-frame z of
// the hit of the pixel-centre ray, disparity = fx * baseline / depth (NaN where the ray misses).
// Calibration error: the true right camera may differ from the rectified rig the images are said
// to come from (Camera(), what the estimator is told): its centre at (baseline + baseline_error_m)
// along the left camera's x axis and its attitude world_R_left * Exp(right_rotation_error_rad).
// The truth disparity stays the calibrated rig's (fx * baseline / depth).
// Plain ground at one sample per pixel is computed in single precision, four pixels per 4-lane
// vector (texture position, footprint and noise arithmetic in float: the 8-bit values may differ
// from the double formulas above by 1 DN in rare pixels; the truth is the same).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/sim/appearance.hpp"
#include "swf/sim/rig.hpp"
#include "swf/sim/terrain.hpp"

namespace swf::sim {

// A dark Gaussian spot painted on the ground (a fiducial whose centre is a known landmark).
struct Fiducial {
  Eigen::Vector2d center_m{0.0, 0.0};
  double sigma_m = 0.1;
  double contrast = 0.8;  // radiance *= 1 - contrast * exp(-r^2 / (2 sigma^2))
};

struct RenderOptions {
  RigOptions rig = EdlRig();
  double exposure_dn = 110.0;
  bool add_noise = true;
  double read_noise_e = 15.0;
  double electrons_per_dn = 40.0;
  std::int32_t samples_per_pixel = 1;  // 1 or 4
  std::vector<Fiducial> fiducials;
  std::uint64_t seed = 1;
  // The true right camera against the calibrated rig (see above); zero: the rig exactly.
  double baseline_error_m = 0.0;
  Eigen::Vector3d right_rotation_error_rad{0.0, 0.0, 0.0};
};

struct StereoImages {
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::vector<std::uint8_t> left;
  std::vector<std::uint8_t> right;
  std::vector<float> depth_m;       // left camera, per pixel
  std::vector<float> disparity_px;  // left camera, per pixel
};

class Renderer {
 public:
  // kInvalidArgument for a bad rig, samples_per_pixel not 1 or 4, non-positive exposure or
  // electrons per DN, negative read noise, a fiducial with non-positive sigma, a true baseline
  // (rig's + error) that is not positive or a non-finite rotation error.
  core::Status Configure(const RenderOptions& options);

  // Renders one pair. `out` is resized on first use only (no allocation for later frames of the
  // same size). kNotConfigured before a successful Configure(); kInvalidArgument when the
  // appearance does not belong to a terrain of the same size.
  core::Status Render(const Terrain& terrain, const Appearance& appearance,
                      const estimator::Pose<double>& world_T_camera, std::uint64_t frame_index,
                      StereoImages* out) const;

  const estimator::StereoCamera<double>& Camera() const { return camera_; }

 private:
  // world_R_c, the centre of camera camera_index (0 left, 1 right) and its image.
  void RenderCamera(const Terrain& terrain, const Appearance& appearance, const Eigen::Matrix3d& r,
                    const Eigen::Vector3d& center, int camera_index, std::uint64_t frame_index,
                    StereoImages* out) const;
  double Shade(const Appearance& appearance, const Eigen::Vector3d& p, double footprint_m) const;

  RenderOptions options_;
  estimator::StereoCamera<double> camera_;
  std::vector<float> gaussian_table_;
  bool configured_ = false;
};

}  // namespace swf::sim
