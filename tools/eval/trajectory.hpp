// Trajectory error measures of swf-eval, on camera poses (world_T_camera) of an estimate and its
// ground truth, frame by frame:
//  * ATE: position RMSE after the rigid SE(3) fit of the estimate onto the truth (Horn/Umeyama,
//    no scale) over all frames;
//  * anchored error: both trajectories expressed in their own first frame, no fit (what an
//    onboard user of the estimate sees; used to call a run diverged);
//  * relative error (KITTI-style, per frame-to-frame motion): the translation and rotation of
//    truth_step^-1 * estimate_step.
#pragma once

#include <string>
#include <vector>

#include "swf/estimator/geometry.hpp"

namespace swf::eval {

using PoseD = estimator::Pose<double>;
using Vec3D = estimator::Vec3<double>;

// The rigid transform a_T_b minimising sum |a_i - (R b_i + t)|^2 (Horn / Umeyama, no scale).
// Needs at least 3 non-collinear points for a unique rotation; degenerate inputs still return a
// proper rotation (the SVD sign fix keeps det R = +1).
PoseD AlignRigid(const std::vector<Vec3D>& a, const std::vector<Vec3D>& b);

bool IsFinite(const PoseD& pose);

struct TrajectoryErrors {
  // False when an estimated pose is not finite: then nothing below is computed (all NaN) and
  // `reason` says which frame.
  bool finite = false;
  std::string reason;
  std::vector<double> aligned_error_m;           // per frame, after the SE(3) fit
  std::vector<double> anchored_error_m;          // per frame, no fit
  std::vector<double> step_translation_error_m;  // per motion j-1 -> j (first entry: frame 1)
  std::vector<double> step_rotation_error_deg;
  double ate_rmse_m = 0.0;
  double ate_max_m = 0.0;
  double final_aligned_error_m = 0.0;
  double final_anchored_error_m = 0.0;
  double max_anchored_error_m = 0.0;
  double truth_path_m = 0.0;  // sum of the true step lengths
  // Relative errors, KITTI-style: mean and largest per step, and the summed translation error
  // over the summed true path (percent; NaN when the truth moved less than 1 cm).
  double step_translation_mean_m = 0.0;
  double step_translation_max_m = 0.0;
  double step_rotation_mean_deg = 0.0;
  double step_rotation_max_deg = 0.0;
  double step_translation_percent = 0.0;
  double step_rotation_deg_per_m = 0.0;  // summed rotation error over the true path
};

// truth and estimate: world_T_camera per frame, same length >= 2 (each in its own world frame).
TrajectoryErrors ScoreTrajectory(const std::vector<PoseD>& truth,
                                 const std::vector<PoseD>& estimate);

}  // namespace swf::eval
