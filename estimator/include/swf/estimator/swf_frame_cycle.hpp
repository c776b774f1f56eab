// SlidingWindowFilter, the frame cycle: configuration, adding a pose and its measurements,
// Update() (marginalize, solve, gate, solve again), and reading results. The order of one
// Update() is the paper's section 3: marginalization first, so that the solve sees the prior
// it leaves behind. Included by sliding_window_filter.hpp; not a header to include alone.
#pragma once

#include <cmath>
#include <cstdint>

#include "swf/estimator/chi_square.hpp"
#include "swf/estimator/sliding_window_filter.hpp"

namespace swf::estimator {

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::Configure(const Model& model,
                                                               const SwfOptions& options) {
  const core::Status status = options.Validate();
  if (status != core::Status::kOk) return status;
  if (options.window_size < 0 || options.window_size > K) return core::Status::kInvalidArgument;
  model_ = model;
  options_ = options;
  window_ = options.window_size == 0 ? K : options.window_size;
  gate_threshold_ = S(ChiSquareQuantile(3, options.gate_probability));
  motion_gate_threshold_ = S(ChiSquareQuantile(6, options.gate_probability));
  configured_ = true;
  Reset();
  return core::Status::kOk;
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::Reset() {
  num_poses_ = 0;
  head_ = 0;
  for (int i = 0; i < N; ++i) SetUsed(i, false);
  free_slots_.clear();
  for (int i = N - 1; i >= 0; --i) (void)free_slots_.push_back(i);
  ids_.Clear();
  num_landmarks_ = 0;
  prior_landmarks_.clear();
  frames_added_ = 0;
  tau_ = S(1e30);
  residual_scale_ = S(1);
  fault_bits_ = 0;
  summary_ = SwfSummary{};
  pending_ = SwfSummary{};
  covariances_current_ = false;
  factor_current_ = false;
  predicted_cov_valid_ = false;
  has_motion_fallback_ = false;
  retired_.clear();
}

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::AddFirstPose(const PoseType& estimate,
                                                                  const StateMat& covariance) {
  if (num_poses_ != 0) return core::Status::kInvalidArgument;
  StateMat information;
  if (!covariance.allFinite() || !SpdInverse(covariance, &information))
    return core::Status::kInvalidArgument;
  const core::Status status = PushPose(estimate, nullptr, nullptr);
  if (status != core::Status::kOk || Slot(0).fixed) return status;
  for (int c = 0; c < kStateDim; ++c)
    for (int r = 0; r < kStateDim; ++r) prior_[c * kPriorLd + r] = information(r, c);
  return core::Status::kOk;
}

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::AddObservation(
    std::int64_t landmark_id, const Vec3<S>& z, const Mat3<S>& sqrt_information) {
  if (num_poses_ == 0) return core::Status::kNotConfigured;
  if (!z.allFinite() || !sqrt_information.allFinite()) return core::Status::kInvalidArgument;
  factor_current_ = false;
  PoseSlot& pose = Newest();
  if (pose.obs.full()) {
    fault_bits_ |= kFaultMeasurementCapacity;
    return core::Status::kFull;
  }
  int slot = ids_.Find(landmark_id);
  bool gate_failed = false;
  if (slot >= 0) {
    for (const Observation& o : pose.obs)
      if (o.landmark == slot) return core::Status::kInvalidArgument;  // duplicate in frame
    gate_failed = FailsPredictionGate(pose.pose, landmarks_[slot], z, sqrt_information);
  } else {
    Vec3<S> params;
    LandmarkAnchor anchor{};
    if (!model_.InitLandmark(pose.pose, z, &anchor, &params) ||
        !TriangulationAcceptable(pose.pose, anchor, params, sqrt_information)) {
      ++pending_.new_landmarks_refused;
      return core::Status::kInvalidArgument;
    }
    if (free_slots_.empty()) {
      fault_bits_ |= kFaultLandmarkCapacity;
      return core::Status::kFull;
    }
    slot = free_slots_.back();
    free_slots_.pop_back();
    LandmarkSlot& l = landmarks_[slot];
    l = LandmarkSlot{};
    SetUsed(slot, true);
    l.id = landmark_id;
    l.params = params;
    l.anchor = anchor;
    ids_.Insert(landmark_id, slot);
    ++num_landmarks_;
  }
  Observation o;
  o.landmark = slot;
  o.z = z;
  o.sqrt_info = sqrt_information;
  o.gate_failed = gate_failed;
  (void)pose.obs.push_back(o);
  LandmarkSlot& l = landmarks_[slot];
  ++l.obs_in_window;
  ++l.total_obs;
  l.last_frame = frames_added_;
  if (options_.hold_depth_precision > 0.0) AddDepthInformation(z, sqrt_information, &l);
  return core::Status::kOk;
}

// Relative depth information of one sighting, (d / sigma_d)^2: with Z = f b / d, sigma_Z / Z =
// sigma_d / d, and sigma_d^2 = e^T R e for the disparity e = (1, -1, 0) of z = (uL, uR, v). Only
// SwfOptions::hold_depth_precision reads it, so only then is it accumulated (Configure resets).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::AddDepthInformation(const Vec3<S>& z,
                                                                 const Mat3<S>& sqrt_information,
                                                                 LandmarkSlot* l) {
  const Vec3<S> e(S(1), S(-1), S(0));
  const S sigma_d2 = (sqrt_information.inverse().transpose() * e).squaredNorm();
  const S disparity = z[0] - z[1];
  if (disparity > S(0) && sigma_d2 > S(0) && std::isfinite(sigma_d2))
    l->depth_information += disparity * disparity / sigma_d2;
}

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::ReplaceNewestObservation(
    std::int64_t landmark_id, const Vec3<S>& z) {
  if (num_poses_ == 0) return core::Status::kEmpty;
  if (!z.allFinite()) return core::Status::kInvalidArgument;
  const int slot = ids_.Find(landmark_id);
  if (slot < 0) return core::Status::kEmpty;
  if (landmarks_[slot].total_obs <= 1) return core::Status::kInvalidArgument;
  for (Observation& o : Newest().obs) {
    if (o.landmark != slot) continue;
    o.z = z;
    factor_current_ = false;
    return core::Status::kOk;
  }
  return core::Status::kEmpty;
}

// Before the solve, each process input in the window is offered to the model with the current
// estimate of the state it starts from (ReintegratingModel): an IMU interval whose biases have
// moved far is integrated again rather than carried on by its first-order bias correction, and
// its process factor weighted by the new integration's covariance (the model recomputes the
// square-root information the caller gave with AddPoseWithMotion).
// Once per Update, not between iterations, so a solve minimizes one cost throughout.
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::RefreshMotions() {
  if constexpr (ReintegratingModel<Model>) {
    for (int j = 1; j < num_poses_; ++j) {
      PoseSlot& p = Slot(j);
      if (p.has_process && model_.RefreshMotion(Slot(j - 1).pose, &p.motion, &p.process_sqrt_info))
        ++summary_.motions_reintegrated;
    }
  }
}

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::Update() {
  if (!configured_) return core::Status::kNotConfigured;
  summary_ = SwfSummary{};
  retired_.clear();
  factor_current_ = false;
  RefreshMotions();
  const MotionGateResult motion_gate = GateNewestMotion();
  ApplyPredictionGate();
  summary_.motion_chi2 = motion_gate.chi2;
  summary_.motion_gate_failed = motion_gate.failed;
  summary_.motion_overruled = motion_gate.overruled;
  if (options_.mode == SwfMode::kVisualOdometry) {
    if (num_poses_ > window_) {
      DeleteOldestPose();
      summary_.poses_marginalized = 1;
    }
  } else {
    // At most kMaxPoses - window_ poses: each pass removes one.
    while (num_poses_ > window_ && !HoldsOldestPose()) {
      MarginalizeOldestPose();
      ++summary_.poses_marginalized;
    }
  }
  RetireUnsupportedLandmarks();
  core::Status status = Solve();
  for (int pass = 0; pass < options_.max_gate_resolves && IsSolved(status); ++pass) {
    if (RejectResidualOutliers() == 0) break;
    RetireUnsupportedLandmarks();
    status = Solve();
  }
  RecordEvidence();
  covariances_current_ = false;
  predicted_cov_valid_ = false;
  if (!StateIsFinite()) {
    // Local recovery: a non-finite state cannot be repaired in place. Start over; the caller
    // re-initializes with its next AddPose (it sees kNumericalFailure and the sticky bit).
    const std::uint32_t faults = fault_bits_ | kFaultReset | kFaultNonFinite;
    Reset();
    fault_bits_ = faults;
    status = core::Status::kNumericalFailure;
  }
  summary_.status = status;
  return status;
}

template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::GetLandmark(std::int64_t id, Vec3<S>* position) const {
  const int slot = ids_.Find(id);
  if (slot < 0) return false;
  return Model::LandmarkPosition(landmarks_[slot].anchor, landmarks_[slot].params, position,
                                 nullptr);
}

template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::GetLandmarkCovariance(std::int64_t id,
                                                                   Mat3<S>* covariance) const {
  const int slot = ids_.Find(id);
  if (slot < 0) return false;
  Vec3<S> position;
  Mat3<S> j;
  const LandmarkSlot& l = landmarks_[slot];
  if (!Model::LandmarkPosition(l.anchor, l.params, &position, &j)) return false;
  *covariance = j * l.covariance * j.transpose();
  return true;
}

template <typename Model, int K, int N, int M, int P>
auto SlidingWindowFilter<Model, K, N, M, P>::StateCovariance(int j) const -> StateMat {
  StateMat c;
  for (int k = 0; k < kStateDim; ++k)
    for (int r = 0; r < kStateDim; ++r)
      c(r, k) = pose_cov_[(kStateDim * j + k) * kMaxPosesDim + kStateDim * j + r];
  return c;
}

template <typename Model, int K, int N, int M, int P>
double SlidingWindowFilter<Model, K, N, M, P>::MeasurementCost() {
  EvaluateMeasurements(false);
  double cost = 0.0;
  for (int j = 0; j < num_poses_; ++j)
    for (const Observation& o : Slot(j).obs)
      if (o.valid) cost += 0.5 * static_cast<double>(o.r.squaredNorm());
  return cost;
}

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::PushPose(const PoseType& estimate,
                                                              const MotionType* u,
                                                              const StateMat* sqrt_info) {
  if (!configured_) return core::Status::kNotConfigured;
  int limit = window_ + 1;
  if (options_.mode == SwfMode::kBatch) {
    limit = window_;
  } else if (HoldEnabled()) {
    limit = kMaxPoses;  // the window may be held up to the capacity
  }
  if (num_poses_ >= limit) return core::Status::kFull;
  if (num_poses_ == 0) head_ = 0;
  ++num_poses_;
  factor_current_ = false;
  predicted_cov_valid_ = u != nullptr && num_poses_ >= 2 && covariances_current_ &&
                         PredictPoseCovariance(Slot(num_poses_ - 2).pose, estimate, *u, *sqrt_info,
                                               &predicted_pose_cov_, &prediction_transition_);
  newest_prediction_ = estimate;
  PoseSlot& slot = Newest();
  slot.pose = estimate;
  slot.obs.clear();
  slot.fixed = false;
  slot.has_process = u != nullptr;
  if (u != nullptr) {
    slot.motion = *u;
    slot.process_sqrt_info = *sqrt_info;
  }
  if (num_poses_ == 1) InitializePrior();
  ++frames_added_;
  return core::Status::kOk;
}

template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::HoldEnabled() const {
  return (options_.hold_sightings > 0 || options_.hold_depth_precision > 0.0) &&
         options_.mode != SwfMode::kVisualOdometry && options_.mode != SwfMode::kBatch;
}

// A landmark whose first estimate would still be poor: fewer sightings than hold_sightings, or
// a relative depth precision from its sightings worse than hold_depth_precision
// (1 / sqrt(depth_information) > p, i.e. depth_information * p^2 < 1).
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::IsYoung(const LandmarkSlot& l) const {
  if (l.total_obs < options_.hold_sightings) return true;
  const S p = S(options_.hold_depth_precision);
  return p > S(0) && l.depth_information * p * p < S(1);
}

// Whether the oldest pose stays in the window (SwfOptions::hold_sightings,
// hold_depth_precision): it sees a landmark that has not entered the prior, is still tracked
// and is still young, and the window has room for the newest pose without it.
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::HoldsOldestPose() const {
  if (!HoldEnabled() || num_poses_ >= kMaxPoses) return false;
  for (const Observation& o : Slot(0).obs) {
    const LandmarkSlot& l = landmarks_[o.landmark];
    if (l.prior_index < 0 && l.last_frame == frames_added_ && IsYoung(l)) return true;
  }
  return false;
}

template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::StateIsFinite() const {
  for (int j = 0; j < num_poses_; ++j) {
    const StateVec d = Model::Difference(prior_pose_lin_, Slot(j).pose, &scratch_jacobian_);
    if (!d.allFinite()) return false;
  }
  bool finite = true;
  ForEachUsedSlot([&](int i) { finite = finite && landmarks_[i].params.allFinite(); });
  if (!finite) return false;
  for (int r = 0; r < prior_dim_; ++r)
    if (!std::isfinite(prior_g_[r])) return false;
  return true;
}

// The health monitor's evidence from the final linearization (integrity.hpp).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::RecordEvidence() {
  summary_.inlier_sigma = static_cast<double>(options_.robust ? residual_scale_ : S(1));
  double chi2 = 0.0;
  int inliers = 0;
  int total = 0;
  for (int j = 0; j < num_poses_; ++j) {
    for (const Observation& o : Slot(j).obs) {
      ++total;
      if (!o.valid) continue;
      chi2 += static_cast<double>(o.r.squaredNorm());
      inliers += o.weight >= S(1) ? 1 : 0;
    }
  }
  summary_.num_measurements = total;
  summary_.measurement_chi2 = chi2;
  summary_.num_inliers = inliers;
  summary_.tracked_measurements = 0;
  summary_.tracked_inliers = 0;
  summary_.new_landmarks = 0;
  if (num_poses_ == 0) return;
  for (const Observation& o : Newest().obs) {
    const bool tracked = landmarks_[o.landmark].obs_in_window > 1;
    summary_.tracked_measurements += tracked ? 1 : 0;
    summary_.tracked_inliers += tracked && o.valid && o.weight >= S(1) ? 1 : 0;
    summary_.new_landmarks += tracked ? 0 : 1;
  }
  if (num_poses_ > 0) {
    StateMat unused;
    const StateVec d = Model::Difference(newest_prediction_, Newest().pose, &unused);
    summary_.newest_pose_step_m = static_cast<double>(d.template head<3>().norm());
    summary_.newest_pose_step_rad = static_cast<double>(d.template segment<3>(3).norm());
  }
}

}  // namespace swf::estimator
