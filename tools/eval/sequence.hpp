// A stereo image sequence with ground truth, run through the flight pipeline
// (swf::app::Pipeline: rectification when the cameras are raw, front end, Sliding Window Filter
// with the constant-velocity process model, navigation output), so that what swf-eval scores is
// the code that flies. Dataset readers (euroc.hpp, kitti.hpp) build a StereoSequence; RunSequence
// runs it once per estimator configuration and records every frame, and says in words why a run
// is not to be trusted (an input the pipeline refused, a non-finite or diverged estimate, frames
// without a single tracked measurement).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/app/pipeline.hpp"
#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/frontend/rectify.hpp"
#include "trajectory.hpp"

namespace swf::eval {

struct SequenceFrame {
  std::string left_path;
  std::string right_path;
  std::int64_t stamp_ns = 0;
  PoseD truth;         // world_T_camera of the (rectified) left camera, truth's world frame
  int source = 0;      // index of the recorded frame shown (differs when the sequence loops)
  std::string record;  // where the frame was listed, for messages ("cam0/data.csv:7")
};

struct StereoSequence {
  std::string name;  // "EuRoC V1_01", "KITTI odometry excerpt"
  std::string dir;
  // Raw cameras (rectified by the pipeline) or already rectified images with `camera`.
  bool rectify = false;
  frontend::CameraCalibration calibration[2];
  estimator::StereoCamera<double> camera;  // the rectified rig (filled in for raw cameras too)
  int width = 0;  // image size the pipeline receives (raw size when rectifying)
  int height = 0;
  // The vertical in the estimate's world (the first camera's frame), for the pipeline's
  // horizontal/vertical protection levels and to split the error the same way.
  Vec3D up_world = Vec3D(0.0, -1.0, 0.0);
  std::vector<SequenceFrame> frames;
  // The recorded IMU, when the dataset has one (on the frames' clock, microseconds), with what
  // the stereo-inertial run needs at start: the extrinsic, gravity and the IMU's velocity in the
  // estimate's world (the first camera's frame), the last two from the ground truth standing in
  // for the state guidance hands over.
  std::vector<estimator::ImuSample<double>> imu;
  estimator::ImuNoise<double> imu_noise;
  std::int64_t imu_period_us = 0;
  PoseD imu_T_camera;
  Vec3D gravity_world_mps2 = Vec3D::Zero();
  Vec3D initial_velocity_mps = Vec3D::Zero();
  bool HasImu() const { return !imu.empty(); }
};

struct RunOptions {
  std::string name;  // "SWF(5)"
  estimator::SwfMode mode = estimator::SwfMode::kSlidingWindow;
  int window = 5;
  std::size_t max_tracks = 150;
  int max_disparity_px = 128;  // the front end's SAD search range
  double sigma_px = 0.5;       // measurement noise the estimator assumes
  // Constant-velocity process noise per frame (1 sigma of the change of the frame-to-frame
  // motion).
  double process_sigma_m = 0.05;
  double process_sigma_rad = 0.02;
  // An anchored position error beyond this calls the run diverged (not merely inaccurate).
  double divergence_m = 1.0;
  // Diagnosis only: hand the pipeline the truth's frame-to-frame motion as its motion input
  // (what an IMU would provide, with the process noise above) instead of constant velocity.
  bool truth_motion = false;
  // The stereo-inertial estimator on the sequence's IMU (PipelineOptions::imu), with the prior
  // sigmas of the biases it starts from (zero: no static calibration before the first frame).
  bool imu = false;
  double gyro_bias_sigma_radps = 0.1;
  double accel_bias_sigma_mps2 = 0.2;
  // Non-empty: the run writes every frame's front-end measurements (left image), the filter's
  // landmarks and the true pose there, as JSON (WriteMeasurements), for the measurement-error
  // histogram on real frames (tools/eval/real_frames.py).
  std::string measurements_path;
};

struct FrameRecord {
  PoseD estimate;               // world_T_camera, world = the first camera
  int tracked = 0;              // landmarks tracked from earlier frames into this one
  int window_measurements = 0;  // measurements in the estimator's window
  int iterations = 0;
  std::uint32_t fault_bits = 0;
  int status = 0;                 // core::Status of the estimate stage
  double position_sigma_m = 0.0;  // sqrt(trace) of the navigation output's position covariance
  double anchored_error_m = 0.0;  // against the truth, both from their first frame
  // The navigation output's integrity (estimator::NavIntegrity: 0 VALID, 1 DEGRADED, 2 INVALID;
  // -1 before a frame is recorded), its flags and protection levels, and the error split
  // along up_world to compare with them.
  int integrity = -1;
  std::uint32_t integrity_flags = 0;
  double hpl_m = 0.0;
  double vpl_m = 0.0;
  double horizontal_error_m = 0.0;
  double vertical_error_m = 0.0;
  bool Misleading() const;  // error beyond a protection level while the output said VALID
};

enum class Verdict { kOk, kInputError, kNonFinite, kDiverged, kNoMeasurements };
const char* ToString(Verdict verdict);  // "ok", "input_error", "non_finite", ...

struct RunRecord {
  RunOptions options;
  std::vector<FrameRecord> frames;  // frames processed (all of them unless the input failed)
  TrajectoryErrors errors;          // over the processed frames
  Verdict verdict = Verdict::kOk;
  std::string reason;  // why the verdict is not ok, naming the frame and its record
  int failure_frame = -1;
  int estimate_failures = 0;               // frames whose estimate stage did not return kOk
  int frames_without_tracks = 0;           // frames after the first with no tracked landmark
  int frames_by_integrity[3] = {0, 0, 0};  // VALID, DEGRADED, INVALID
  int misleading_frames = 0;               // FrameRecord::Misleading()
  int first_misleading_frame = -1;
  int degraded_beyond_protection = 0;  // DEGRADED frames with the error beyond a protection level
  double mean_tracked = 0.0;
  // Stereo-inertial runs: the IMU biases estimated at the last frame, and the stream's counts.
  bool has_biases = false;
  Vec3D gyro_bias_radps = Vec3D::Zero();
  Vec3D accel_bias_mps2 = Vec3D::Zero();
  std::int64_t imu_samples_accepted = 0;
  std::int64_t imu_samples_dropped = 0;
  std::int64_t imu_intervals_bridged = 0;
  double seconds = 0.0;  // wall time, images loaded once
  bool Ok() const { return verdict == Verdict::kOk; }
};

// The flight pipeline's options for a run on this sequence (what swf-eval flies).
app::PipelineOptions PipelineFor(const StereoSequence& sequence, const RunOptions& options);

// Runs the sequence; never throws, every problem ends in the verdict and reason.
RunRecord RunSequence(const StereoSequence& sequence, const RunOptions& options);

// The same run as SWF(window) and as VO(window): name and mode set from `base`'s window.
std::vector<RunRecord> RunSwfAndVo(const StereoSequence& sequence, const RunOptions& base);

// For every run that diverged or went non-finite, the same run with the truth's motion as the
// motion input: when that one follows the truth, the images and the front end carry the
// trajectory and what failed is the estimate without a motion input.
std::vector<RunRecord> DiagnoseFailures(const StereoSequence& sequence,
                                        const std::vector<RunRecord>& runs);

// A dataset's evaluation: `load` (LoadEuroc, LoadKitti) reads it into *result, then SWF and VO
// run on it with options.run and the failed ones are diagnosed (DiagnoseFailures). False with
// *error only when the dataset cannot be loaded; a failed run is in its RunRecord's verdict.
template <typename Options, typename Result>
bool LoadAndRun(bool (*load)(const std::string&, const Options&, Result*, std::string*),
                const std::string& dir, const Options& options, Result* result,
                std::string* error) {
  if (!load(dir, options, result, error)) return false;
  result->runs = RunSwfAndVo(result->sequence, options.run);
  result->diagnostics = DiagnoseFailures(result->sequence, result->runs);
  return true;
}

// `total` indices into n recorded frames, forwards then backwards (0, 1, ..., n-1, n-2, ..., 1,
// 0, 1, ...): a ping-pong, so the image motion between consecutive frames stays continuous.
std::vector<int> PingPong(int n, int total);

}  // namespace swf::eval
