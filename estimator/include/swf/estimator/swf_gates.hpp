// SlidingWindowFilter, the integrity gates (SwfOptions::gate_probability, motion_gate_*): what
// keeps a wrong measurement or a wrong motion input out of the solve, and says so in the
// summary and the fault bits. Not in the paper; the tests of docs/integrity.md. Included by
// sliding_window_filter.hpp; not a header to include alone.
#pragma once

#include <cmath>

#include "swf/estimator/sliding_window_filter.hpp"

namespace swf::estimator {

// Covariance of the pose predicted by the process model from `prev` (whose marginal is the
// last computed newest-pose covariance): linearizing r = f(prev, next, u) ~ N(0, Q) gives
// A d_prev + B d_next = w, so d_next = Phi d_prev + B^-1 w with Phi = -B^-1 A and
// P_next = B^-1 (A P_prev A^T + Q) B^-T. Phi carries prev's correlation with the landmarks.
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::PredictPoseCovariance(
    const PoseType& prev, const PoseType& next, const MotionType& u, const StateMat& sqrt_info,
    StateMat* covariance, StateMat* transition) const {
  StateMat a;
  StateMat b;
  (void)model_.ProcessResidual(prev, next, u, &a, &b);
  StateMat w_inv;
  StateMat b_inv;
  if (!FullPivInverse(sqrt_info, &w_inv) || !FullPivInverse(b, &b_inv)) return false;
  *covariance = b_inv * (a * newest_state_cov_ * a.transpose() + w_inv * w_inv.transpose()) *
                b_inv.transpose();
  *transition = -b_inv * a;
  return covariance->allFinite();
}

// Before fusion: the squared Mahalanobis distance of the innovation z - h against its
// covariance R + J_p P_pose J_p^T + J_l P_l J_l^T + J_p C J_l^T + (J_p C J_l^T)^T, with
// C = Phi Cov(prev pose, l). The correlation matters: pose and landmarks drift together, and
// without C the gate would be loose by the whole absolute uncertainty of the path.
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::FailsPredictionGate(const PoseType& pose,
                                                                 const LandmarkSlot& l,
                                                                 const Vec3<S>& z,
                                                                 const Mat3<S>& sqrt_info) {
  if (gate_threshold_ <= S(0)) return false;
  if (!predicted_cov_valid_ || !l.covariance_valid) {
    ++pending_.gate_unchecked;
    return false;
  }
  Vec3<S> h;
  Mat36<S> jp;
  Mat3<S> jl;
  if (!model_.Predict(pose, l.anchor, l.params, &h, &jp, &jl)) {
    ++pending_.gate_unchecked;
    return false;
  }
  Mat3<S> w_inv;
  if (!FullPivInverse(sqrt_info, &w_inv)) return true;
  const Mat3<S> coupling =
      jp * prediction_transition_.template topRows<6>() * l.cross_newest * jl.transpose();
  const Mat3<S> innovation_cov =
      w_inv * w_inv.transpose() +
      jp * predicted_pose_cov_.template topLeftCorner<6, 6>() * jp.transpose() +
      jl * l.covariance * jl.transpose() + coupling + coupling.transpose();
  ++pending_.gate_checked;
  const Vec3<S> e = z - h;
  S d2;
  const bool factored = LdltMahalanobis(innovation_cov, e, &d2);
  return !(factored && std::isfinite(d2) && d2 <= gate_threshold_);
}

// A new landmark's single stereo sighting must determine it: the 3x3 information J^T R^-1 J
// is positive definite and, with max_init_sigma_m, its world covariance is small enough.
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::TriangulationAcceptable(
    const PoseType& pose, const LandmarkAnchor& anchor, const Vec3<S>& params,
    const Mat3<S>& sqrt_info) const {
  Vec3<S> h;
  Mat36<S> jp;  // the models fill the landmark Jacobian only together with the pose's
  Mat3<S> jl;
  if (!model_.Predict(pose, anchor, params, &h, &jp, &jl)) return false;
  const Mat3<S> jw = sqrt_info * jl;
  Mat3<S> params_cov;
  if (!SpdInverse<S, 3>(jw.transpose() * jw, &params_cov)) return false;
  if (options_.max_init_sigma_m <= 0.0) return true;
  Vec3<S> position;
  Mat3<S> dl_dm;
  if (!Model::LandmarkPosition(anchor, params, &position, &dl_dm)) return false;
  const Mat3<S> world_cov = dl_dm * params_cov * dl_dm.transpose();
  const S largest = SymmetricEigenvalues(world_cov)(2);
  return std::isfinite(largest) &&
         largest <= S(options_.max_init_sigma_m * options_.max_init_sigma_m);
}

// Removes the newest pose's measurements that failed the prediction gate, unless too many
// failed (then the prediction is the suspect: keep them, flag kFaultGateSuspended). A landmark
// whose second sighting fails goes whole (the two disagree, and the first alone placed it).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::ApplyPredictionGate() {
  summary_.gate_checked = pending_.gate_checked;
  summary_.gate_unchecked = pending_.gate_unchecked;
  summary_.new_landmarks_refused = pending_.new_landmarks_refused;
  pending_ = SwfSummary{};
  if (num_poses_ == 0) return;
  PoseSlot& p = Newest();
  int failed = 0;
  for (const Observation& o : p.obs) failed += o.gate_failed ? 1 : 0;
  if (failed == 0) return;
  if (failed > S(options_.max_gated_fraction) * S(summary_.gate_checked)) {
    summary_.gate_suspended = true;
    fault_bits_ |= kFaultGateSuspended;
    for (Observation& o : p.obs) o.gate_failed = false;
    return;
  }
  for (std::size_t k = p.obs.size(); k-- > 0;) {
    if (!p.obs[k].gate_failed) continue;
    LandmarkSlot& l = landmarks_[p.obs[k].landmark];
    if (l.prior_index < 0 && l.total_obs == 2 && l.obs_in_window == 2) {
      // Its second sighting disagrees with the first, which alone placed it: either may be
      // the wrong one, and a wrong first sighting would go on rejecting every good later one.
      // Neither is kept; the track starts again from its next sighting.
      RemoveLandmark(p.obs[k].landmark);
      summary_.measurements_gated += 2;
      ++summary_.landmarks_rejected;
      continue;
    }
    --l.obs_in_window;
    --l.total_obs;
    p.obs.erase(k);
    ++summary_.measurements_gated;
  }
}

