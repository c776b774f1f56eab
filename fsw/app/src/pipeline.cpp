#include "swf/app/pipeline.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <new>

namespace swf::app {

using core::Status;
using estimator::Pose;
using estimator::Vec3;

Status Pipeline::Configure(const PipelineOptions& options) {
  if (!(options.measurement_sigma_px > 0.0) || !(options.process_sigma_m > 0.0) ||
      !(options.process_sigma_rad > 0.0) || !options.camera.Valid() || options.width_px <= 0 ||
      options.height_px <= 0 || options.width_px > frontend::kMaxImageWidth ||
      options.height_px > frontend::kMaxImageHeight) {
    return Status::kInvalidArgument;
  }
  if (options.swf.mode == estimator::SwfMode::kBatch) return Status::kInvalidArgument;
  options_ = options;
  // Everything large is created here, once, before the loop starts.
  frontend_.reset(new (std::nothrow) frontend::Frontend());
  output_.reset(new (std::nothrow) frontend::FrameOutput());
  swf_.reset(new (std::nothrow) FlightSwf());
  estimates_.reset(new (std::nothrow) frontend::LandmarkEstimate[kMaxLandmarks]);
  sightings_.reset(new (std::nothrow) FirstSighting[kMaxSightings]);
  if (!frontend_ || !output_ || !swf_ || !estimates_ || !sightings_) return Status::kFull;
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
  s = swf_->Configure(model, options_.swf);
  if (s != Status::kOk) return s;
  r_sqrt_ = estimator::Mat3<double>::Identity() / options_.measurement_sigma_px;
  q_sqrt_.setZero();
  q_sqrt_.diagonal() << Vec3<double>::Constant(1.0 / options_.process_sigma_m),
      Vec3<double>::Constant(1.0 / options_.process_sigma_rad);
  for (std::uint32_t i = 0; i < kMaxSightings; ++i) sightings_[i] = FirstSighting{};
  has_previous_pose_ = false;
  has_before_previous_ = false;
  frames_estimated_ = 0;
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
  if (has_previous_pose_ && swf_->NumPoses() > 0) {
    prediction.has_pose = true;
    prediction.world_T_camera =
        has_before_previous_ ? previous_pose_ * (before_previous_pose_.Inverse() * previous_pose_)
                             : previous_pose_;
    std::size_t n = 0;
    swf_->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int /*obs*/) {
      if (n < static_cast<std::size_t>(kMaxLandmarks)) {
        estimates_[n].id = static_cast<std::uint32_t>(id);
        estimates_[n].p_world = p;
        ++n;
      }
    });
    prediction.landmarks = estimates_.get();
    prediction.num_landmarks = n;
  }
  return frontend_->ProcessFrame(current_, prediction, output_.get());
}

Status Pipeline::Estimate(const Pose<double>* motion) {
  if (!configured_) return Status::kNotConfigured;
  Status s;
  if (swf_->NumPoses() == 0) {
    // First frame, or re-initialization after the filter's local recovery (reset): start from
    // the last good estimate.
    s = swf_->AddPose(has_previous_pose_ ? previous_pose_ : options_.initial_world_T_camera);
    has_before_previous_ = false;
  } else {
    // The navigation system's relative motion when there is one (IMU); otherwise repeat the last
    // estimated motion (constant velocity: can run away under the rotation/translation
    // ambiguity of a narrow field of view, estimator/README.md).
    s = motion != nullptr ? swf_->AddPoseWithMotion(*motion, q_sqrt_)
                          : swf_->AddPoseConstantVelocity(q_sqrt_);
  }
  if (s != Status::kOk) {
    last_status_ = s;
    return s;
  }
  for (const frontend::StereoMeasurement& m : output_->measurements) {
    if (m.quality < options_.min_quality) continue;
    (void)swf_->AddObservation(m.landmark_id, Vec3<double>(m.u_left, m.u_right, m.v), r_sqrt_);
  }
  for (const frontend::NewLandmark& n : output_->new_landmarks) {
    if (swf_->AddObservation(n.landmark_id, Vec3<double>(n.u_left, n.u_right, n.v), r_sqrt_) ==
        Status::kOk) {
      FirstSighting& f = sightings_[n.landmark_id % kMaxSightings];
      f.frame_seq = seq_;
      f.u_left = static_cast<float>(n.u_left);
      f.v = static_cast<float>(n.v);
    }
  }
  s = swf_->Update();
  last_status_ = s;
  covariance_valid_ = false;
  if (swf_->NumPoses() > 0) {
    if (has_previous_pose_) {
      before_previous_pose_ = previous_pose_;
      has_before_previous_ = true;
    }
    previous_pose_ = swf_->NewestPose();
    has_previous_pose_ = true;
  }
  ++frames_estimated_;
  return s == Status::kNotConverged ? Status::kOk : s;
}

