#include "swf/sim/measurement.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "swf/sim/rng.hpp"

namespace swf::sim {
namespace {

struct Track {
  std::int32_t landmark_id;
  std::int32_t remaining;  // observations left; < 0 means unlimited
};

}  // namespace

core::Status MeasurementScenario::Configure(const MeasurementOptions& options) {
  frames_.clear();
  landmarks_world_.clear();
  summary_ = MeasurementSummary{};
  if (ValidateRig(options.rig) != core::Status::kOk) return core::Status::kInvalidArgument;
  if (options.features_per_frame < 0 || options.track_length_frames < 0 ||
      !(options.pixel_sigma_px >= 0.0) || !(options.outlier_fraction >= 0.0) ||
      !(options.outlier_fraction <= 1.0) || !(options.outlier_min_px >= 0.0) ||
      !(options.outlier_min_px <= options.outlier_max_px) || !(options.border_px >= 0.0) ||
      2.0 * options.border_px >= std::min(options.rig.width_px, options.rig.height_px) - 1 ||
      !(options.relief_wavelength_m > 0.0)) {
    return core::Status::kInvalidArgument;
  }
  if (trajectory_.Configure(options.trajectory) != core::Status::kOk) {
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  camera_ = MakeStereoCamera(options.rig);
  if (options.surface != nullptr) {
    own_surface_.reset();
    surface_ = options.surface;
  } else {
    own_surface_ = std::make_unique<PlaneWaveSurface>(
        options.surface_base_m, options.relief_amplitude_m, options.relief_wavelength_m);
    surface_ = own_surface_.get();
  }

  Rng rng(options.seed);
  std::vector<Track> live;
  std::vector<Track> next_live;
  const std::int32_t length = options.track_length_frames;
  const std::int32_t spread = length / 2;
  const double u_lo = options.border_px;
  const double u_hi = options.rig.width_px - 1 - options.border_px;
  const double v_lo = options.border_px;
  const double v_hi = options.rig.height_px - 1 - options.border_px;

  frames_.reserve(trajectory_.NumFrames());
  for (std::int32_t k = 0; k < trajectory_.NumFrames(); ++k) {
    MeasurementFrame frame;
    frame.index = k;
    frame.t_ns = trajectory_.FrameTimeNs(k);
    frame.world_T_camera = trajectory_.WorldTCamera(k);
    const estimator::Pose<double>& pose = frame.world_T_camera;

    next_live.clear();
    for (const Track& track : live) {
      Observation obs;
      if (track.remaining == 0 ||
          !Visible(pose, landmarks_world_[track.landmark_id], &obs.z_true)) {
        continue;  // the track ends for good
      }
      obs.landmark_id = track.landmark_id;
      frame.observations.push_back(obs);
      next_live.push_back({track.landmark_id, track.remaining > 0 ? track.remaining - 1 : -1});
    }
    live.swap(next_live);

    const std::int32_t max_attempts = 50 * options.features_per_frame + 50;
    for (std::int32_t attempt = 0;
         attempt < max_attempts &&
         static_cast<std::int32_t>(frame.observations.size()) < options.features_per_frame;
         ++attempt) {
      const double u = rng.Uniform(u_lo, u_hi);
      const double v = rng.Uniform(v_lo, v_hi);
      const Eigen::Vector3d ray_camera((u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy,
                                       1.0);
      const Eigen::Vector3d ray_world = pose.R * ray_camera;
      double t = 0.0;
      if (!surface_->Intersect(pose.t, ray_world, &t)) continue;
      const Eigen::Vector3d l_world = pose.t + t * ray_world;
      Observation obs;
      if (!Visible(pose, l_world, &obs.z_true)) continue;
      obs.landmark_id = static_cast<std::int32_t>(landmarks_world_.size());
      landmarks_world_.push_back(l_world);
      frame.observations.push_back(obs);
      ++frame.new_landmarks;
      std::int32_t remaining = -1;
      if (length > 0) {
        remaining = static_cast<std::int32_t>(
                        rng.UniformInt(std::max(1, length - spread), length + spread)) -
                    1;
      }
      live.push_back({obs.landmark_id, remaining});
    }

    for (Observation& obs : frame.observations) {
      obs.u_left_px = obs.z_true.x() + options.pixel_sigma_px * rng.Gaussian();
      obs.u_right_px = obs.z_true.y() + options.pixel_sigma_px * rng.Gaussian();
      obs.v_px = obs.z_true.z() + options.pixel_sigma_px * rng.Gaussian();
      // Always draw, so the outlier fraction does not change the noise of the inliers.
      const double draw = rng.Uniform();
      const double magnitude = rng.Uniform(options.outlier_min_px, options.outlier_max_px);
      const double angle = rng.Uniform(0.0, 2.0 * std::numbers::pi);
      const double disparity_error = rng.Uniform(-0.5, 0.5) * magnitude;
      if (draw < options.outlier_fraction) {
        obs.is_outlier = true;
        obs.u_left_px += magnitude * std::cos(angle);
        obs.v_px += magnitude * std::sin(angle);
        obs.u_right_px += magnitude * std::cos(angle) - disparity_error;
        ++summary_.num_outliers;
      }
    }
    summary_.num_observations += static_cast<std::int64_t>(frame.observations.size());
    frames_.push_back(std::move(frame));
  }
  summary_.num_frames = NumFrames();
  summary_.num_landmarks = static_cast<std::int32_t>(landmarks_world_.size());
  summary_.mean_features_per_frame =
      static_cast<double>(summary_.num_observations) / std::max(1, summary_.num_frames);
  summary_.mean_track_length_frames =
      static_cast<double>(summary_.num_observations) / std::max(1, summary_.num_landmarks);
  return core::Status::kOk;
}

bool MeasurementScenario::Visible(const estimator::Pose<double>& world_T_camera,
                                  const Eigen::Vector3d& l_world, Eigen::Vector3d* z) const {
  const Eigen::Vector3d p_camera = world_T_camera.ApplyInverse(l_world);
  if (!(p_camera.z() > 1e-3)) return false;
  *z = camera_.Project(p_camera);
  const double lo_u = options_.border_px;
  const double hi_u = options_.rig.width_px - 1 - options_.border_px;
  const double lo_v = options_.border_px;
  const double hi_v = options_.rig.height_px - 1 - options_.border_px;
  if (z->x() < lo_u || z->x() > hi_u || z->y() < lo_u || z->y() > hi_u || z->z() < lo_v ||
      z->z() > hi_v) {
    return false;
  }
  if (!options_.check_occlusion) return true;
  // Occlusion: the first surface hit along each camera's ray must be the landmark itself.
  const Eigen::Vector3d right_center =
      world_T_camera.Apply(Eigen::Vector3d(camera_.baseline_m, 0.0, 0.0));
  for (const Eigen::Vector3d& center : {world_T_camera.t, right_center}) {
    const Eigen::Vector3d ray = l_world - center;
    double t = 0.0;
    if (surface_->Intersect(center, ray, &t) && t < 1.0 - 1e-4) return false;
  }
  return true;
}

}  // namespace swf::sim
