#include "swf/app/pipeline.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <new>

namespace swf::app {

using core::Status;
using estimator::Pose;
using estimator::Vec3;

double MeasurementSigmaPx(const PipelineOptions& options, double magnification, int sighting) {
  if (!(magnification > 0.0)) return options.measurement_sigma_px;
  const double warp = std::max(magnification, 1.0 / magnification) - 1.0;
  const double shared = (options.measurement_sigma_per_magnification_px +
                         options.camera.fx * options.measurement_sigma_per_magnification_rad) *
                        warp;
  const double sigma = options.measurement_sigma_px + shared;
  if (!options.track_error_shared || sighting <= 1) return sigma;
  return std::sqrt(sigma * sigma + static_cast<double>(sighting - 1) * shared * shared);
}

MeasurementNoise MeasurementNoiseOf(const PipelineOptions& options, double magnification,
                                    double disparity_px, int sighting) {
  MeasurementNoise noise;
  noise.sigma_px = MeasurementSigmaPx(options, magnification, sighting);
  if (!(options.measurement_disparity_sigma_px > 0.0)) {
    noise.disparity_sigma_px = std::sqrt(2.0) * noise.sigma_px;  // uR independent of uL
    return noise;
  }
  const double parallax = std::max(0.0, disparity_px) / options.camera.fx;
  noise.disparity_sigma_px = options.measurement_disparity_sigma_px +
                             options.measurement_disparity_sigma_per_parallax_px * parallax;
  noise.right_follows_left = true;
  return noise;
}

estimator::Mat3<double> MeasurementSqrtInformation(const MeasurementNoise& noise) {
  const double s = noise.sigma_px;
  if (!noise.right_follows_left) return estimator::Mat3<double>::Identity() / s;
  const double sd = noise.disparity_sigma_px;
  estimator::Mat3<double> w = estimator::Mat3<double>::Zero();
  w(0, 0) = 1.0 / s;
  w(1, 0) = -1.0 / sd;
  w(1, 1) = 1.0 / sd;
  w(2, 2) = 1.0 / s;
  return w;
}

Status Pipeline::Configure(const PipelineOptions& options) {
  if (!(options.measurement_sigma_px > 0.0) ||
      !(options.measurement_sigma_per_magnification_px >= 0.0) ||
      !std::isfinite(options.measurement_sigma_per_magnification_px) ||
      !(options.measurement_sigma_per_magnification_rad >= 0.0) ||
      !std::isfinite(options.measurement_sigma_per_magnification_rad) ||
      !(options.measurement_disparity_sigma_px >= 0.0) ||
      !std::isfinite(options.measurement_disparity_sigma_px) ||
      !(options.measurement_disparity_sigma_per_parallax_px >= 0.0) ||
      !std::isfinite(options.measurement_disparity_sigma_per_parallax_px) ||
      !(options.process_sigma_m > 0.0) || !(options.process_sigma_rad > 0.0) ||
      !options.camera.Valid() || options.width_px <= 0 || options.height_px <= 0 ||
      options.width_px > frontend::kMaxImageWidth ||
      options.height_px > frontend::kMaxImageHeight) {
    return Status::kInvalidArgument;
  }
  if (options.swf.mode == estimator::SwfMode::kBatch) return Status::kInvalidArgument;
  if (options.imu.enabled && !options.imu.Valid()) return Status::kInvalidArgument;
  if (!(options.still_translation_m >= 0.0) || !(options.still_rotation_rad >= 0.0) ||
      !(options.max_process_inflation >= 1.0) || !(options.max_turn_rate_radps > 0.0) ||
      monitor_.Configure(options.integrity) != Status::kOk) {
    return Status::kInvalidArgument;
  }
  options_ = options;
  // Everything large is created here, once, before the loop starts.
  frontend_.reset(new (std::nothrow) frontend::Frontend());
  output_.reset(new (std::nothrow) frontend::FrameOutput());
  swf_.reset();
  inertial_.reset();
  if (options.imu.enabled) {
    inertial_.reset(new (std::nothrow) InertialFlightSwf());
  } else {
    swf_.reset(new (std::nothrow) FlightSwf());
  }
  estimates_.reset(new (std::nothrow) frontend::LandmarkEstimate[kMaxLandmarks]);
  new_sightings_.reset(new (std::nothrow) NewSighting[kMaxNewSightings]);
  feature_marks_.reset(new (std::nothrow) FeatureMark[kMaxFeatureMarks]);
  fused_ids_.reset(new (std::nothrow) std::int64_t[kMaxMeasurementsPerPose]);
  disparities_.reset(new (std::nothrow) float[2 * frontend::kMaxTracks]);
  if (!frontend_ || !output_ || (!swf_ && !inertial_) || !estimates_ || !new_sightings_ ||
      !disparities_ || !feature_marks_ || !fused_ids_)
    return Status::kFull;
  if (options.rectify) {
    rectifier_.reset(new (std::nothrow) frontend::StereoRectifier());
    rect_left_.reset(new (std::nothrow) frontend::Image<std::uint8_t>());
    rect_right_.reset(new (std::nothrow) frontend::Image<std::uint8_t>());
    if (!rectifier_ || !rect_left_ || !rect_right_) return Status::kFull;
    frontend::RectifyOptions ro;
    ro.width = options.width_px;
    ro.height = options.height_px;
    Status s = rectifier_->Configure(options.left_calibration, options.right_calibration, ro);
    if (s != Status::kOk) return s;
    options_.camera = rectifier_->Camera();
    if (rect_left_->Resize(options.width_px, options.height_px) != Status::kOk ||
        rect_right_->Resize(options.width_px, options.height_px) != Status::kOk) {
      return Status::kInvalidArgument;
    }
  }
  options_.frontend.camera = options_.camera;
  Status s = frontend_->Configure(options_.frontend);
  if (s != Status::kOk) return s;
  estimator::StereoModel<double> model;
  model.camera = options_.camera;
  if (inertial_) {
    inertial_model_ = estimator::InertialStereoModel<double>{};
    inertial_model_.stereo = model;
    inertial_model_.imu_T_camera = options_.imu.imu_T_camera;
    inertial_model_.gravity_world_mps2 = options_.imu.gravity_world_mps2;
    inertial_model_.first_velocity_sigma_mps = options_.imu.first_velocity_sigma_mps;
    inertial_model_.first_gyro_bias_sigma_radps = options_.imu.first_gyro_bias_sigma_radps;
    inertial_model_.first_accel_bias_sigma_mps2 = options_.imu.first_accel_bias_sigma_mps2;
    s = inertial_->Configure(inertial_model_, options_.swf);
    if (s == Status::kOk) s = imu_.Configure(options_.imu);
    if (s == Status::kOk) s = time_offset_.Configure(TimeOffsetOptionsOf(options_.imu));
  } else {
    s = swf_->Configure(model, options_.swf);
  }
  if (s != Status::kOk) return s;
  q_sqrt_.setZero();
  q_sqrt_.diagonal() << Vec3<double>::Constant(1.0 / options_.process_sigma_m),
      Vec3<double>::Constant(1.0 / options_.process_sigma_rad);
  num_new_sightings_ = 0;
  num_feature_marks_ = 0;
  has_previous_pose_ = false;
  has_before_previous_ = false;
  frames_estimated_ = 0;
  frontend_counters_ = FrontendCounters{};
  integrity_ = IntegrityCounters{};
  report_ = estimator::IntegrityReport{};
  trusted_pose_ = options_.initial_world_T_camera;
  trusted_covariance_.setZero();
  trusted_covariance_.diagonal() << Vec3<double>::Constant(options_.swf.first_pose_sigma_m *
                                                           options_.swf.first_pose_sigma_m),
      Vec3<double>::Constant(options_.swf.first_pose_sigma_rad * options_.swf.first_pose_sigma_rad);
  since_trusted_ = Pose<double>();
  trusted_motion_ = Pose<double>();
  smoothed_step_m_ = 1e9;  // unknown until VALID frames have moved (or not)
  smoothed_step_rad_ = 1e9;
  frames_since_trusted_ = 0;
  restart_pending_ = false;
  frames_since_restart_ = -1;
  velocity_world_.setZero();
  last_dt_s_ = 0.0;
  distance_m_ = 0.0;
  camera_covariance_.setZero();
  imu_gap_ = false;
  ClearCoast();
  dr_reanchor_ = false;
  motion_refused_ = false;
  configured_ = true;
  return Status::kOk;
}

Status Pipeline::Rectify(const PipelineFrame& frame) {
  if (!configured_) return Status::kNotConfigured;
  if (!frame.left.Valid() || !frame.right.Valid()) return Status::kInvalidArgument;
  utime_ = frame.utime;
  seq_ = frame.seq;
  if (options_.rectify) {
    const Status s =
        rectifier_->Rectify(frame.left, frame.right, rect_left_->View(), rect_right_->View());
    if (s != Status::kOk) return s;
    current_.left = rect_left_->View();
    current_.right = rect_right_->View();
    return Status::kOk;
  }
  if (frame.left.width != options_.width_px || frame.left.height != options_.height_px ||
      frame.right.width != options_.width_px || frame.right.height != options_.height_px) {
    return Status::kInvalidArgument;
  }
  current_.left = frame.left;
  current_.right = frame.right;
  return Status::kOk;
}

Status Pipeline::Track() {
  if (!configured_) return Status::kNotConfigured;
  frontend::FramePrediction prediction;
  if (has_previous_pose_ && NumPoses() > 0) {
    prediction.has_pose = true;
    prediction.world_T_camera =
        coast_frames_ > 0      ? coast_pose_ * last_motion_
        : has_before_previous_ ? previous_pose_ * (before_previous_pose_.Inverse() * previous_pose_)
                               : previous_pose_;
    // With an IMU the search is predicted by the IMU since the newest state.
    if (inertial_ && imu_.IntegrateTo(utime_) == Status::kOk) {
      prediction.world_T_camera = inertial_model_.CameraPose(
          inertial_model_.Propagate(inertial_->NewestPose(), imu_.SinceEstimate()));
    }
    prediction.landmarks = estimates_.get();
    prediction.num_landmarks = GatherLandmarkEstimates();
  }
  const Status s = frontend_->ProcessFrame(current_, prediction, output_.get());
  const frontend::FrameStats& f = output_->stats;
  FrontendCounters& c = frontend_counters_;
  c.measurements += static_cast<std::int64_t>(output_->measurements.size());
  c.warped += static_cast<std::int64_t>(f.warped);
  c.lost_tracking += static_cast<std::int64_t>(f.lost_tracking);
  c.searched += static_cast<std::int64_t>(f.searched);
  c.recovered += static_cast<std::int64_t>(f.recovered);
  c.recovered_inconsistent += static_cast<std::int64_t>(f.recovered_inconsistent);
  c.rejected_consistency += static_cast<std::int64_t>(f.rejected_consistency);
  return s;
}

std::size_t Pipeline::GatherLandmarkEstimates() {
  std::size_t n = 0;
  Visit([&](const auto& filter) {
    filter.ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int /*obs*/) {
      if (n < static_cast<std::size_t>(kMaxLandmarks)) {
        estimates_[n].id = static_cast<std::uint32_t>(id);
        estimates_[n].p_world = p;
        ++n;
      }
    });
  });
  return n;
}

