// Pipeline: the frame group's computation for one stereo pair, in flight form (no allocation,
// no exceptions, no clocks, single-threaded, deterministic):
//   rectify (raw cameras only) -> front end (track + stereo + new landmarks) -> Sliding Window
//   Filter (process factor, gated stereo measurements, robust Gauss-Newton) -> newest-pose
//   covariance -> integrity monitor (status, protection levels, restart from the last trusted
//   state on a detected divergence) -> navigation output and, on request, the landmark map with
//   covariances for the hazard group.
//
// Two estimators, chosen by PipelineOptions::imu.enabled:
//   stereo-only      pose states; the process factor is the navigation system's relative motion
//                    (drivers::MotionInput) or, without one, a bounded constant-velocity model
//   stereo-inertial  pose, velocity and IMU biases (InertialStereoModel); the process factor is
//                    the IMU preintegrated between exposures (ImuInput, fed by AddImu), which
//                    also predicts the front end's search, carries the state through a camera
//                    outage with its covariance, and restarts the filter from the last trusted
//                    state; a motion input is not used
// The navigation output is the left camera's pose either way (the inertial state through the
// camera extrinsic, velocity: the IMU's).
//
// The estimator's world frame is the frame `initial_world_T_camera` is expressed in (the
// simulator's local level frame, or whatever the navigation system hands over at start).
// Stage times are measured by the caller (FlightLoop), never inside: results must not depend on
// the clock.
#pragma once

#include <cstdint>
#include <memory>

#include "swf/app/imu_input.hpp"
#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/estimator/imu_time_offset.hpp"
#include "swf/estimator/inertial_model.hpp"
#include "swf/estimator/integrity.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/frontend/frontend.hpp"
#include "swf/frontend/rectify.hpp"

namespace swf::app {

// Compile-time capacities of the flight estimator (STYLE.md, memory). K is what the held window
// (hold_depth_precision, docs/integrity.md) needs on the descent from 100 m: its first landmarks
// reach 0.5 % depth precision after 25 frames. N lets each of those K + 1 poses bring the demo's
// 150 tracks (26 x 150 = 3900). P holds a frame's tracks: marginalizing a pose moves every
// landmark it shares with the window into the prior (the demo's and flight_gige's 150, with room
// for tracks the front end recovers after a gap). The configuration check refuses what does not
// fit.
inline constexpr int kMaxWindow = 25;                                 // K
inline constexpr int kMaxLandmarks = 4096;                            // N (active in the window)
inline constexpr int kMaxMeasurementsPerPose = frontend::kMaxTracks;  // M
inline constexpr int kMaxPriorLandmarks = 160;                        // P
inline constexpr int kMaxMapLandmarks = kMaxLandmarks;  // landmarks in one published map

using FlightSwf =
    estimator::SlidingWindowFilter<estimator::StereoModel<double>, kMaxWindow, kMaxLandmarks,
                                   kMaxMeasurementsPerPose, kMaxPriorLandmarks>;
using InertialFlightSwf =
    estimator::SlidingWindowFilter<estimator::InertialStereoModel<double>, kMaxWindow,
                                   kMaxLandmarks, kMaxMeasurementsPerPose, kMaxPriorLandmarks>;

}  // namespace swf::app

// Compiled once, in flight_swf.cpp and inertial_flight_swf.cpp.
namespace swf::estimator {
extern template class SlidingWindowFilter<StereoModel<double>, app::kMaxWindow, app::kMaxLandmarks,
                                          app::kMaxMeasurementsPerPose, app::kMaxPriorLandmarks>;
extern template class SlidingWindowFilter<InertialStereoModel<double>, app::kMaxWindow,
                                          app::kMaxLandmarks, app::kMaxMeasurementsPerPose,
                                          app::kMaxPriorLandmarks>;
}  // namespace swf::estimator