void Pipeline::MakeNav(NavOutput* nav) {
  nav->utime = utime_;
  nav->frame_seq = seq_;
  const Pose<double>& pose = previous_pose_;
  const Eigen::Quaterniond q(pose.R);
  for (int i = 0; i < 3; ++i) nav->position_world_m[i] = pose.t[i];
  nav->orientation_world_q[0] = q.w();
  nav->orientation_world_q[1] = q.x();
  nav->orientation_world_q[2] = q.y();
  nav->orientation_world_q[3] = q.z();
  const double dt_s = static_cast<double>(utime_ - previous_utime_) * 1e-6;
  for (int i = 0; i < 3; ++i) {
    nav->velocity_world_mps[i] =
        has_before_previous_ && dt_s > 0.0 ? (pose.t[i] - before_previous_pose_.t[i]) / dt_s : 0.0;
  }
  previous_utime_ = utime_;
  // The newest pose's marginal covariance (a dense solve over the reduced system).
  if (swf_->NumPoses() > 0 && swf_->ComputeCovariances() == Status::kOk) {
    covariance_valid_ = true;
    const estimator::Mat6<double>& c = swf_->NewestPoseCovariance();
    for (int r = 0; r < 6; ++r)
      for (int k = 0; k < 6; ++k) nav->covariance[6 * r + k] = c(r, k);
  } else {
    for (double& v : nav->covariance) v = 0.0;
  }
  nav->status = static_cast<std::int8_t>(last_status_);
  nav->fault_bits = static_cast<std::int32_t>(swf_->FaultBits());
  nav->iterations = swf_->Summary().iterations;
  nav->num_measurements = swf_->Summary().num_measurements;
}

Status Pipeline::NewestPose(Pose<double>* pose, estimator::Mat6<double>* covariance) {
  if (swf_->NumPoses() == 0) return Status::kEmpty;
  if (!covariance_valid_) {
    const Status s = swf_->ComputeCovariances();
    if (s != Status::kOk) return s;
    covariance_valid_ = true;
  }
  *pose = swf_->NewestPose();
  *covariance = swf_->NewestPoseCovariance();
  return Status::kOk;
}

Status Pipeline::MakeMap(MapOutput* map) {
  map->utime = utime_;
  map->frame_seq = seq_;
  map->num_landmarks = 0;
  if (swf_->NumPoses() == 0) return Status::kEmpty;
  if (!covariance_valid_) {
    const Status s = swf_->ComputeCovariances();
    if (s != Status::kOk) return s;
    covariance_valid_ = true;
  }
  swf_->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int obs) {
    if (map->num_landmarks >= kMaxMapLandmarks) return;
    MapLandmark& l = map->landmarks[map->num_landmarks++];
    l.id = id;
    for (int i = 0; i < 3; ++i) l.position_world_m[i] = p[i];
    estimator::Mat3<double> c;
    if (!swf_->GetLandmarkCovariance(id, &c)) c.setZero();
    l.covariance_m2[0] = c(0, 0);
    l.covariance_m2[1] = c(0, 1);
    l.covariance_m2[2] = c(0, 2);
    l.covariance_m2[3] = c(1, 1);
    l.covariance_m2[4] = c(1, 2);
    l.covariance_m2[5] = c(2, 2);
    l.num_observations = obs;
  });
  return Status::kOk;
}

}  // namespace swf::app