// Paper 4.1.2. The templates this frame started take its estimated pose as their reference;
// then every measurement of the frame is re-aligned at the updated pose and landmarks and the
// refined value replaces the one the filter holds (measurements a gate took out stay out; the
// feature marks show the refined pixel).
void Pipeline::RefineAfterUpdate() {
  const Pose<double> pose = NewestCameraPose();
  frontend_->SetReferencePose(pose);
  if (!options_.refine_in_loop) return;
  frontend::FramePrediction updated;
  updated.has_pose = true;
  updated.world_T_camera = pose;
  updated.landmarks = estimates_.get();
  updated.num_landmarks = GatherLandmarkEstimates();
  std::size_t refined = 0;
  if (frontend_->Refine(updated, output_.get(), &refined) != Status::kOk || refined == 0) return;
  // AddMeasurements marked the measurements first, in their order.
  const std::size_t marks =
      std::min(output_->measurements.size(), static_cast<std::size_t>(num_feature_marks_));
  for (std::size_t i = 0; i < output_->measurements.size(); ++i) {
    const frontend::StereoMeasurement& m = output_->measurements[i];
    if (m.quality < options_.min_quality) continue;
    const Status s = Visit([&](auto& filter) {
      return filter.ReplaceNewestObservation(m.landmark_id, Vec3<double>(m.u_left, m.u_right, m.v));
    });
    if (s != Status::kOk) continue;
    ++frontend_counters_.refined;
    if (i < marks && feature_marks_[i].id == m.landmark_id) {
      feature_marks_[i].u_px = static_cast<float>(m.u_left);
      feature_marks_[i].v_px = static_cast<float>(m.v);
      feature_marks_[i].u_right_px = static_cast<float>(m.u_right);
    }
  }
}

