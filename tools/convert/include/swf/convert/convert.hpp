// swf-convert: datasets into LCM logs swf-replay runs, and logs back out into images and
// trajectory files (docs/convert.md in tools/convert/README.md).
//
// In:  a EuRoC ASL folder, a KITTI odometry folder or swf-grab's PNG pairs become a log of raw
//      stereo_frame_t on SWF_STEREO (rectified = false: swf-replay rectifies them with the
//      calibration written beside the log), imu_t on SWF_IMU (EuRoC's imu0, each sample recorded
//      before the first frame at or after it, as the flight process records them) and the
//      ground truth as truth_state_t on GROUND_TRUTH (the rectified left camera, world = the
//      dataset's).
// Out: the stereo pairs of a log as PNG pairs; the navigation outputs (nav_state_t on SWF_NAV) of
//      a replay's recording as TUM (t tx ty tz qx qy qz qw) and KITTI (3x4 row-major) trajectory
//      files; the ATE of a TUM trajectory against a EuRoC folder's truth, computed by swf-eval's
//      own code (tools/eval trajectory.hpp).
// Every file is written to a temporary name and renamed, so a failed run leaves none half
// written. Errors name the file and line or record.
#pragma once

#include <cstdint>
#include <string>

namespace swf::convert {

struct InputSummary {
  std::int64_t frames = 0;
  std::int64_t imu_samples = 0;
  std::int64_t truth_poses = 0;
  int width = 0;
  int height = 0;
};

struct LogInputOptions {
  std::string log_path;  // the LCM log written
  std::string
      calib_dir;  // "" = none; else left.yaml / right.yaml (EuRoC sensor.yaml) for swf-replay
  double rate_hz = 10.0;  // swf-grab only: its PNG names carry no time, only the sequence number
  int max_frames = 0;     // > 0: only the first max_frames frames (and the IMU up to the last)
};

bool EurocToLog(const std::string& dir, const LogInputOptions& options, InputSummary* summary,
                std::string* error);
bool KittiToLog(const std::string& dir, const LogInputOptions& options, InputSummary* summary,
                std::string* error);
// swf-grab's left_NNNNNN.png / right_NNNNNN.png (NNNNNN = the pair's sequence number; a missing
// number is a pair the camera dropped, recorded in the next frame's dropped_before).
bool GrabToLog(const std::string& dir, const LogInputOptions& options, InputSummary* summary,
               std::string* error);

// The stereo pairs on `channel` as OUT/left_NNNNNN.png and OUT/right_NNNNNN.png (NNNNNN = seq).
bool LogToPngs(const std::string& log_path, const std::string& channel, const std::string& out_dir,
               std::int64_t* pairs, std::string* error);

// nav_state_t on `channel` as TUM and/or KITTI trajectory files ("" = not written), in the run's
// world frame, or with `anchor_first` in the first output's camera frame (KITTI's convention:
// the first pose is the identity).
bool LogToTrajectory(const std::string& log_path, const std::string& channel,
                     const std::string& tum_path, const std::string& kitti_path, bool anchor_first,
                     std::int64_t* poses, std::string* error);

struct AteResult {
  int matched = 0;  // TUM poses matched to a EuRoC frame (within 1 ms)
  double ate_rmse_m = 0.0;
  double ate_max_m = 0.0;
};
// The ATE of a TUM trajectory of the rectified left camera against a EuRoC folder's ground truth
// as swf-eval computes it (eval::ScoreTrajectory: SE(3) fit, no scale, all matched frames).
bool TumAteAgainstEuroc(const std::string& tum_path, const std::string& euroc_dir,
                        AteResult* result, std::string* error);

}  // namespace swf::convert