namespace swf::app {

struct PipelineOptions {
  // Raw cameras: rectify with these calibrations. Otherwise frames arrive rectified and
  // `camera` is the rectified rig.
  bool rectify = false;
  frontend::CameraCalibration left_calibration;
  frontend::CameraCalibration right_calibration;
  estimator::StereoCamera<double> camera;
  int width_px = 0;  // rectified image size the pipeline expects
  int height_px = 0;

  frontend::FrontendOptions frontend;  // camera is filled in by Configure
  // Paper 4.1.2, refinement in the loop: after the filter's update the frame's measurements are
  // re-aligned at the updated pose and landmarks (Frontend::Refine) and the refined values
  // replace the ones the filter holds, so the next frame's solve (every solve of the window that
  // still holds this pose) uses them. One warped LK and one stereo LK per measurement.
  bool refine_in_loop = true;
  estimator::SwfOptions swf;
  // The 1-sigma of a measurement's left coordinates (uL, v): the tracker's sub-pixel
  // precision, plus a misregistration that grows with the magnification m of its template's
  // warp (StereoMeasurement::magnification), part of it in pixels (the template's resampling)
  // and part an angle on the scene (camera.fx times it in pixels):
  // measurement_sigma_px + (measurement_sigma_per_magnification_px + fx *
  // measurement_sigma_per_magnification_rad) * (max(m, 1 / m) - 1) (MeasurementSigmaPx).
  double measurement_sigma_px = 0.5;
  double measurement_sigma_per_magnification_px = 0.0;
  double measurement_sigma_per_magnification_rad = 0.0;
  // Whether the warp-grown part of that error is shared by a track's sightings. It is the
  // template's misregistration, which drifts slowly as the warp grows: the same track's error
  // in consecutive frames is correlated 0.5 at 2-3 frames of age and 0.94 beyond 16 (docs/imu.md).
  // n sightings with a common error b and independent errors w carry 1 / (sigma_w^2 / n +
  // sigma_b^2) about their mean, the information a diagonal model gives when each of them is
  // stated with variance sigma_w^2 + n sigma_b^2; so with this on, the n-th sighting of a track
  // (the filter's count, this one included) is stated with (sigma_w + sigma_b)^2 + (n - 1)
  // sigma_b^2, sigma_w = measurement_sigma_px and sigma_b the warp term above. The first
  // sighting keeps the sigma of before; the disparity's own error (below) is not shared.
  bool track_error_shared = false;
  // The right coordinate uR = uL - d: the stereo match refines the disparity d of the left
  // point wherever the tracker put it, so uR carries uL's error plus the match's own, which is
  // independent of it and does not grow with m but with the parallax d / fx = baseline / range
  // (the right view's perspective on the patch departs from the left's):
  // measurement_disparity_sigma_px + measurement_disparity_sigma_per_parallax_px * d / fx
  // (MeasurementNoiseOf). 0: the model of before, uR independent of uL at uL's sigma (the
  // disparity then at sqrt(2) times it).
  double measurement_disparity_sigma_px = 0.0;
  double measurement_disparity_sigma_per_parallax_px = 0.0;
  float min_quality = 0.7f;  // measurements below this ZNCC are not used
  // Constant-velocity process model: 1-sigma of the per-frame deviation from the previous
  // relative motion, camera frame of the previous pose.
  double process_sigma_m = 0.5;
  double process_sigma_rad = 0.01;
  // Without a motion input the last estimated motion is repeated, but bounded: a motion below
  // these per-frame thresholds is taken as standing still (noise must not integrate into a
  // drift), one faster than integrity.max_speed_mps is clipped, and the process sigma grows
  // with every frame since the last VALID one (at most max_process_inflation times); frames
  // after the last VALID one repeat its motion rather than extrapolate the doubtful estimates.
  double still_translation_m = 0.005;
  double still_rotation_rad = 0.001;
  double max_process_inflation = 3.0;
  // Motion-input envelope: a relative motion faster than integrity.max_speed_mps or turning
  // faster than this is a glitch, refused before it reaches the filter (the filter's motion
  // gate, SwfOptions::gate_probability, catches the subtler ones against the images).
  double max_turn_rate_radps = 3.0;
  estimator::Pose<double> initial_world_T_camera;
  // Stereo calibration errors the filter does not estimate ("consider" parameters, 1-sigma): the
  // baseline's, and a disparity bias (a relative rotation of the cameras about their y axis by
  // an angle a shifts every disparity by fx * a). Either one scales every range, so the motion
  // estimated from the images, and the position error it leaves grows along the path. That
  // error is added to the published covariance and so to the protection levels. 0 states a
  // perfect calibration.
  double calibration_baseline_sigma_m = 0.0;
  double calibration_disparity_sigma_px = 0.0;
  estimator::IntegrityOptions integrity;
  ImuOptions imu;  // enabled: the stereo-inertial estimator (see the file comment)
};

// The sigma the filter states for a measurement whose template is warped with this magnification
// (PipelineOptions). The warped tracker's error against the renderer's truth grows linearly with
// how far the warp is from the identity, whichever way the scale goes, and its growth in pixels
// doubles with the image's focal length (docs/imu.md, "Consistency along the descent").
// sighting: the track's sighting count in the filter, this one included (1 = a first sighting;
// PipelineOptions::track_error_shared).
double MeasurementSigmaPx(const PipelineOptions& options, double magnification, int sighting = 1);

// A stereo measurement's noise (PipelineOptions): the 1-sigma of uL and v, and of the disparity
// uL - uR. right_follows_left: uR = uL - d with d's error independent of uL's; false: the model
// of before, uR's error independent of uL's at the same sigma (the disparity's then sqrt(2) s).
struct MeasurementNoise {
  double sigma_px = 0.0;
  double disparity_sigma_px = 0.0;
  bool right_follows_left = false;
};
MeasurementNoise MeasurementNoiseOf(const PipelineOptions& options, double magnification,
                                    double disparity_px, int sighting = 1);
// W with W^T W = R^-1 for z = (uL, uR, v). With right_follows_left R = [s^2 s^2 0; s^2 s^2 +
// sd^2 0; 0 0 s^2] (uR = uL - d), W = L^-1 for R = L L^T, which whitens a residual into
// (e_uL / s, (e_uR - e_uL) / sd, e_v / s): the left bearing and the disparity as two independent
// errors. Without: I / s.
estimator::Mat3<double> MeasurementSqrtInformation(const MeasurementNoise& noise);

// Integrity since Configure: statuses, restarts and every gate (health_t carries them).
struct IntegrityCounters {
  std::int64_t frames_valid = 0;
  std::int64_t frames_degraded = 0;
  std::int64_t frames_invalid = 0;
  std::int64_t restarts = 0;
  std::int32_t last_recovery_frames = -1;  // frames from the last restart to VALID
  std::int64_t measurements_gated = 0;
  std::int64_t measurements_rejected = 0;
  std::int64_t landmarks_rejected = 0;
  std::int64_t new_landmarks_refused = 0;
  std::int64_t gate_suspensions = 0;
  std::int64_t motion_refused = 0;    // motion inputs outside the envelope (not fused)
  std::int64_t motion_overruled = 0;  // motion inputs the images overruled in the filter
  std::int64_t frames_coasted = 0;    // cycles without a stereo pair (camera outage) ...
  std::int64_t frames_blind = 0;      // ... or, stereo-inertial, with images too poor to measure
  std::int32_t longest_outage_frames = 0;
  std::int64_t flag_counts[estimator::kNumIntegrityFlags] = {};
};

// The front end since Configure: its per-frame statistics summed, and the measurements
// refinement in the loop replaced in the filter.
struct FrontendCounters {
  std::int64_t measurements = 0;  // of tracked landmarks (before the filter's gates)
  std::int64_t warped = 0;
  std::int64_t lost_tracking = 0;
  std::int64_t searched = 0;  // lost tracks searched for around their prediction
  std::int64_t recovered = 0;
  std::int64_t recovered_inconsistent = 0;
  std::int64_t rejected_consistency = 0;
  std::int64_t refined = 0;  // replaced in the filter by refinement in the loop
};

// The navigation output of one frame (nav_state_t without the transport fields).
struct NavOutput {
  std::int64_t utime = 0;
  std::int64_t frame_seq = 0;
  double position_world_m[3] = {0, 0, 0};
  double orientation_world_q[4] = {1, 0, 0, 0};  // w x y z
  double velocity_world_mps[3] = {0, 0, 0};
  double covariance[36] = {};
  std::int8_t status = 2;  // estimator::NavIntegrity (nav_state_t.STATUS_*)
  std::int32_t integrity_flags = 0;
  double horizontal_protection_m = 0.0;
  double vertical_protection_m = 0.0;
  double integrity_risk = 0.0;
  std::int8_t update_status = 0;  // core::Status of the filter update
  std::int32_t fault_bits = 0;
  std::int32_t iterations = 0;
  std::int32_t num_measurements = 0;
};

struct MapLandmark {
  std::int64_t id = 0;
  double position_world_m[3] = {0, 0, 0};
  double covariance_m2[6] = {};  // xx xy xz yy yz zz
  std::int32_t num_observations = 0;
};

// The landmark map handed to the hazard group (landmark_map_t without the transport fields).
struct MapOutput {
  std::int64_t utime = 0;
  std::int64_t frame_seq = 0;
  std::int32_t num_landmarks = 0;
  MapLandmark landmarks[kMaxMapLandmarks];
};

// A landmark the front end started this frame, and where: the frame group hands them on with the
// navigation output (NavRecord), and whoever keeps a history of them (the simulator's truth
// channels, a display) keeps it outside the flight process.
struct NewSighting {
  std::int64_t landmark_id = 0;
  std::int64_t frame_seq = 0;
  float u_left = 0.0f;
  float v = 0.0f;
};
inline constexpr int kMaxNewSightings = static_cast<int>(frontend::kMaxTracks);

// A feature of the frame on the rectified left image and what became of it (feature_set_t, for
// display on the ground). kGated: measured and added, but the filter's prediction or residual
// gate took it out; kRejected: below min_quality, refused by the filter, or a new landmark the
// filter did not keep.
enum class FeatureFate : std::int8_t { kTracked = 0, kNew = 1, kRejected = 2, kGated = 3 };
struct FeatureMark {
  std::int64_t id = 0;
  float u_px = 0.0f;
  float v_px = 0.0f;
  FeatureFate fate = FeatureFate::kTracked;
  float sigma_px = 0.0f;  // the 1-sigma the filter was told for u (left) and v
  float u_right_px = 0.0f;
  float sigma_disparity_px = 0.0f;  // ... and for the disparity u - u_right
  float quality = 0.0f;             // StereoMeasurement / NewLandmark::quality (ZNCC)
};
inline constexpr int kMaxFeatureMarks =
    static_cast<int>(frontend::kMaxTracks + frontend::kMaxNewLandmarks);

// One stereo pair as the pipeline consumes it.
struct PipelineFrame {
  frontend::GrayView left;
  frontend::GrayView right;
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  bool has_motion = false;
  estimator::Pose<double> motion;  // camera_prev_T_camera from the navigation system (IMU)
};

class Pipeline {
 public:
  Pipeline() = default;
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Validates and sizes everything. kInvalidArgument for options the components refuse.
  core::Status Configure(const PipelineOptions& options);

