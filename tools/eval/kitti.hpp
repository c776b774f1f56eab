// swf-eval kitti: the flight pipeline (swf::app::Pipeline, frames already rectified) on a folder
// in the KITTI odometry layout: image_0/NNNNNN.png (left), image_1/NNNNNN.png (right),
// calib.txt (row-major 3x4 projection matrices P0 and P1, optionally labelled "P0:"), poses.txt
// (one row-major 3x4 world_T_camera of the left camera per frame, world = the first camera).
// No motion input: the pipeline's constant-velocity process model carries the pose between
// frames. Frames are taken at 10 Hz (KITTI's rate; the excerpt has no times.txt).
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "sequence.hpp"

namespace swf::eval {

// The runs' defaults on KITTI: more tracks, a car's process noise (0.5 m per frame: it changes
// speed and heading slowly) and a 10 m anchored error before a run is called diverged.
inline RunOptions KittiRunOptions() {
  RunOptions o;
  o.max_tracks = 300;
  o.process_sigma_m = 0.5;
  o.divergence_m = 10.0;
  return o;
}

struct KittiOptions {
  RunOptions run = KittiRunOptions();  // for SWF and VO alike (name, mode unset)
  int max_frames = 0;                  // > 0: only the first max_frames frames
};

struct KittiResult {
  StereoSequence sequence;
  double gt_path_length_m = 0.0;
  std::vector<RunRecord> runs;         // SWF(window), VO(window)
  std::vector<RunRecord> diagnostics;  // DiagnoseFailures(runs)
};

// P0/P1 from calib.txt into the rectified rig: f, cx, cy from P0, baseline = -P1[0,3] / P1[0,0].
// Refused, naming path:line: a line that is not 12 finite numbers, fewer than two matrices,
// P0/P1 that are not a rectified pair, a baseline that is not positive.
bool ReadKittiCalibration(const std::string& path, estimator::StereoCamera<double>* camera,
                          std::string* error);
// Refused, naming path:line: a line that is not 12 finite numbers or whose 3x3 part is not a
// rotation; fewer than 3 poses.
bool ReadKittiPoses(const std::string& path, std::vector<PoseD>* poses, std::string* error);
// The same from streams (the fuzz harness reads from memory); `path` names them in messages.
bool ParseKittiCalibration(std::istream& in, const std::string& path,
                           estimator::StereoCamera<double>* camera, std::string* error);
bool ParseKittiPoses(std::istream& in, const std::string& path, std::vector<PoseD>* poses,
                     std::string* error);

// LoadKitti refuses a baseline above this (a car's rig is about half a metre): a calib.txt in
// millimetres would otherwise pass.
inline constexpr double kMaxKittiBaselineM = 10.0;

// Reads DIR. Besides the files' own checks: the first left and right images must have the same
// size, and calib.txt must meet CheckCalibration's bounds (euroc.hpp) over that size.
bool LoadKitti(const std::string& dir, const KittiOptions& options, KittiResult* result,
               std::string* error);

// LoadKitti, then SWF and VO with the same window. False only for unusable input.
bool RunKitti(const std::string& dir, const KittiOptions& options, KittiResult* result,
              std::string* error);

}  // namespace swf::eval
