// swf-eval euroc: the whole pipeline (rectification, front end, Sliding Window Filter) on a
// folder in EuRoC's ASL layout (DIR/mav0/cam0, DIR/mav0/cam1, each with data.csv, sensor.yaml
// and data/) with the ground truth as DIR/groundtruth_tum.txt (timestamp tx ty tz qx qy qz qw,
// world_T_body). The online estimate (newest pose after every frame's update) is compared with
// the ground truth after a rigid SE(3) alignment (Horn/Umeyama without scale).
#pragma once

#include <string>
#include <vector>

#include "swf/estimator/geometry.hpp"
#include "swf/estimator/sliding_window_filter.hpp"

namespace swf::eval {

using PoseD = estimator::Pose<double>;
using Vec3D = estimator::Vec3<double>;

// The rigid transform a_T_b minimising sum |a_i - (R b_i + t)|^2 (Horn / Umeyama, no scale).
// Needs at least 3 non-collinear points for a unique rotation; degenerate inputs still return a
// proper rotation (the SVD sign fix keeps det R = +1).
PoseD AlignRigid(const std::vector<Vec3D>& a, const std::vector<Vec3D>& b);

struct TumPose {
  double stamp_s = 0.0;
  PoseD pose;
};

bool ReadTum(const std::string& path, std::vector<TumPose>* poses, std::string* error);
bool WriteTum(const std::string& path, const std::vector<TumPose>& poses);

struct EurocOptions {
  int window = 5;                // poses in the window, for SWF and VO alike
  std::size_t max_tracks = 150;  // front end tracks (the prior's landmarks make S dense: keep
                                 // 3 * max_tracks + 6 * window moderate)
  double sigma_px = 0.5;         // measurement noise used by the estimator
  double motion_sigma_m = 0.05;  // constant-velocity process noise per frame
  double motion_sigma_rad = 0.02;
  bool predict = true;  // pass the estimator's predicted pose and landmarks to the front end
};

struct EurocRun {
  std::string name;  // "SWF(5)", "VO(5)"
  estimator::SwfMode mode = estimator::SwfMode::kSlidingWindow;
  std::vector<TumPose> estimate;  // world_T_body, world = first rectified camera
  std::vector<double> error_m;    // per frame, after alignment
  double ate_rmse_m = 0.0;
  double ate_max_m = 0.0;
  double final_error_m = 0.0;
  int update_failures = 0;
  double mean_measurements = 0.0;  // per frame, into the estimator
  double seconds = 0.0;            // wall time of the whole run
};

struct EurocResult {
  int frames = 0;
  double gt_path_length_m = 0.0;
  double gt_extent_m = 0.0;  // largest distance from the first ground-truth position
  double focal_px = 0.0;
  double baseline_m = 0.0;
  std::vector<TumPose> ground_truth;  // associated with the frames
  std::vector<EurocRun> runs;
};

// Runs SWF and VO (same window) on DIR. False with *error for missing or malformed input.
bool RunEuroc(const std::string& dir, const EurocOptions& options, EurocResult* result,
              std::string* error);

}  // namespace swf::eval