  // One IMU sample (stereo-inertial only), in stream order; the samples stamped at or before a
  // frame's exposure must be added before its Track(). Returns the stream checker's verdict.
  estimator::ImuSampleVerdict AddImu(const estimator::ImuSample<double>& sample);

  // Stages of one frame; call in this order. Each returns kOk or the reason it failed; a failed
  // estimate stage leaves the filter in its local recovery (fault bits) and the frame counted.
  core::Status Rectify(const PipelineFrame& frame);
  core::Status Track();
  // motion: camera_prev_T_camera from the navigation system (nullptr: constant velocity).
  core::Status Estimate(const estimator::Pose<double>* motion);
  // A cycle without a stereo pair (camera stall or loss): the estimate is carried forward by
  // the motion input (nullptr: the bounded constant-velocity model; stereo-inertial: the IMU)
  // with its covariance grown per cycle, assessed (CAMERA_OUTAGE: DEGRADED, INVALID once the
  // covariance leaves the envelope) and ready for MakeNav. The next Estimate() fuses the whole
  // outage's motion as one process factor. kEmpty before the first estimate (nothing to carry).
  // The stereo-inertial Estimate() coasts the same way on a frame with fewer features than
  // integrity.min_valid_tracks (black or blinded images): IntegrityCounters::frames_blind.
  core::Status Coast(const estimator::Pose<double>* motion);
  // The exposure time the next Coast() stands for (the last one plus a frame period).
  std::int64_t CoastUtime() const;
  // Fills the navigation output of the frame just estimated (or coasted).
  void MakeNav(NavOutput* nav);
  // Computes covariances and fills the landmark map (hazard-group rate: O(n^3)).
  core::Status MakeMap(MapOutput* map);