Status Pipeline::Estimate(const Pose<double>* motion_input) {
  if (!configured_) return Status::kNotConfigured;
  num_feature_marks_ = 0;
  // Stereo-inertial: a frame whose images gave (next to) nothing to measure (black, blinded,
  // a lens cap) is a camera outage, the IMU carries the state; not a solve on nothing.
  const std::size_t features = output_->measurements.size() + output_->new_landmarks.size();
  if (inertial_ && has_previous_pose_ && NumPoses() > 0 && !restart_pending_ &&
      features < static_cast<std::size_t>(options_.integrity.min_valid_tracks)) {
    ++integrity_.frames_blind;
    return CoastCycle(nullptr);
  }
  // With an IMU the process input is the preintegrated IMU: a motion input is not used.
  const Pose<double>* motion = inertial_ ? nullptr : AcceptMotion(motion_input);
  Status s = AddFrameState(motion);
  const bool after_outage = coast_frames_ > 0;
  ClearCoast();
  if (s != Status::kOk) {
    last_status_ = s;
    if (inertial_ && s == Status::kEmpty) {
      // No IMU sample has ever arrived (nothing carries the state to this frame), or the static
      // start has too few yet.
      report_ = estimator::IntegrityReport{};
      report_.status = estimator::NavIntegrity::kInvalid;
      report_.flags = estimator::kFlagNoMotionInput;
      CountReport();
    }
    return s;
  }
  AddMeasurements();
  s = Visit([](auto& filter) { return filter.Update(); });
  MarkUnfused();
  last_status_ = s;
  covariance_valid_ = false;
  const bool filter_reset = NumPoses() == 0;  // its local recovery from a non-finite state
  if (!filter_reset) {
    const double dt_s = static_cast<double>(utime_ - last_estimate_utime_) * 1e-6;
    const Pose<double> newest = NewestCameraPose();
    velocity_world_ = inertial_ ? inertial_->NewestPose().velocity_world_mps
                      : has_previous_pose_ && dt_s > 0.0
                          ? Vec3<double>((newest.t - previous_pose_.t) / dt_s)
                          : Vec3<double>::Zero();
    if (dt_s > 0.0 && !after_outage) last_dt_s_ = dt_s;
    if (has_previous_pose_) {
      distance_m_ += (newest.t - previous_pose_.t).norm();
      AccumulateCalibrationSensitivity(newest.t - previous_pose_.t);
    }
    const bool overruled =
        Visit([](const auto& filter) { return filter.Summary().motion_overruled; });
    if (overruled && (motion != nullptr || inertial_)) {
      // The images overruled the input: what the frame really moved is the solved motion.
      last_motion_ = previous_pose_.Inverse() * newest;
      ++integrity_.motion_overruled;
      dr_reanchor_ = true;
    }
    if (has_previous_pose_) {
      before_previous_pose_ = previous_pose_;
      has_before_previous_ = true;
    }
    previous_pose_ = newest;
    has_previous_pose_ = true;
    covariance_valid_ = ComputeCovariances() == Status::kOk;
    if (dr_reanchor_) {
      dr_valid_ = covariance_valid_;
      dr_pose_ = newest;
      dr_variance_m2_ = covariance_valid_ ? camera_covariance_.topLeftCorner<3, 3>().trace() : 0.0;
      dr_distance_m_ = 0.0;
      dr_reanchor_ = false;
    }
    if (inertial_ && options_.imu.estimate_time_offset &&
        (s == Status::kOk || s == Status::kNotConverged))
      EstimateTimeOffset();
    // The next interval is integrated at the biases just estimated.
    if (inertial_) (void)imu_.RestartSinceEstimate(inertial_->NewestPose().biases);
    if (s == Status::kOk || s == Status::kNotConverged) RefineAfterUpdate();
  }
  last_estimate_utime_ = utime_;
  AssessIntegrity(filter_reset, motion != nullptr);
  ++frames_estimated_;
  return s == Status::kNotConverged ? Status::kOk : s;
}

// The state of this frame: the first, a restart from the trusted state, or a prediction.
Status Pipeline::AddFrameState(const Pose<double>* motion) {
  Status s;
  if (NumPoses() == 0 && !has_previous_pose_) {
    s = AddFirstState();  // the very first frame
    last_motion_ = Pose<double>();
    DeadReckon(nullptr);
  } else if (NumPoses() == 0 || restart_pending_) {
    s = RestartFromTrusted();
    DeadReckon(nullptr);
  } else if (inertial_) {
    s = AddInertialState();
  } else {
    // After a refused input or an outage the reckoning restarts from this frame's estimate.
    const bool reckon = motion != nullptr && coast_frames_ == 0;
    if (motion_refused_ || coast_frames_ > 0) dr_reanchor_ = true;
    s = AddPredictedPose(motion);
    if (reckon) {
      DeadReckon(motion);
    } else if (!dr_reanchor_) {
      DeadReckon(nullptr);
    }
  }
  return s;
}

// The initial state (the guidance's pose; with an IMU also its velocity, biases zero) with the
// first-state sigmas; the IMU intervals start at this frame.
Status Pipeline::AddFirstState() {
  if (!inertial_) return swf_->AddPose(options_.initial_world_T_camera);
  if (options_.imu.static_start) {
    // A live IMU stream may have begun just before the first pair: the static start waits,
    // frame by frame (INVALID, no motion input), until the rest is long enough to level on.
    const estimator::ImuSample<double>* samples = nullptr;
    if (imu_.Buffered(utime_, &samples) < options_.imu.static_alignment.min_samples)
      return Status::kEmpty;
  }
  estimator::NavState<double> first;
  first.world_T_imu = options_.initial_world_T_camera * options_.imu.imu_T_camera.Inverse();
  first.velocity_world_mps = options_.imu.initial_velocity_world_mps;
  estimator::Vec15<double> sigma;
  sigma << Vec3<double>::Constant(options_.swf.first_pose_sigma_m),
      Vec3<double>::Constant(options_.swf.first_pose_sigma_rad), inertial_model_.FirstStateSigmas();
  const bool aligned = options_.imu.static_start && AlignStaticStart(&first, &sigma);
  trusted_state_ = first;
  trusted_state_covariance_.setZero();
  trusted_state_covariance_.diagonal() = sigma.cwiseAbs2();
  // The guidance's start takes the filter's own first-state prior (the same sigmas).
  Status s = aligned ? inertial_->AddFirstPose(first, trusted_state_covariance_)
                     : inertial_->AddPose(first);
  if (s == Status::kOk) s = imu_.Start(utime_, first.biases);
  return s;
}

