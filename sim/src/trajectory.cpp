#include "swf/sim/trajectory.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "swf/sim/rng.hpp"

namespace swf::sim {

TrajectoryOptions DescentTrajectory(double rate_hz, double start_altitude_m, double end_altitude_m,
                                    double descent_rate_mps) {
  TrajectoryOptions o;
  o.start_world_m = {0.0, 0.0, start_altitude_m};
  o.velocity_world_mps = {0.0, 0.0, -descent_rate_mps};
  o.rate_hz = rate_hz;
  // 90 m at 10 m/s = 9 s; both ends included. A count beyond any trajectory's (or not a number)
  // becomes 0 frames, which Configure refuses, instead of overflowing the conversion.
  const double intervals = (start_altitude_m - end_altitude_m) / descent_rate_mps * rate_hz;
  o.num_frames = intervals >= 0.0 && intervals < 1e9
                     ? static_cast<std::int32_t>(std::lround(intervals)) + 1
                     : 0;
  o.jitter_sigma_rad = 0.1 * std::numbers::pi / 180.0;
  return o;
}

TrajectoryOptions HoverTrajectory(double altitude_m, std::int32_t num_frames) {
  TrajectoryOptions o;
  o.start_world_m = {0.0, 0.0, altitude_m};
  o.velocity_world_mps = Eigen::Vector3d::Zero();
  o.num_frames = num_frames;
  o.jitter_sigma_rad = 0.0;
  return o;
}

TrajectoryOptions SidewaysTrajectory(const RigOptions& rig, double altitude_m,
                                     double overlap_fraction, std::int32_t num_frames) {
  TrajectoryOptions o;
  const double half_fov_rad = 0.5 * rig.horizontal_fov_deg * std::numbers::pi / 180.0;
  const double footprint_m = 2.0 * altitude_m * std::tan(half_fov_rad);
  const double step_m = (1.0 - overlap_fraction) * footprint_m;
  o.start_world_m = {-0.5 * step_m * (num_frames - 1), 0.0, altitude_m};
  o.velocity_world_mps = {step_m * o.rate_hz, 0.0, 0.0};
  o.num_frames = num_frames;
  o.jitter_sigma_rad = 0.05 * std::numbers::pi / 180.0;
  return o;
}

TrajectoryOptions LabTrajectory(double rate_hz) {
  TrajectoryOptions o;
  o.start_world_m = {0.0, 0.0, 10.0};
  o.velocity_world_mps = {0.0, 0.0, -0.15 * rate_hz};
  o.rate_hz = rate_hz;
  o.num_frames = 61;  // 10 m - 60 * 0.15 m = 1 m
  o.jitter_sigma_rad = 0.0;
  return o;
}

Eigen::Matrix3d NadirRotation(double heading_rad) {
  Eigen::Matrix3d nadir;
  // Columns: camera x, y, z axes expressed in the world frame.
  nadir << 1.0, 0.0, 0.0,  //
      0.0, -1.0, 0.0,      //
      0.0, 0.0, -1.0;
  const Eigen::Matrix3d rz =
      Eigen::AngleAxisd(heading_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return rz * nadir;
}

Eigen::Matrix3d AttitudeOffset(const Eigen::Vector3d& roll_pitch_yaw_rad) {
  const Eigen::Vector3d& a = roll_pitch_yaw_rad;
  return (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Matrix3d SteeredAttitude(const TrajectoryOptions& options, double tau_s) {
  const Eigen::Matrix3d base = NadirRotation(options.heading_rad);
  // Without offset and rate the nadir attitude itself, not a product with identities that could
  // flip the sign of a zero: the preset trajectories keep their bits.
  if ((options.attitude_offset_rad.array() == 0.0).all() &&
      (options.body_rate_radps.array() == 0.0).all()) {
    return base;
  }
  return base * AttitudeOffset(options.attitude_offset_rad) *
         estimator::ExpSO3<double>(Eigen::Vector3d(options.body_rate_radps * tau_s));
}

core::Status Trajectory::Configure(const TrajectoryOptions& options) {
  poses_.clear();
  if (!(options.rate_hz > 0.0) || !std::isfinite(options.rate_hz) || options.num_frames < 1 ||
      options.num_frames > 1000000 || !(options.jitter_correlation >= 0.0) ||
      !(options.jitter_correlation < 1.0) || !(options.jitter_sigma_rad >= 0.0) ||
      !options.start_world_m.allFinite() || !options.velocity_world_mps.allFinite() ||
      !std::isfinite(options.heading_rad) || !options.attitude_offset_rad.allFinite() ||
      !options.body_rate_radps.allFinite()) {
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  Rng rng(options.seed);
  const double a = options.jitter_correlation;
  const double innovation = std::sqrt(1.0 - a * a) * options.jitter_sigma_rad;
  Eigen::Vector3d phi = Eigen::Vector3d::Zero();
  poses_.reserve(options.num_frames);
  for (std::int32_t k = 0; k < options.num_frames; ++k) {
    const Eigen::Vector3d n(rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
    phi = (k == 0) ? Eigen::Vector3d(options.jitter_sigma_rad * n)
                   : Eigen::Vector3d(a * phi + innovation * n);
    const double tau_s = k / options.rate_hz;
    estimator::Pose<double> pose;
    pose.R = SteeredAttitude(options, tau_s) * estimator::ExpSO3<double>(phi);
    pose.t = options.start_world_m + options.velocity_world_mps * tau_s;
    poses_.push_back(pose);
  }
  return core::Status::kOk;
}

core::TimeNs Trajectory::FrameTimeNs(std::int32_t k) const {
  return options_.start_time_ns +
         static_cast<core::TimeNs>(std::llround(k * 1e9 / options_.rate_hz));
}

}  // namespace swf::sim