  // The newest pose and its 6x6 marginal covariance ([rho, phi]); computes the covariances when
  // MakeNav/MakeMap have not. kEmpty before the first estimate, else the solver's status.
  core::Status NewestPose(estimator::Pose<double>* pose, estimator::Mat6<double>* covariance);
  // The rectified pair of the current frame (valid after Rectify() succeeded, until the source
  // buffer is released when the frames arrive rectified).
  const frontend::GrayView& RectifiedLeft() const { return current_.left; }
  const frontend::GrayView& RectifiedRight() const { return current_.right; }

  int NumFeatures() const { return static_cast<int>(output_->measurements.size()); }
  int NumLandmarks() const;
  // Poses in the filter's window (above `window` while the held window holds them).
  int NumPoses() const;
  std::uint32_t FaultBits() const;
  bool Inertial() const { return inertial_ != nullptr; }
  // The stereo-inertial filter's newest state (nullptr: stereo-only, or no state yet).
  const estimator::NavState<double>* NewestNavState() const;
  ImuCounts ImuStreamCounts() const { return imu_.Counts(); }
  // The camera-IMU time offset applied to the next interval (seconds: the configured one, or
  // the online estimate with imu.estimate_time_offset), and the estimator behind it.
  double ImuTimeOffsetS() const { return static_cast<double>(imu_.TimeOffsetUs()) * 1e-6; }
  const estimator::TimeOffsetEstimator<double>& ImuTimeOffset() const { return time_offset_; }
  core::Status LastStatus() const { return last_status_; }
  const estimator::IntegrityReport& LastIntegrity() const { return report_; }
  const IntegrityCounters& Integrity() const { return integrity_; }
  // The landmarks started by the last frame estimated (its measurements were fused).
  int NumNewSightings() const { return num_new_sightings_; }
  const NewSighting* NewSightings() const { return new_sightings_.get(); }
  // The last frame's features with their fate (none after a coasted cycle).
  int NumFeatureMarks() const { return num_feature_marks_; }
  const FeatureMark* FeatureMarks() const { return feature_marks_.get(); }
  const estimator::StereoCamera<double>& Camera() const { return options_.camera; }
  std::int64_t FramesEstimated() const { return frames_estimated_; }
  const FrontendCounters& Frontend() const { return frontend_counters_; }
  bool Rectifies() const { return options_.rectify; }