// The static start (ImuOptions::static_start): the samples up to the first exposure level the
// guidance's attitude and give the gyroscope bias; the camera stays where guidance put it. The
// sigmas: the tilt as well as the accelerometer bias lets it be known (sigma_ba / g, and never
// tighter than the guidance's), the gyroscope bias the mean's standard error and its drift over
// the static period, the velocity at rest. Not at rest: false, counted; the guidance's state
// stands.
bool Pipeline::AlignStaticStart(estimator::NavState<double>* first,
                                estimator::Vec15<double>* sigma) {
  using Model = estimator::InertialStereoModel<double>;
  const ImuOptions& o = options_.imu;
  const estimator::ImuSample<double>* samples = nullptr;
  const int n = imu_.Buffered(utime_, &samples);
  estimator::StaticAlignment<double> a;
  if (!estimator::AlignStatic(samples, n, first->world_T_imu.R, o.gravity_world_mps2,
                              o.static_alignment, &a)) {
    imu_.NoteStaticStart(-1, 0.0);
    return false;
  }
  imu_.NoteStaticStart(1, a.tilt_correction_rad);
  first->world_T_imu.R = a.world_R_imu;
  first->world_T_imu.t = options_.initial_world_T_camera.t - a.world_R_imu * o.imu_T_camera.t;
  first->velocity_world_mps.setZero();
  first->biases.gyro_radps = a.gyro_bias_radps;
  const double tilt_sigma = std::max(options_.swf.first_pose_sigma_rad,
                                     o.first_accel_bias_sigma_mps2 / o.gravity_world_mps2.norm());
  const double t = std::max(a.duration_s, 1e-3);
  const double gyro_sigma =
      o.noise.gyro_noise_density / std::sqrt(t) + o.noise.gyro_random_walk * std::sqrt(t);
  sigma->segment<3>(Model::kRotation).setConstant(tilt_sigma);
  sigma->segment<3>(Model::kVelocity).setConstant(o.static_velocity_sigma_mps);
  sigma->segment<3>(Model::kGyroBias).setConstant(gyro_sigma);
  return true;
}

// The IMU from the newest state to this exposure (an outage's cycles included) as the process
// factor, with the preintegration's covariance and the bias random walk.
Status Pipeline::AddInertialState() {
  const Status integrated = imu_.IntegrateTo(utime_);
  imu_gap_ = integrated != Status::kOk || imu_.LastInterval().gap;
  if (integrated != Status::kOk) return integrated;
  estimator::Mat15<double> sqrt_information;
  if (!estimator::InertialStereoModel<double>::ProcessSqrtInformation(imu_.SinceEstimate(),
                                                                      &sqrt_information)) {
    return Status::kInvalidArgument;  // an empty interval: the frame time did not advance
  }
  return inertial_->AddPoseWithMotion(imu_.SinceEstimate(), sqrt_information);
}

// The estimator's options from the flight's IMU options (the prior: a tenth of the bound, and
// a memory of 50 intervals, 5 s at 10 Hz).
estimator::TimeOffsetOptions<double> Pipeline::TimeOffsetOptionsOf(const ImuOptions& imu) {
  estimator::TimeOffsetOptions<double> o;
  o.initial_offset_s = imu.time_offset_s;
  o.max_offset_s = imu.max_time_offset_s;
  o.prior_sigma_s = 0.1 * imu.max_time_offset_s;
  return o;
}

// The newest interval's process factor, solved, read for the camera-IMU time offset; the next
// interval ends at the exposure plus the new estimate.
void Pipeline::EstimateTimeOffset() {
  const int n = inertial_->NumPoses();
  const estimator::ImuPreintegration<double>* u = nullptr;
  const estimator::Mat15<double>* w = nullptr;
  if (n < 2 || !inertial_->ProcessFactorInto(n - 1, &u, &w)) return;
  if (!time_offset_.Observe(inertial_model_, inertial_->PoseAt(n - 2), inertial_->NewestPose(), *u,
                            *w, ImuTimeOffsetS()))
    return;
  imu_.SetTimeOffsetUs(std::llround(time_offset_.OffsetS() * 1e6));
}

// The process factor of a new pose: the navigation system's relative motion when there is one
// (IMU), else the bounded constant-velocity model, with its sigma inflated by the frames since
// the last VALID estimate.
Status Pipeline::AddPredictedPose(const Pose<double>* motion) {
  double inflation = 1.0;
  last_motion_ = FrameMotion(motion, &inflation);
  if (coast_frames_ == 0) {
    const Status s = swf_->AddPoseWithMotion(last_motion_, q_sqrt_ / inflation);
    if (s != Status::kOk || motion == nullptr) return s;
    // Should the images overrule the input (the filter's motion gate), the frame is predicted
    // as if there were none, with the widest constant-velocity sigma.
    double unused = 1.0;
    const Pose<double> fallback = FrameMotion(nullptr, &unused);
    return swf_->SetMotionFallback(fallback, q_sqrt_ / options_.max_process_inflation);
  }
  // After an outage: the coasted motion and this frame's as one factor, with the variance of
  // every cycle summed and the rotation noise acting on the distance flown.
  const Pose<double> u = coast_motion_ * last_motion_;
  const double sigma_t = inflation / q_sqrt_(0, 0);
  const double sigma_r = inflation / q_sqrt_(3, 3);
  const double variance_rad2 = coast_variance_rad2_ + sigma_r * sigma_r;
  const double variance_m2 =
      coast_variance_m2_ + sigma_t * sigma_t + variance_rad2 * u.t.squaredNorm();
  estimator::Mat6<double> sqrt_information = estimator::Mat6<double>::Zero();
  sqrt_information.diagonal() << Vec3<double>::Constant(1.0 / std::sqrt(variance_m2)),
      Vec3<double>::Constant(1.0 / std::sqrt(variance_rad2));
  return swf_->AddPoseWithMotion(u, sqrt_information);
}

// Without a motion input, frames after the last VALID one repeat the trusted frame's motion.
Pose<double> Pipeline::FrameMotion(const Pose<double>* motion, double* inflation) const {
  *inflation = motion != nullptr ? 1.0
                                 : std::min(options_.max_process_inflation,
                                            1.0 + static_cast<double>(frames_since_trusted_));
  return motion != nullptr           ? *motion
         : frames_since_trusted_ > 0 ? trusted_motion_
                                     : BoundedConstantVelocity();
}

// The envelope of a relative motion over one frame period (twice the last measured period, for
// jitter; one second before there is one): finite, a rotation matrix, no faster than the
// vehicle can fly or turn. Outside it the input is a glitch: refused, counted, flagged.
const Pose<double>* Pipeline::AcceptMotion(const Pose<double>* motion) {
  motion_refused_ = false;
  if (motion == nullptr) return nullptr;
  const double period_s = 2.0 * (last_dt_s_ > 0.0 ? last_dt_s_ : 1.0);
  const bool finite = motion->t.allFinite() && motion->R.allFinite();
  const bool rotation =
      finite && (motion->R.transpose() * motion->R - estimator::Mat3<double>::Identity())
                        .cwiseAbs()
                        .maxCoeff() < 1e-6;
  const bool inside =
      rotation && motion->t.norm() <= options_.integrity.max_speed_mps * period_s &&
      estimator::LogSO3<double>(motion->R).norm() <= options_.max_turn_rate_radps * period_s;
  if (inside) return motion;
  motion_refused_ = true;
  ++integrity_.motion_refused;
  return nullptr;
}

