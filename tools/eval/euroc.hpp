// swf-eval euroc: the flight pipeline (rectification, front end, Sliding Window Filter) on a
// folder in EuRoC's ASL layout (DIR/mav0/cam0, DIR/mav0/cam1, each with data.csv, sensor.yaml
// and data/) with the ground truth as DIR/groundtruth_tum.txt (timestamp tx ty tz qx qy qz qw,
// world_T_body). Inputs are checked before anything runs: the two image lists must pair line by
// line with equal timestamps (a list shifted by one frame is refused, naming the line), image
// names must stay inside data/, and each calibration must be one that can be rectified over the
// whole image. Optionally the recorded frames are looped (ping-pong) into a longer sequence with
// monotonic timestamps, a stress case for a camera at rest.
#pragma once

#include <cstdint>
#include <istream>
#include <string>
#include <vector>

#include "sequence.hpp"
#include "trajectory.hpp"

namespace swf::eval {

struct TumPose {
  double stamp_s = 0.0;
  PoseD pose;
};

bool ReadTum(const std::string& path, std::vector<TumPose>* poses, std::string* error);
bool WriteTum(const std::string& path, const std::vector<TumPose>& poses);

// Bounds a calibration must meet to be believed (CheckCalibration; KITTI's calib.txt too).
inline constexpr double kMinFieldOfViewDeg = 1.0;         // horizontal, from fx and the width
inline constexpr double kMaxFieldOfViewDeg = 170.0;       // wider needs a fisheye model
inline constexpr double kMaxPixelAspect = 1.5;            // fx / fy and fy / fx
inline constexpr double kMaxRadialCoefficient = 5.0;      // |k1|, |k2|, |k3|
inline constexpr double kMaxTangentialCoefficient = 0.1;  // |p1|, |p2|

// False with *error naming `path` and the field when the calibration cannot describe a real
// camera over its image: focal lengths not positive or implausible (a horizontal field of view
// outside kMinFieldOfViewDeg..kMaxFieldOfViewDeg, pixels more than kMaxPixelAspect from square),
// principal point outside the image, distortion coefficients beyond the bounds above, or a
// radial distortion that folds back (stops growing with the radius) before the image corners.
bool CheckCalibration(const frontend::CameraCalibration& c, const std::string& path,
                      std::string* error);

// False with *error when `name` (an image file name from a list) is absolute, has a ".."
// component or a control character: the lists may only name files inside their data folder.
bool CheckImageName(const std::string& name, std::string* error);

// One line of an ASL data.csv: the image's timestamp and file name.
struct ListedImage {
  std::int64_t stamp_ns = 0;
  std::string name;
  int line = 0;  // in the list (1-based), for messages
};

// Reads an ASL image list ("timestamp_ns,filename" per line, '#' comments). Refused, naming
// path:line: a malformed line, a name CheckImageName refuses, a numeric file name that is not
// the line's timestamp (a list shifted against its files), timestamps that do not increase, and
// a list without frames.
bool ParseImageList(std::istream& csv, const std::string& path, std::vector<ListedImage>* frames,
                    std::string* error);

struct EurocOptions {
  RunOptions run;  // window, tracks, noise and divergence for SWF and VO alike (name, mode unset)
  // > 0: loop the recorded frames forwards and backwards into this many seconds.
  double loop_seconds = 0.0;
};

struct EurocResult {
  StereoSequence sequence;  // the frames run (looped when asked)
  int recorded_frames = 0;  // frames with both images and ground truth
  int skipped_frames = 0;   // listed frames without ground truth within 5 ms
  double frame_interval_s = 0.0;
  double gt_path_length_m = 0.0;       // of the recorded frames
  double gt_extent_m = 0.0;            // largest distance from the first ground-truth position
  std::vector<RunRecord> runs;         // SWF(window), VO(window)
  std::vector<RunRecord> diagnostics;  // DiagnoseFailures(runs)
};

// Reads DIR into a sequence (truth: the rectified left camera, world = the ground truth's).
bool LoadEuroc(const std::string& dir, const EurocOptions& options, EurocResult* result,
               std::string* error);

// LoadEuroc, then SWF and VO (same window). False with *error only for unusable input; a run
// that fails (diverged, no measurements) is in its RunRecord's verdict.
bool RunEuroc(const std::string& dir, const EurocOptions& options, EurocResult* result,
              std::string* error);

}  // namespace swf::eval