 private:
  PipelineOptions options_;
  bool configured_ = false;
  std::unique_ptr<frontend::StereoRectifier> rectifier_;
  std::unique_ptr<frontend::Image<std::uint8_t>> rect_left_;
  std::unique_ptr<frontend::Image<std::uint8_t>> rect_right_;
  std::unique_ptr<frontend::Frontend> frontend_;
  std::unique_ptr<frontend::FrameOutput> output_;
  // Exactly one of the two filters exists (PipelineOptions::imu.enabled).
  std::unique_ptr<FlightSwf> swf_;
  std::unique_ptr<InertialFlightSwf> inertial_;
  estimator::InertialStereoModel<double> inertial_model_;
  ImuInput imu_;
  estimator::TimeOffsetEstimator<double> time_offset_;
  template <typename F>
  decltype(auto) Visit(F&& f) {
    return inertial_ ? f(*inertial_) : f(*swf_);
  }
  template <typename F>
  decltype(auto) Visit(F&& f) const {
    return inertial_ ? f(*inertial_) : f(*swf_);
  }
  bool AddObservation(std::int64_t landmark_id, const estimator::Vec3<double>& z,
                      const MeasurementNoise& noise);
  estimator::Pose<double> NewestCameraPose() const;
  // The filter's covariances, and the newest camera pose's 6x6 from them (camera_covariance_).
  core::Status ComputeCovariances();
  estimator::Mat6<double> camera_covariance_ = estimator::Mat6<double>::Zero();
  std::unique_ptr<frontend::LandmarkEstimate[]> estimates_;
  std::unique_ptr<NewSighting[]> new_sightings_;
  int num_new_sightings_ = 0;
  void Mark(std::int64_t id, const estimator::Vec3<double>& z, float quality, FeatureFate fate,
            const MeasurementNoise& noise);
  void MarkUnfused();
  std::unique_ptr<FeatureMark[]> feature_marks_;
  int num_feature_marks_ = 0;
  std::unique_ptr<std::int64_t[]> fused_ids_;  // MarkUnfused's workspace (kMaxMeasurementsPerPose)
  frontend::StereoFrame current_{};
  std::int64_t utime_ = 0;
  std::int64_t seq_ = 0;
  bool has_previous_pose_ = false;
  estimator::Pose<double> previous_pose_;
  estimator::Pose<double> before_previous_pose_;
  bool has_before_previous_ = false;
  core::Status last_status_ = core::Status::kOk;
  estimator::Mat6<double> q_sqrt_ = estimator::Mat6<double>::Identity();
  std::int64_t frames_estimated_ = 0;
  bool covariance_valid_ = false;