// A cycle without images: the state carried by the process model alone (see pipeline.hpp).
Status Pipeline::Coast(const Pose<double>* motion_input) {
  if (!configured_) return Status::kNotConfigured;
  if (!has_previous_pose_) return Status::kEmpty;
  utime_ = CoastUtime();
  ++seq_;
  return CoastCycle(motion_input);
}

// The coasted state of the cycle stamped utime_, seq_ (a missing pair, or a blind frame).
Status Pipeline::CoastCycle(const Pose<double>* motion_input) {
  num_new_sightings_ = 0;  // no measurement of this cycle was fused
  num_feature_marks_ = 0;
  const Pose<double>* motion = inertial_ ? nullptr : AcceptMotion(motion_input);
  double inflation = 1.0;
  last_motion_ = FrameMotion(motion, &inflation);
  const Pose<double> before = coast_frames_ > 0 ? coast_pose_ : previous_pose_;
  ++coast_frames_;
  bool has_motion = motion != nullptr;
  if (inertial_) {
    has_motion = CoastInertial();
  } else {
    CoastStereo(inflation);
  }
  if (last_dt_s_ > 0.0) velocity_world_ = (coast_pose_.t - before.t) / last_dt_s_;
  if (inertial_ && has_motion) velocity_world_ = coast_state_velocity_;
  estimator::IntegrityEvidence e;
  e.has_motion_input = has_motion;
  e.motion_rejected = motion_refused_;
  e.position_world = coast_pose_.t;
  e.velocity_world = velocity_world_;
  e.has_covariance = true;
  e.covariance = coast_covariance_;
  e.distance_m = distance_m_ +
                 (inertial_ ? (coast_pose_.t - previous_pose_.t).norm() : coast_motion_.t.norm());
  report_ = monitor_.AssessCoast(e);
  CountReport();
  ++integrity_.frames_coasted;
  integrity_.longest_outage_frames =
      std::max(integrity_.longest_outage_frames, static_cast<std::int32_t>(coast_frames_));
  since_trusted_ = since_trusted_ * last_motion_;
  ++frames_since_trusted_;
  dr_reanchor_ = true;
  return Status::kOk;
}

// An outage cycle of the stereo-only estimator: the motion (input or bounded constant velocity)
// composed, its process variance summed.
void Pipeline::CoastStereo(double inflation) {
  coast_motion_ = coast_motion_ * last_motion_;
  const double sigma_t = inflation / q_sqrt_(0, 0);
  const double sigma_r = inflation / q_sqrt_(3, 3);
  coast_variance_m2_ += sigma_t * sigma_t;
  coast_variance_rad2_ += sigma_r * sigma_r;
  coast_pose_ = previous_pose_ * coast_motion_;
  // Covariance: the newest estimate's (or the trusted one grown per frame since), plus the
  // process noise of the outage, plus every rotation uncertainty acting on the distance flown.
  estimator::Mat6<double> base = trusted_covariance_;
  if (covariance_valid_ && NumPoses() > 0) {
    base = camera_covariance_;
  } else {
    base.diagonal() += static_cast<double>(frames_since_trusted_) *
                       q_sqrt_.diagonal().cwiseInverse().array().square().matrix();
  }
  const double rotation_rad2 =
      base.bottomRightCorner<3, 3>().diagonal().maxCoeff() + coast_variance_rad2_;
  coast_covariance_ = base;
  coast_covariance_.topLeftCorner<3, 3>().diagonal().array() +=
      coast_variance_m2_ + rotation_rad2 * coast_motion_.t.squaredNorm();
  coast_covariance_.bottomRightCorner<3, 3>().diagonal().array() += coast_variance_rad2_;
}

// An outage cycle of the stereo-inertial estimator: the newest state (or, without its
// covariance, the trusted one) carried by the IMU to this cycle with its covariance. False when
// the IMU could not carry it (no sample, a gap): the state is then held, its covariance grown
// as the stereo-only coast would.
bool Pipeline::CoastInertial() {
  const bool integrated = imu_.IntegrateTo(utime_) == Status::kOk;
  imu_gap_ = !integrated || imu_.LastInterval().gap;
  const bool from_newest = covariance_valid_ && NumPoses() > 0;
  estimator::NavState<double> state;
  estimator::Mat15<double> covariance;
  const bool carried =
      integrated &&
      (from_newest
           ? inertial_model_.PropagateWithCovariance(inertial_->NewestPose(),
                                                     inertial_->NewestStateCovariance(),
                                                     imu_.SinceEstimate(), &state, &covariance)
           : inertial_model_.PropagateWithCovariance(trusted_state_, trusted_state_covariance_,
                                                     imu_.SinceTrusted(), &state, &covariance));
  if (!carried) {
    CoastStereo(options_.max_process_inflation);
    return false;
  }
  coast_pose_ = inertial_model_.CameraPose(state);
  coast_covariance_ = inertial_model_.CameraPoseCovariance(state, covariance.topLeftCorner<6, 6>());
  coast_state_velocity_ = state.velocity_world_mps;
  return !imu_gap_;
}

void Pipeline::ClearCoast() {
  coast_frames_ = 0;
  coast_motion_ = Pose<double>();
  coast_variance_m2_ = 0.0;
  coast_variance_rad2_ = 0.0;
}

Pose<double> Pipeline::BoundedConstantVelocity() const {
  if (!has_before_previous_) return Pose<double>();
  Pose<double> u = before_previous_pose_.Inverse() * previous_pose_;
  const double angle = estimator::LogSO3<double>(u.R).norm();
  // A still scene stays still: judged on the last motion and on the smoothed speed of the
  // VALID frames, so that one jumpy frame of a vehicle at rest does not start a drift.
  const bool still_now =
      u.t.norm() < options_.still_translation_m && angle < options_.still_rotation_rad;
  const bool still_recently = smoothed_step_m_ < options_.still_translation_m &&
                              smoothed_step_rad_ < options_.still_rotation_rad;
  if (still_now || still_recently) return Pose<double>();
  const double max_step_m = options_.integrity.max_speed_mps * last_dt_s_;
  if (last_dt_s_ > 0.0 && u.t.norm() > max_step_m) u.t *= max_step_m / u.t.norm();
  return u;
}

// Restarts the filter from the last VALID pose carried forward by the motion predicted since,
// with that pose's covariance grown by one process noise per frame since: the restarted
// covariance (and protection levels) still covers the error made before the restart.
Status Pipeline::RestartFromTrusted() {
  Status s;
  if (inertial_) {
    s = RestartInertial();
  } else {
    swf_->Reset();
    const Pose<double> start = trusted_pose_ * since_trusted_;
    estimator::Mat6<double> covariance = trusted_covariance_;
    const double n = static_cast<double>(std::max<std::int64_t>(1, frames_since_trusted_));
    covariance.diagonal() += n * (q_sqrt_.diagonal().cwiseInverse().array().square()).matrix();
    s = swf_->AddFirstPose(start, covariance);
  }
  restart_pending_ = false;
  has_before_previous_ = false;
  last_motion_ = Pose<double>();
  monitor_.NoteRestart();
  ++integrity_.restarts;
  frames_since_restart_ = 0;
  return s;
}