// After a solve: measurements whose whitened residual, in inlier sigmas, exceeds the gate
// are removed; a landmark with every window measurement failing is removed whole. Returns
// how many measurements went. Stands down (flags) when too many fail.
template <typename Model, int K, int N, int M, int P>
int SlidingWindowFilter<Model, K, N, M, P>::RejectResidualOutliers() {
  if (gate_threshold_ <= S(0)) return 0;
  const S sigma = InlierSigma();
  const S limit = gate_threshold_ * sigma * sigma;
  int checked = 0;
  int failed = 0;
  ForEachUsedSlot([&](int i) { landmarks_[i].lm_count = 0; });
  for (int j = 0; j < num_poses_; ++j) {
    for (Observation& o : Slot(j).obs) {
      o.gate_failed = o.valid && !(o.r.squaredNorm() <= limit);
      if (!o.valid) continue;
      ++checked;
      if (o.gate_failed) {
        ++failed;
        ++landmarks_[o.landmark].lm_count;
      }
    }
  }
  if (failed == 0) return 0;
  if (failed > S(options_.max_gated_fraction) * S(checked)) {
    summary_.gate_suspended = true;
    fault_bits_ |= kFaultGateSuspended;
    return 0;
  }
  ForEachUsedSlot([&](int i) {
    const LandmarkSlot& l = landmarks_[i];
    if (l.lm_count > 0 && l.lm_count == l.obs_in_window) {
      RemoveLandmark(i);
      ++summary_.landmarks_rejected;
    }
  });
  for (int j = 0; j < num_poses_; ++j) {
    PoseSlot& p = Slot(j);
    for (std::size_t k = p.obs.size(); k-- > 0;) {
      if (!p.obs[k].gate_failed) continue;
      --landmarks_[p.obs[k].landmark].obs_in_window;
      p.obs.erase(k);
    }
  }
  summary_.measurements_rejected += failed;
  return failed;
}