  // Integrity: the monitor, the last VALID state, and what happened since.
  core::Status AddFrameState(const estimator::Pose<double>* motion);
  core::Status AddFirstState();
  core::Status AddPredictedPose(const estimator::Pose<double>* motion);
  // Stereo-inertial: the IMU interval up to this frame as the process factor; the restart from
  // the trusted state carried by the IMU; the coasted state; the IMU's disagreement with the
  // estimate (MotionDisagreement's counterpart).
  core::Status AddInertialState();
  bool AlignStaticStart(estimator::NavState<double>* first, estimator::Vec15<double>* sigma);
  core::Status RestartInertial();
  static estimator::TimeOffsetOptions<double> TimeOffsetOptionsOf(const ImuOptions& imu);
  void EstimateTimeOffset();
  bool CoastInertial();
  double ImuDisagreement() const;
  estimator::NavState<double> trusted_state_;
  estimator::Mat15<double> trusted_state_covariance_ = estimator::Mat15<double>::Zero();
  bool imu_gap_ = false;  // this frame's IMU interval bridged a gap or had no sample
  void CoastStereo(double inflation);
  core::Status CoastCycle(const estimator::Pose<double>* motion);
  estimator::Vec3<double> coast_state_velocity_ = estimator::Vec3<double>::Zero();
  // The motion input if it is inside the envelope, else nullptr (refused and counted).
  const estimator::Pose<double>* AcceptMotion(const estimator::Pose<double>* motion);
  // The motion of one frame: the accepted input, or the bounded constant-velocity model with
  // the process sigma's inflation factor.
  estimator::Pose<double> FrameMotion(const estimator::Pose<double>* motion,
                                      double* inflation) const;
  void CountReport();
  void ClearCoast();
  bool motion_refused_ = false;  // this frame's motion input was refused
  // Camera outage: cycles since the filter's newest pose, their composed motion and the
  // process variance it accumulated (per axis: translation, rotation), and the coasted state.
  std::int64_t coast_frames_ = 0;
  estimator::Pose<double> coast_motion_;
  double coast_variance_m2_ = 0.0;
  double coast_variance_rad2_ = 0.0;
  estimator::Pose<double> coast_pose_;
  estimator::Mat6<double> coast_covariance_ = estimator::Mat6<double>::Zero();
  bool dr_reanchor_ = false;  // restart the dead reckoning at the next estimate
  core::Status RestartFromTrusted();
  estimator::Pose<double> BoundedConstantVelocity() const;
  void AddMeasurements();
  // After a solve: templates' reference pose and refinement in the loop (refine_in_loop).
  void RefineAfterUpdate();
  // The filter's landmarks into estimates_ (the front end's view of the map); their count.
  std::size_t GatherLandmarkEstimates();
  FrontendCounters frontend_counters_{};
  void AssessIntegrity(bool filter_reset, bool has_motion);
  estimator::IntegrityMonitor monitor_;
  estimator::IntegrityReport report_{};
  IntegrityCounters integrity_{};
  estimator::Pose<double> trusted_pose_;
  estimator::Mat6<double> trusted_covariance_ = estimator::Mat6<double>::Zero();
  estimator::Pose<double> since_trusted_;   // motion predicted since the trusted pose
  estimator::Pose<double> trusted_motion_;  // bounded constant velocity at the trusted pose
  double smoothed_step_m_ = 1e9;            // smoothed per-frame motion of the VALID frames
  double smoothed_step_rad_ = 1e9;
  std::int64_t frames_since_trusted_ = 0;
  bool restart_pending_ = false;
  std::int64_t frames_since_restart_ = -1;  // -1: no restart waiting to recover
  estimator::Pose<double> last_motion_;     // the motion the newest pose was predicted with
  estimator::Vec3<double> velocity_world_ = estimator::Vec3<double>::Zero();
  std::int64_t last_estimate_utime_ = 0;
  // Dead reckoning of the motion input from the last (re)start, an independent check of the
  // visual solution: its position and per-axis variance (the process noise summed, plus the
  // rotation noise acting on the distance travelled).
  void DeadReckon(const estimator::Pose<double>* motion);
  double MotionDisagreement() const;
  bool dr_valid_ = false;
  estimator::Pose<double> dr_pose_;
  double dr_variance_m2_ = 0.0;
  double dr_distance_m_ = 0.0;
  double last_dt_s_ = 0.0;
  double distance_m_ = 0.0;  // flown since the start (the protection levels' drift bound)
  // Position error per unit of each calibration error (calibration_*_sigma), summed along the
  // path: a baseline error db scales a range by -db / b, a disparity bias dd by -z dd / (fx b),
  // and the motion estimated across that range by the same factor.
  void AccumulateCalibrationSensitivity(const estimator::Vec3<double>& step_m);
  estimator::Vec3<double> baseline_sensitivity_ = estimator::Vec3<double>::Zero();   // m / m
  estimator::Vec3<double> disparity_sensitivity_ = estimator::Vec3<double>::Zero();  // m / px
  // Evidence of the newest frame's measurements (image spread, disparities).
  std::unique_ptr<float[]> disparities_;
  int num_disparities_ = 0;
  double image_spread_px_ = 0.0;
};

}  // namespace swf::app