// The trusted state carried to this frame by the IMU since, with its covariance: the restarted
// covariance covers the error made before the restart the way the IMU's own would.
Status Pipeline::RestartInertial() {
  inertial_->Reset();
  Status s = imu_.IntegrateTo(utime_);
  imu_gap_ = s != Status::kOk || imu_.LastInterval().gap;
  if (s != Status::kOk) return s;
  estimator::NavState<double> start;
  estimator::Mat15<double> covariance;
  if (!inertial_model_.PropagateWithCovariance(trusted_state_, trusted_state_covariance_,
                                               imu_.SinceTrusted(), &start, &covariance)) {
    return Status::kNumericalFailure;
  }
  s = inertial_->AddFirstPose(start, covariance);
  if (s == Status::kOk) s = imu_.RestartSinceEstimate(start.biases);
  return s;
}

// The front end's measurements into the filter (gated there), and the geometry evidence of the
// frame: spread of the measured pixels and the median disparity.
void Pipeline::AddMeasurements() {
  double su = 0.0, sv = 0.0, suu = 0.0, svv = 0.0, suv = 0.0;
  num_disparities_ = 0;
  num_new_sightings_ = 0;
  const auto note = [&](double u_left, double u_right, double v) {
    su += u_left;
    sv += v;
    suu += u_left * u_left;
    svv += v * v;
    suv += u_left * v;
    disparities_[num_disparities_++] = static_cast<float>(u_left - u_right);
  };
  for (const frontend::StereoMeasurement& m : output_->measurements) {
    const Vec3<double> z(m.u_left, m.u_right, m.v);
    const int sighting =
        1 + Visit([&](const auto& filter) { return filter.LandmarkSightings(m.landmark_id); });
    const MeasurementNoise noise =
        MeasurementNoiseOf(options_, m.magnification, z.x() - z.y(), sighting);
    if (m.quality < options_.min_quality) {
      Mark(m.landmark_id, z, m.quality, FeatureFate::kRejected, noise);
      continue;
    }
    const bool added = AddObservation(m.landmark_id, z, noise);
    if (added) note(m.u_left, m.u_right, m.v);
    Mark(m.landmark_id, z, m.quality, added ? FeatureFate::kTracked : FeatureFate::kRejected,
         noise);
  }
  for (const frontend::NewLandmark& n : output_->new_landmarks) {
    const Vec3<double> z(n.u_left, n.u_right, n.v);
    // A first sighting is its template's own frame (magnification 1).
    const MeasurementNoise noise = MeasurementNoiseOf(options_, 1.0, z.x() - z.y());
    const bool added = AddObservation(n.landmark_id, z, noise);
    Mark(n.landmark_id, z, n.quality, added ? FeatureFate::kNew : FeatureFate::kRejected, noise);
    if (!added) continue;
    note(n.u_left, n.u_right, n.v);
    if (num_new_sightings_ < kMaxNewSightings) {
      new_sightings_[num_new_sightings_++] =
          NewSighting{n.landmark_id, seq_, static_cast<float>(n.u_left), static_cast<float>(n.v)};
    }
  }
  image_spread_px_ = 0.0;
  if (num_disparities_ > 1) {
    const double k = 1.0 / num_disparities_;
    const double cuu = suu * k - su * su * k * k;
    const double cvv = svv * k - sv * sv * k * k;
    const double cuv = suv * k - su * sv * k * k;
    // Smaller eigenvalue of the 2x2 pixel covariance: small when the points lie on a line.
    const double half_trace = 0.5 * (cuu + cvv);
    const double root = std::sqrt(std::max(0.0, half_trace * half_trace - (cuu * cvv - cuv * cuv)));
    image_spread_px_ = std::sqrt(std::max(0.0, half_trace - root));
  }
}

void Pipeline::Mark(std::int64_t id, const Vec3<double>& z, float quality, FeatureFate fate,
                    const MeasurementNoise& noise) {
  if (num_feature_marks_ >= kMaxFeatureMarks) return;
  feature_marks_[num_feature_marks_++] = FeatureMark{id,
                                                     static_cast<float>(z.x()),
                                                     static_cast<float>(z.z()),
                                                     fate,
                                                     static_cast<float>(noise.sigma_px),
                                                     static_cast<float>(z.y()),
                                                     static_cast<float>(noise.disparity_sigma_px),
                                                     quality};
}

// After the update: a measurement added this frame that is no longer among the newest pose's
// observations was taken out by a gate (a new landmark: not kept). Sorting a fixed array does
// not allocate; at most M ids.
void Pipeline::MarkUnfused() {
  if (NumPoses() == 0) return;  // the filter reset itself: nothing was fused, nothing to tell
  int n = 0;
  Visit([&](const auto& filter) {
    filter.ForEachNewestObservation([&](std::int64_t id) {
      if (n < kMaxMeasurementsPerPose) fused_ids_[n++] = id;
    });
  });
  std::sort(fused_ids_.get(), fused_ids_.get() + n);
  for (int i = 0; i < num_feature_marks_; ++i) {
    FeatureMark& m = feature_marks_[i];
    if (m.fate == FeatureFate::kRejected) continue;
    if (std::binary_search(fused_ids_.get(), fused_ids_.get() + n, m.id)) continue;
    m.fate = m.fate == FeatureFate::kNew ? FeatureFate::kRejected : FeatureFate::kGated;
  }
}

// motion == nullptr on a (re)start: anchor at the filter's first pose. Without a motion input
// there is nothing independent to reckon with.
void Pipeline::DeadReckon(const Pose<double>* motion) {
  if (motion == nullptr) {
    dr_valid_ = NumPoses() == 1;
    if (dr_valid_) dr_pose_ = NewestCameraPose();
    dr_variance_m2_ = options_.swf.first_pose_sigma_m * options_.swf.first_pose_sigma_m;
    dr_distance_m_ = 0.0;
    return;
  }
  if (!dr_valid_) return;
  dr_pose_ = dr_pose_ * *motion;
  dr_distance_m_ += motion->t.norm();
  const double rotation_lever_m = options_.process_sigma_rad * dr_distance_m_;
  dr_variance_m2_ +=
      options_.process_sigma_m * options_.process_sigma_m + rotation_lever_m * rotation_lever_m;
}