template <typename Model, int K, int N, int M, int P>
auto SlidingWindowFilter<Model, K, N, M, P>::GateNewestMotion() -> MotionGateResult {
  MotionGateResult result;
  const bool had_fallback = has_motion_fallback_;
  has_motion_fallback_ = false;
  if (num_poses_ < 2 || !Newest().has_process || motion_gate_threshold_ <= S(0)) return result;
  PoseSlot& p = Newest();
  PoseType fitted = p.pose;
  Mat6<S> information = Mat6<S>::Zero();
  const int inliers = FitNewestPose(&fitted, &information);
  if (inliers < 6) return result;  // too few to fix a pose: nothing to compare
  StateMat unused;
  const Vec6<S> d = Model::Difference(p.pose, fitted, &unused).template head<6>();
  // Covariance of the difference: the prediction's (with the motion noise) plus the fit's,
  // both of the pose part (what the images determine).
  Mat6<S> covariance;
  if (predicted_cov_valid_) {
    covariance = predicted_pose_cov_.template topLeftCorner<6, 6>();
  } else {
    const StateMat w_inv = PlainInverse(p.process_sqrt_info);
    covariance = (w_inv * w_inv.transpose()).template topLeftCorner<6, 6>();
  }
  Mat6<S> fit_covariance;
  if (!LdltInverse(information, &fit_covariance)) return result;
  covariance += fit_covariance;
  S chi2;
  if (!LdltMahalanobis(covariance, d, &chi2)) return result;
  result.chi2 = static_cast<double>(chi2);
  result.failed = !(chi2 <= motion_gate_threshold_);
  if (!result.failed || inliers < options_.motion_gate_min_inliers ||
      !(chi2 > S(options_.motion_overrule_factor) * motion_gate_threshold_)) {
    return result;
  }
  result.overruled = true;
  p.pose = fitted;  // newest_prediction_ stays: the step from it is evidence too
  if (had_fallback) {
    p.motion = motion_fallback_;
    p.process_sqrt_info = motion_fallback_sqrt_info_;
  } else {
    p.process_sqrt_info *= S(options_.motion_gate_weight);
  }
  predicted_cov_valid_ = false;
  for (Observation& o : p.obs) o.gate_failed = false;
  return result;
}

// Robust Gauss-Newton on the newest pose alone against its measurements of landmarks seen
// before (their estimates held; a first sighting was placed from the very prediction under
// test). Returns the inliers (Huber weight 1) at the end and the pose's information.
template <typename Model, int K, int N, int M, int P>
int SlidingWindowFilter<Model, K, N, M, P>::FitNewestPose(PoseType* pose, Mat6<S>* information) {
  const PoseType prediction = *pose;
  const S k = S(options_.huber_k);
  int inliers = 0;
  for (int iteration = 0; iteration < 8; ++iteration) {
    Mat6<S> h = Mat6<S>::Zero();
    Vec6<S> g = Vec6<S>::Zero();
    inliers = 0;
    for (Observation& o : Newest().obs) {
      const LandmarkSlot& l = landmarks_[o.landmark];
      if (l.obs_in_window < 2 && l.prior_index < 0) continue;
      Vec3<S> z_hat;
      Mat36<S> jp;
      Mat3<S> jl;
      if (!model_.Predict(*pose, l.anchor, l.params, &z_hat, &jp, &jl)) continue;
      const Mat3<S> whiten = FitWhitening(prediction, o, l);
      const Vec3<S> r = whiten * (o.z - z_hat);
      const Mat36<S> j = whiten * jp;
      const S norm = r.norm();
      const S w = norm <= k ? S(1) : k / norm;
      inliers += norm <= k ? 1 : 0;
      h += w * j.transpose() * j;
      g += w * j.transpose() * r;
    }
    *information = h;
    Vec6<S> step;
    if (!LdltSolve(h, g, &step)) return 0;
    StateVec delta = StateVec::Zero();
    delta.template head<6>() = step;
    if (!delta.allFinite()) return 0;
    *pose = Model::Retract(*pose, delta);
    if (delta.norm() < S(1e-9)) break;
  }
  return inliers;
}

// (R + J_l P_l J_l^T)^(-1/2) at the prediction, when the landmark's marginal is known: a
// landmark seen from one earlier pose is far less certain than the pixel noise. Held fixed
// over the fit's iterations so that Gauss-Newton converges as on a fixed weighting.
template <typename Model, int K, int N, int M, int P>
auto SlidingWindowFilter<Model, K, N, M, P>::FitWhitening(const PoseType& prediction,
                                                          const Observation& o,
                                                          const LandmarkSlot& l) const -> Mat3<S> {
  Vec3<S> z_hat;
  Mat36<S> jp;
  Mat3<S> jl;
  if (!l.covariance_valid || !model_.Predict(prediction, l.anchor, l.params, &z_hat, &jp, &jl))
    return o.sqrt_info;
  const Mat3<S> r_inv = PlainInverse<S, 3>(o.sqrt_info.transpose() * o.sqrt_info);
  Mat3<S> whitening;
  if (!InverseCholeskyFactor<S, 3>(r_inv + jl * l.covariance * jl.transpose(), &whitening))
    return o.sqrt_info;
  return whitening;
}

}  // namespace swf::estimator
