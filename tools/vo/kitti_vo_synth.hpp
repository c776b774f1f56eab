// A deterministic generator of kitti-vo problems with the statistics of a real one, and a writer
// of the kitti-vo text format. The default statistics are those of the KITTI sequence-00 excerpt
// users solve with swf-vo (77 poses, 15,638 landmarks, 52,544 stereo factors, ~680 per pose), so
// tests and benchmarks can exercise that size without the data set.
//
// The scene: a car-like path (camera x right, y down, z forward; ~1 m between poses, a gentle
// curve, small pitch/roll), landmarks placed in front of the camera that first sees them at
// log-uniform depths, each seen from a run of consecutive poses (2 + a geometric number, capped;
// lengths adjusted so the factor count is exact) while it stays in the image. Runs are placed so
// every pose sees about the same number of factors, as in a real sequence where every frame has a
// full image of features. Measurements are the true projections plus Gaussian pixel noise (sigma
// 1 px on uL, uR and v); initial poses drift from the truth by a random walk per step, as
// visual-odometry estimates do (the first pose, the gauge, is exact). Initial landmarks are the
// solvers' own stereo initializations from these measurements.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kitti_vo.hpp"

namespace swf::tools {

struct KittiLikeOptions {
  int poses = 77;
  int landmarks = 15638;
  int observations = 52544;  // exact; at least 2 and at most max_track per landmark
  int max_track = 15;        // poses one landmark is seen from, at most
  double step_m = 1.0;       // mean distance between poses
  double pixel_sigma = 1.0;
  double drift_sigma_m = 0.01;     // initial estimates: random-walk error per step, per axis
  double drift_sigma_rad = 0.001;  // (rotation, radians per axis)
  double min_depth_m = 4.0;        // depth where a landmark is first seen (log-uniform)
  double max_depth_m = 70.0;
  int width_px = 1241;  // KITTI-00 image size
  int height_px = 376;
  std::uint64_t seed = 1;
};

// Fills *problem (factors grouped by pose, lines numbered as WriteKittiVo writes them) and, when
// truth is not null, the true camera-to-world poses. False with *error when the options are
// inconsistent (e.g. more observations than landmarks x max_track) or a landmark cannot be placed.
bool GenerateKittiLike(const estimator::StereoCamera<double>& camera,
                       const KittiLikeOptions& options, KittiVoProblem* problem,
                       std::vector<estimator::Pose<double>>* truth, std::string* error);

// Writes the three kitti-vo files (full precision). Factors are written landmark by landmark, as
// in the data set; X Y Z is the stereo triangulation of the measurement in its camera's frame.
bool WriteKittiVo(const KittiVoProblem& problem, const std::string& calib_path,
                  const std::string& poses_path, const std::string& factors_path,
                  std::string* error);

}  // namespace swf::tools
