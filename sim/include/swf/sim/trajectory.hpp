// Trajectory: the one parameterized motion model behind every simulated sequence.
//
// World frame: x east, y north, z up (metres); the terrain is the height field z = h(x, y).
// Frame k (k = 0 .. num_frames-1) is taken at time t_k = start_time + k / rate_hz, tau_k = k /
// rate_hz after the start, with
//     position   p_k = start + velocity * tau_k
//     attitude   world_R_camera_k = S(tau_k) * Exp(phi_k)
//                S(tau) = Rz(heading) * R_nadir * A * Exp(omega tau)
// where R_nadir points the camera straight down (camera x = world x, camera y = world -y,
// camera z = world -z), A = Rz(yaw) Ry(pitch) Rx(roll) is a constant attitude offset about the
// camera's own axes (roll about x, pitch about y, yaw about the optical axis z), omega a constant
// body rate in the camera frame (the offset grows linearly with time: S's angular velocity in its
// own frame is exactly omega), and phi_k is attitude jitter in the camera frame: a first-order
// Gauss-Markov sequence phi_k = a phi_k-1 + sqrt(1 - a^2) sigma n_k (stationary std sigma per
// axis, n_k standard normal from the seed). S is the steered attitude without jitter
// (SteeredAttitude); the velocity is constant, so the camera never accelerates. Presets below are
// parameter sets of this model, not separate code paths.
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
  Eigen::Vector3d attitude_offset_rad{0.0, 0.0, 0.0};  // roll, pitch, yaw of A (camera axes)
  Eigen::Vector3d body_rate_radps{0.0, 0.0, 0.0};      // omega, camera frame
  double jitter_sigma_rad = 0.0;                       // stationary std of each jitter axis
  double jitter_correlation = 0.9;  // a in [0, 1): frame-to-frame correlation of the jitter
  std::uint64_t seed = 1;
  core::TimeNs start_time_ns = 0;
};

// Paper section 4: descent from 100 m to 10 m at 10 m/s, rate_hz frames per second (10-15 Hz),
// 0.1 deg attitude jitter. Other altitudes and rates: (start - end) / rate seconds, both ends
// included (the last frame is the one nearest end_altitude_m on the frame grid).
TrajectoryOptions DescentTrajectory(double rate_hz = 15.0, double start_altitude_m = 100.0,
                                    double end_altitude_m = 10.0, double descent_rate_mps = 10.0);
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
  // correlation outside [0, 1), a negative jitter or non-finite vectors or angles.
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

// A = Rz(yaw) Ry(pitch) Rx(roll) for roll_pitch_yaw_rad = (roll, pitch, yaw).
Eigen::Matrix3d AttitudeOffset(const Eigen::Vector3d& roll_pitch_yaw_rad);

// S(tau): world_R_camera without jitter, tau_s seconds after the trajectory's start. The one
// definition the frames and the simulated IMU (imu_model.hpp) share.
Eigen::Matrix3d SteeredAttitude(const TrajectoryOptions& options, double tau_s);

}  // namespace swf::sim