// d^T (P_est + P_dr)^-1 d for d = estimate - dead reckoning (the two are treated as
// independent; the estimate used the same inputs, so this understates the distance).
double Pipeline::MotionDisagreement() const {
  if (!dr_valid_ || !covariance_valid_ || NumPoses() == 0) return -1.0;
  const Vec3<double> d = NewestCameraPose().t - dr_pose_.t;
  const estimator::Mat3<double> s = camera_covariance_.topLeftCorner<3, 3>() +
                                    dr_variance_m2_ * estimator::Mat3<double>::Identity();
  const Eigen::LDLT<estimator::Mat3<double>> ldlt(s);
  const double d2 = d.dot(ldlt.solve(d));
  return ldlt.info() == Eigen::Success && std::isfinite(d2) ? d2 : -1.0;
}

// The same distance for the IMU: the estimate against the trusted state carried by the IMU
// alone (its position covariance from the preintegration and the trusted state's).
double Pipeline::ImuDisagreement() const {
  if (!covariance_valid_ || NumPoses() == 0 || imu_gap_) return -1.0;
  estimator::NavState<double> reckoned;
  estimator::Mat15<double> covariance;
  if (!inertial_model_.PropagateWithCovariance(trusted_state_, trusted_state_covariance_,
                                               imu_.SinceTrusted(), &reckoned, &covariance)) {
    return -1.0;
  }
  const Vec3<double> d = inertial_->NewestPose().world_T_imu.t - reckoned.world_T_imu.t;
  const estimator::Mat3<double> s =
      inertial_->NewestStateCovariance().topLeftCorner<3, 3>() + covariance.topLeftCorner<3, 3>();
  const Eigen::LDLT<estimator::Mat3<double>> ldlt(s);
  const double d2 = d.dot(ldlt.solve(d));
  return ldlt.info() == Eigen::Success && std::isfinite(d2) ? d2 : -1.0;
}

void Pipeline::AssessIntegrity(bool filter_reset, bool has_motion) {
  const estimator::SwfSummary& summary =
      Visit([](const auto& filter) -> const estimator::SwfSummary& { return filter.Summary(); });
  // The IMU is the motion input of the stereo-inertial estimator (unless it left a gap).
  if (inertial_) has_motion = !imu_gap_;
  estimator::IntegrityEvidence e;
  e.update_status = last_status_;
  e.filter_reset = filter_reset;
  e.gate_suspended = summary.gate_suspended;
  e.has_motion_input = has_motion;
  e.motion_rejected = motion_refused_ || (has_motion && summary.motion_gate_failed);
  e.num_measurements = summary.num_measurements;
  e.num_inliers = summary.num_inliers;
  // A (re)started window has nothing tracked yet: its first frame counts what it measured.
  const bool first_frame = NumPoses() == 1;
  e.tracked_inliers = first_frame ? summary.new_landmarks : summary.tracked_inliers;
  e.tracked_measurements = first_frame ? summary.new_landmarks : summary.tracked_measurements;
  e.rejected_measurements = summary.measurements_gated + summary.measurements_rejected;
  e.motion_disagreement = inertial_ ? ImuDisagreement() : has_motion ? MotionDisagreement() : -1.0;
  e.inlier_sigma = summary.inlier_sigma;
  e.step_m = summary.newest_pose_step_m;
  e.step_rad = summary.newest_pose_step_rad;
  e.position_world = previous_pose_.t;
  e.velocity_world = velocity_world_;
  e.has_covariance = covariance_valid_;
  if (covariance_valid_) e.covariance = camera_covariance_;
  e.image_spread_px = image_spread_px_;
  e.distance_m = distance_m_;
  if (num_disparities_ > 0) {
    float* mid = disparities_.get() + num_disparities_ / 2;
    std::nth_element(disparities_.get(), mid, disparities_.get() + num_disparities_);
    e.median_disparity_px = *mid;
  }
  // Stereo-inertial: a frame whose pose no tracked measurement constrains (the first one after
  // an outage: every landmark is new) is carried by the IMU, and graded like a coasted cycle.
  const bool imu_carried = inertial_ && !filter_reset && !first_frame && !imu_gap_ &&
                           e.tracked_measurements < options_.integrity.min_valid_tracks;
  report_ = imu_carried ? monitor_.AssessCoast(e) : monitor_.Assess(e);
  integrity_.measurements_gated += summary.measurements_gated;
  integrity_.measurements_rejected += summary.measurements_rejected;
  integrity_.landmarks_rejected += summary.landmarks_rejected;
  integrity_.new_landmarks_refused += summary.new_landmarks_refused;
  integrity_.gate_suspensions += summary.gate_suspended ? 1 : 0;
  CountReport();
  if (report_.status == estimator::NavIntegrity::kValid) {
    trusted_pose_ = previous_pose_;
    trusted_covariance_ = camera_covariance_;
    if (inertial_) {
      trusted_state_ = inertial_->NewestPose();
      trusted_state_covariance_ = inertial_->NewestStateCovariance();
      (void)imu_.RestartSinceTrusted(trusted_state_.biases);
    }
    since_trusted_ = Pose<double>();
    frames_since_trusted_ = 0;
    // Smoothed per-frame motion of the VALID frames (time constant ~5 frames).
    {
      const double step_m = last_motion_.t.norm();
      const double step_rad = estimator::LogSO3<double>(last_motion_.R).norm();
      const bool first = smoothed_step_m_ >= 1e8;  // no VALID frame yet
      smoothed_step_m_ = first ? step_m : smoothed_step_m_ + 0.2 * (step_m - smoothed_step_m_);
      smoothed_step_rad_ =
          first ? step_rad : smoothed_step_rad_ + 0.2 * (step_rad - smoothed_step_rad_);
    }
    trusted_motion_ = BoundedConstantVelocity();
    if (frames_since_restart_ >= 0) {
      integrity_.last_recovery_frames = static_cast<std::int32_t>(frames_since_restart_);
      frames_since_restart_ = -1;
    }
  } else {
    // Carried forward by the motion input, or without one by the motion of the trusted frame:
    // not by a constant-velocity extrapolation of the very estimates that are in doubt.
    since_trusted_ = since_trusted_ * (has_motion ? last_motion_ : trusted_motion_);
    ++frames_since_trusted_;
  }
  restart_pending_ = report_.restart || filter_reset;
}

// The report's status and flags into the counters (every estimated or coasted frame).
void Pipeline::CountReport() {
  for (int b = 0; b < estimator::kNumIntegrityFlags; ++b)
    integrity_.flag_counts[b] += (report_.flags >> b) & 1u;
  if (frames_since_restart_ >= 0) ++frames_since_restart_;
  switch (report_.status) {
    case estimator::NavIntegrity::kValid: ++integrity_.frames_valid; break;
    case estimator::NavIntegrity::kDegraded: ++integrity_.frames_degraded; break;
    case estimator::NavIntegrity::kInvalid: ++integrity_.frames_invalid; break;
  }
}

