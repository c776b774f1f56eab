#include "swf/sim/trajectory.hpp"

#include <cmath>
#include <numbers>

#include "swf/sim/rng.hpp"

namespace swf::sim {

TrajectoryOptions DescentTrajectory(double rate_hz) {
  TrajectoryOptions o;
  o.start_world_m = {0.0, 0.0, 100.0};
  o.velocity_world_mps = {0.0, 0.0, -10.0};
  o.rate_hz = rate_hz;
  // 90 m at 10 m/s = 9 s; both ends included.
  o.num_frames = static_cast<std::int32_t>(std::lround(9.0 * rate_hz)) + 1;
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

core::Status Trajectory::Configure(const TrajectoryOptions& options) {
  poses_.clear();
  if (!(options.rate_hz > 0.0) || !std::isfinite(options.rate_hz) || options.num_frames < 1 ||
      options.num_frames > 1000000 || !(options.jitter_correlation >= 0.0) ||
      !(options.jitter_correlation < 1.0) || !(options.jitter_sigma_rad >= 0.0) ||
      !options.start_world_m.allFinite() || !options.velocity_world_mps.allFinite() ||
      !std::isfinite(options.heading_rad)) {
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  Rng rng(options.seed);
  const Eigen::Matrix3d base = NadirRotation(options.heading_rad);
  const double a = options.jitter_correlation;
  const double innovation = std::sqrt(1.0 - a * a) * options.jitter_sigma_rad;
  Eigen::Vector3d phi = Eigen::Vector3d::Zero();
  poses_.reserve(options.num_frames);
  for (std::int32_t k = 0; k < options.num_frames; ++k) {
    const Eigen::Vector3d n(rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
    phi = (k == 0) ? Eigen::Vector3d(options.jitter_sigma_rad * n)
                   : Eigen::Vector3d(a * phi + innovation * n);
    estimator::Pose<double> pose;
    pose.R = base * estimator::ExpSO3<double>(phi);
    pose.t = options.start_world_m + options.velocity_world_mps * (k / options.rate_hz);
    poses_.push_back(pose);
  }
  return core::Status::kOk;
}

core::TimeNs Trajectory::FrameTimeNs(std::int32_t k) const {
  return options_.start_time_ns +
         static_cast<core::TimeNs>(std::llround(k * 1e9 / options_.rate_hz));
}

}  // namespace swf::sim
