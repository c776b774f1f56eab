// MeasurementScenario: measurement-level simulation for the estimator and the evaluation. True
// landmarks lie on a surface; each frame observes them through the rectified stereo model of
// estimator/geometry.hpp with Gaussian pixel noise and a controllable fraction of gross outliers,
// with every truth kept alongside.
//
// Per frame k (pose from the shared Trajectory model, trajectory.hpp):
//   1. every live track whose landmark is still visible (inside both images with a border, in
//      front of the camera, not occluded by the surface) and has not reached its length is
//      observed again; the others end for good (a landmark is never re-observed after a gap);
//   2. new landmarks are spawned where a uniformly drawn left-image pixel's ray meets the
//      surface, until features_per_frame observations exist (or a bounded number of attempts);
//   3. each observation z = (uL, uR, v) = Project(p_camera) + sigma_px * n (independent N(0, 1)
//      per component); with probability outlier_fraction it is instead displaced by a gross
//      error of outlier_min_px .. outlier_max_px (random direction in (uL, v), the disparity
//      perturbed by up to half that) and flagged is_outlier.
// Track lengths (frames a landmark is observed) are drawn uniformly from
// [L - L/2, L + L/2] (mean L = track_length_frames); 0 means unlimited (paper Fig. 13: the same
// features tracked throughout). Everything is generated in Configure(), deterministically.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/core/time.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/sim/rig.hpp"
#include "swf/sim/surface.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sim {

struct MeasurementOptions {
  TrajectoryOptions trajectory = DescentTrajectory();
  RigOptions rig = EdlRig();
  // Landmarks lie on this surface (not owned; must outlive Configure()). Null: the analytic
  // PlaneWaveSurface(surface_base_m, relief_amplitude_m, relief_wavelength_m).
  const Surface* surface = nullptr;
  double surface_base_m = 0.0;
  double relief_amplitude_m = 0.0;
  double relief_wavelength_m = 20.0;

  std::int32_t features_per_frame = 20;   // target observations per frame
  std::int32_t track_length_frames = 10;  // mean track length; 0 = unlimited
  double pixel_sigma_px = 0.5;            // paper Fig. 14: 0.5 px
  double outlier_fraction = 0.0;          // in [0, 1]
  double outlier_min_px = 5.0;
  double outlier_max_px = 50.0;
  double border_px = 8.0;  // observations keep this far inside both images
  bool check_occlusion = true;
  std::uint64_t seed = 1;
};

struct Observation {
  std::int32_t landmark_id = -1;  // index into MeasurementScenario::Landmarks()
  double u_left_px = 0.0;         // noisy (or outlier) measurement
  double u_right_px = 0.0;
  double v_px = 0.0;
  bool is_outlier = false;
  Eigen::Vector3d z_true{0.0, 0.0, 0.0};  // noise-free (uL, uR, v)
};

struct MeasurementFrame {
  std::int32_t index = 0;
  core::TimeNs t_ns = 0;
  estimator::Pose<double> world_T_camera;  // truth
  std::vector<Observation> observations;
  std::int32_t new_landmarks = 0;  // observations of landmarks first seen in this frame
};

struct MeasurementSummary {
  std::int32_t num_frames = 0;
  std::int32_t num_landmarks = 0;
  std::int64_t num_observations = 0;
  std::int64_t num_outliers = 0;
  double mean_features_per_frame = 0.0;
  double mean_track_length_frames = 0.0;  // observations per landmark
};

class MeasurementScenario {
 public:
  // kInvalidArgument for bad options (rig, trajectory, negative counts or sigmas, an outlier
  // fraction outside [0, 1], outlier_min_px > outlier_max_px, a border that leaves no image).
  core::Status Configure(const MeasurementOptions& options);

  std::int32_t NumFrames() const { return static_cast<std::int32_t>(frames_.size()); }
  // Precondition: 0 <= k < NumFrames().
  const MeasurementFrame& Frame(std::int32_t k) const { return frames_[k]; }
  // True landmark positions, world frame, indexed by Observation::landmark_id.
  const std::vector<Eigen::Vector3d>& Landmarks() const { return landmarks_world_; }
  const estimator::StereoCamera<double>& Camera() const { return camera_; }
  const Trajectory& Path() const { return trajectory_; }
  const MeasurementSummary& Summary() const { return summary_; }

 private:
  bool Visible(const estimator::Pose<double>& world_T_camera, const Eigen::Vector3d& l_world,
               Eigen::Vector3d* z) const;

  MeasurementOptions options_;
  std::unique_ptr<Surface> own_surface_;
  const Surface* surface_ = nullptr;
  Trajectory trajectory_;
  estimator::StereoCamera<double> camera_;
  std::vector<Eigen::Vector3d> landmarks_world_;
  std::vector<MeasurementFrame> frames_;
  MeasurementSummary summary_;
};

}  // namespace swf::sim