void Pipeline::MakeNav(NavOutput* nav) {
  nav->utime = utime_;
  nav->frame_seq = seq_;
  const bool coasting = coast_frames_ > 0;
  const Pose<double>& pose = coasting ? coast_pose_ : previous_pose_;
  const Eigen::Quaterniond q(pose.R);
  for (int i = 0; i < 3; ++i) nav->position_world_m[i] = pose.t[i];
  nav->orientation_world_q[0] = q.w();
  nav->orientation_world_q[1] = q.x();
  nav->orientation_world_q[2] = q.y();
  nav->orientation_world_q[3] = q.z();
  for (int i = 0; i < 3; ++i) nav->velocity_world_mps[i] = velocity_world_[i];
  // The newest pose's marginal covariance (computed by Estimate for the integrity checks).
  if (coasting || covariance_valid_) {
    const estimator::Mat6<double>& c = coasting ? coast_covariance_ : camera_covariance_;
    for (int r = 0; r < 6; ++r)
      for (int k = 0; k < 6; ++k) nav->covariance[6 * r + k] = c(r, k);
  } else {
    for (double& v : nav->covariance) v = 0.0;
  }
  nav->status = static_cast<std::int8_t>(report_.status);
  nav->integrity_flags = static_cast<std::int32_t>(report_.flags);
  nav->horizontal_protection_m = report_.hpl_m;
  nav->vertical_protection_m = report_.vpl_m;
  nav->integrity_risk = options_.integrity.integrity_risk;
  nav->update_status = static_cast<std::int8_t>(last_status_);
  nav->fault_bits = static_cast<std::int32_t>(FaultBits());
  const estimator::SwfSummary& summary =
      Visit([](const auto& filter) -> const estimator::SwfSummary& { return filter.Summary(); });
  nav->iterations = summary.iterations;
  nav->num_measurements = summary.num_measurements;
}

Status Pipeline::NewestPose(Pose<double>* pose, estimator::Mat6<double>* covariance) {
  if (NumPoses() == 0) return Status::kEmpty;
  if (!covariance_valid_) {
    const Status s = ComputeCovariances();
    if (s != Status::kOk) return s;
    covariance_valid_ = true;
  }
  *pose = NewestCameraPose();
  *covariance = camera_covariance_;
  return Status::kOk;
}

Status Pipeline::MakeMap(MapOutput* map) {
  map->utime = utime_;
  map->frame_seq = seq_;
  map->num_landmarks = 0;
  if (NumPoses() == 0) return Status::kEmpty;
  if (!covariance_valid_) {
    const Status s = ComputeCovariances();
    if (s != Status::kOk) return s;
    covariance_valid_ = true;
  }
  Visit([&](const auto& filter) {
    filter.ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int obs) {
      if (map->num_landmarks >= kMaxMapLandmarks) return;
      MapLandmark& l = map->landmarks[map->num_landmarks++];
      l.id = id;
      for (int i = 0; i < 3; ++i) l.position_world_m[i] = p[i];
      estimator::Mat3<double> c;
      if (!filter.GetLandmarkCovariance(id, &c)) c.setZero();
      l.covariance_m2[0] = c(0, 0);
      l.covariance_m2[1] = c(0, 1);
      l.covariance_m2[2] = c(0, 2);
      l.covariance_m2[3] = c(1, 1);
      l.covariance_m2[4] = c(1, 2);
      l.covariance_m2[5] = c(2, 2);
      l.num_observations = obs;
    });
  });
  return Status::kOk;
}

estimator::ImuSampleVerdict Pipeline::AddImu(const estimator::ImuSample<double>& sample) {
  if (!inertial_) return estimator::ImuSampleVerdict::kDroppedInvalid;
  return imu_.Add(sample);
}

std::int64_t Pipeline::CoastUtime() const {
  return last_dt_s_ > 0.0 ? utime_ + static_cast<std::int64_t>(last_dt_s_ * 1e6) : utime_;
}

int Pipeline::NumLandmarks() const {
  return Visit([](const auto& filter) { return filter.NumLandmarks(); });
}

std::uint32_t Pipeline::FaultBits() const {
  return Visit([](const auto& filter) { return filter.FaultBits(); });
}

const estimator::NavState<double>* Pipeline::NewestNavState() const {
  return inertial_ && inertial_->NumPoses() > 0 ? &inertial_->NewestPose() : nullptr;
}

int Pipeline::NumPoses() const {
  return Visit([](const auto& filter) { return filter.NumPoses(); });
}

bool Pipeline::AddObservation(std::int64_t id, const Vec3<double>& z,
                              const MeasurementNoise& noise) {
  const estimator::Mat3<double> r_sqrt = MeasurementSqrtInformation(noise);
  return Visit([&](auto& filter) { return filter.AddObservation(id, z, r_sqrt); }) == Status::kOk;
}

Pose<double> Pipeline::NewestCameraPose() const {
  return inertial_ ? inertial_model_.CameraPose(inertial_->NewestPose()) : swf_->NewestPose();
}

Status Pipeline::ComputeCovariances() {
  const Status s = Visit([](auto& filter) { return filter.ComputeCovariances(); });
  if (s != Status::kOk) return s;
  camera_covariance_ = inertial_ ? inertial_model_.CameraPoseCovariance(
                                       inertial_->NewestPose(), inertial_->NewestPoseCovariance())
                                 : swf_->NewestPoseCovariance();
  // The calibration's share: each consider parameter adds sigma^2 s s^T.
  const double sb = options_.calibration_baseline_sigma_m;
  const double sd = options_.calibration_disparity_sigma_px;
  camera_covariance_.topLeftCorner<3, 3>() +=
      sb * sb * baseline_sensitivity_ * baseline_sensitivity_.transpose() +
      sd * sd * disparity_sensitivity_ * disparity_sensitivity_.transpose();
  return Status::kOk;
}

void Pipeline::AccumulateCalibrationSensitivity(const Vec3<double>& step_m) {
  if (options_.calibration_baseline_sigma_m <= 0.0 &&
      options_.calibration_disparity_sigma_px <= 0.0)
    return;
  const estimator::StereoCamera<double>& cam = options_.camera;
  // The range the motion was measured across: the mean depth of the window's landmarks from
  // where the step began.
  double depth_sum = 0.0;
  int count = 0;
  Visit([&](const auto& filter) {
    filter.ForEachLandmark([&](std::int64_t, const Vec3<double>& p, int) {
      const double z = previous_pose_.ApplyInverse(p).z();
      if (z > 0.0) {
        depth_sum += z;
        ++count;
      }
    });
  });
  baseline_sensitivity_ += step_m / cam.baseline_m;
  if (count > 0) {
    disparity_sensitivity_ += (depth_sum / count) / (cam.fx * cam.baseline_m) * step_m;
  }
}

}  // namespace swf::app
