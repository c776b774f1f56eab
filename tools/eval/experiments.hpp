// swf-eval's experiments that are also checked, in reduced form, by the test suite:
// NEES consistency over Monte Carlo runs and the map-MSE study of Fig. 16 (track length against
// window size). swf_eval.cpp writes their JSON, plot data and results.md text.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "run_filter.hpp"

namespace swf::eval {

// Quantile of the chi-square distribution with `dof` degrees of freedom (Wilson-Hilferty: off by
// about 1% at dof = 10 in the lower tail, below 1e-4 at dof = 150, the smallest bound swf-eval
// reports with 50 runs).
double ChiSquareQuantile(double p, double dof);

struct NeesOptions {
  SceneOptions scene;  // seed is replaced per run
  estimator::SwfMode mode = estimator::SwfMode::kSlidingWindow;
  int window = 5;
  int runs = 50;
  int hold_sightings = 0;             // SwfOptions::hold_sightings
  double hold_depth_precision = 0.0;  // SwfOptions::hold_depth_precision
};

struct NeesResult {
  std::string name;
  int runs = 0;
  // Per frame, averaged over the runs: NEES of the newest pose (6 dof) and the mean NEES of the
  // active landmarks (3 dof, first averaged over the landmarks of one run).
  std::vector<double> pose_nees;
  std::vector<double> landmark_nees;
  // Two-sided 95% bounds of the run average of a chi-square(dof) variable: chi2(dof * runs) /
  // runs. For the landmark average they are conservative (averaging correlated landmarks inside
  // a run leaves the mean at 3 and can only shrink the spread).
  double pose_lower = 0.0;
  double pose_upper = 0.0;
  double landmark_lower = 0.0;
  double landmark_upper = 0.0;
  // Averages over frames 2..end (frame 1 is the first-pose prior plus stereo initialization).
  double mean_pose_nees = 0.0;
  double mean_landmark_nees = 0.0;
  double pose_fraction_inside = 0.0;  // frames whose run average lies inside the bounds
  double landmark_fraction_inside = 0.0;
  // At the last frame: RMS over the runs of the newest pose's position error along x, y, z
  // (metres) and the mean of its stated standard deviations (the covariance's, in the pose's
  // update coordinates).
  double final_error_m[3] = {0.0, 0.0, 0.0};
  double final_sigma_m[3] = {0.0, 0.0, 0.0};
  // Poses in the window after each Update, mean and largest over all frames and runs (more
  // than the window size only with hold_sightings).
  double mean_poses = 0.0;
  int max_poses = 0;
  int covariance_failures = 0;  // ComputeCovariances errors or non-SPD blocks (skipped)
  int update_failures = 0;
};

NeesResult RunNees(const std::string& name, const NeesOptions& options);

struct TrackLengthPoint {
  double step_m = 0.0;
  double mean_track_length = 0.0;  // observations per landmark, measured on the scenes
  double mean_features_per_frame = 0.0;
  std::vector<int> windows;
  std::vector<double> final_mse_m2;  // per window, averaged over the runs
};

struct TrackLengthOptions {
  std::vector<double> steps_m = {7.4, 4.4, 2.8, 1.85, 1.1};
  std::vector<int> windows = {2, 3, 5, 10, 20};
  int frames = 40;
  int runs = 5;
};

// Fig. 16: sideways flight at 50 m over ~30 features per frame; the step between frames sets the
// average track length. Final map MSE (every landmark ever seen) for each window size.
std::vector<TrackLengthPoint> RunTrackLengthStudy(const TrackLengthOptions& options);

}  // namespace swf::eval
