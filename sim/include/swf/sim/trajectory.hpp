// Trajectory: the one parameterized motion model behind every simulated sequence.
//
// World frame: x east, y north, z up (metres); the terrain is the height field z = h(x, y).
// Frame k (k = 0 .. num_frames-1) is taken at time t_k = start_time + k / rate_hz with
//     position   p_k = start + velocity * (k / rate_hz)
//     attitude   world_R_camera_k = Rz(heading) * R_nadir * Exp(phi_k)
// where R_nadir points the camera straight down (camera x = world x, camera y = world -y,
// camera z = world -z) and phi_k is attitude jitter in the camera frame: a first-order
// Gauss-Markov sequence phi_k = a phi_k-1 + sqrt(1 - a^2) sigma n_k (stationary std sigma per
// axis, n_k standard normal from the seed). Presets below are parameter sets of this model, not
// separate code paths.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/core/time.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/sim/rig.hpp"

namespace swf::sim {

struct TrajectoryOptions {
  Eigen::Vector3d start_world_m{0.0, 0.0, 100.0};
  Eigen::Vector3d velocity_world_mps{0.0, 0.0, -10.0};
  double rate_hz = 15.0;
  std::int32_t num_frames = 136;
  double heading_rad = 0.0;
  double jitter_sigma_rad = 0.0;    // stationary std of each jitter axis
  double jitter_correlation = 0.9;  // a in [0, 1): frame-to-frame correlation of the jitter
  std::uint64_t seed = 1;
  core::TimeNs start_time_ns = 0;
};

// Paper section 4: descent from 100 m to 10 m at 10 m/s, rate_hz frames per second (10-15 Hz),
// 0.1 deg attitude jitter.
TrajectoryOptions DescentTrajectory(double rate_hz = 15.0);
// Paper Fig. 12: the cameras do not move (no jitter), num_frames frames at altitude_m.
TrajectoryOptions HoverTrajectory(double altitude_m = 50.0, std::int32_t num_frames = 60);
// Paper Fig. 15: sideways (along +x) at constant altitude; consecutive frames overlap by
// overlap_fraction of the image width of `rig` (the paper: ~85 %).
TrajectoryOptions SidewaysTrajectory(const RigOptions& rig, double altitude_m = 50.0,
                                     double overlap_fraction = 0.85, std::int32_t num_frames = 40);
// Paper section 4.2.2 lab experiment: 10 m to 1 m in 15 cm steps (61 frames).
TrajectoryOptions LabTrajectory(double rate_hz = 15.0);

class Trajectory {
 public:
  // kInvalidArgument for a non-positive rate, fewer than 1 or more than 1e6 frames, a jitter
  // correlation outside [0, 1), a negative jitter or non-finite vectors.
  core::Status Configure(const TrajectoryOptions& options);

  std::int32_t NumFrames() const { return static_cast<std::int32_t>(poses_.size()); }
  // Precondition: 0 <= k < NumFrames().
  const estimator::Pose<double>& WorldTCamera(std::int32_t k) const { return poses_[k]; }
  core::TimeNs FrameTimeNs(std::int32_t k) const;
  const TrajectoryOptions& Options() const { return options_; }

 private:
  TrajectoryOptions options_;
  std::vector<estimator::Pose<double>> poses_;
};

// Camera pointing straight down with the given heading (rotation about world z).
Eigen::Matrix3d NadirRotation(double heading_rad);

}  // namespace swf::sim
