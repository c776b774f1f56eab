// SlidingWindowFilter, robust Gauss-Newton (section 3.1.3): linearization of the measurements
// and the process factors, Huber weights, the reduced system S over [poses ; prior landmarks]
// with the free landmarks eliminated (eqs. 6-7, Figs. 4-8), the iteration with backtracking, and
// the marginal covariances of the result. Included by sliding_window_filter.hpp; not a header
// to include alone.
#pragma once

#include <algorithm>
#include <cmath>

#include "swf/estimator/sliding_window_filter.hpp"

namespace swf::estimator {

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::ComputeNewestCovariance() {
  if (num_poses_ == 0) return core::Status::kNotConfigured;
  covariances_current_ = false;
  ForEachUsedSlot([&](int i) { landmarks_[i].covariance_valid = false; });
  // The covariance at the last Gauss-Newton iteration's linearization point, from that
  // iteration's factor: factorizing again at the final estimate, one (converged, small) step
  // further, cost as much as the iteration itself and moved the covariance by second-order
  // terms only (an iterated EKF reports its covariance at its last linearization point too).
  // Only when the window or its measurements changed since is the system built and factorized
  // at the current estimate.
  if (!factor_current_) {
    EvaluateMeasurements(true);
    const core::Status status = BuildAndFactor();
    if (status != core::Status::kOk) return status;
    factor_current_ = true;
  }
  // The newest state's columns of S^-1 (its rows of the pose block and its correlation with
  // the prior landmarks): a forward and a backward O(n^2) solve per kCovarianceWidth columns,
  // nothing else of the inverse.
  const int npd = kStateDim * num_poses_;
  const int newest0 = npd - kStateDim;
  const int nq = static_cast<int>(prior_landmarks_.size());
  S* const columns = covariance_columns_;
  for (int c0 = newest0; c0 < npd; c0 += kCovarianceWidth) {
    const int count = std::min(kCovarianceWidth, npd - c0);
    dense_.InverseColumns(c0, count, columns, kMaxDense);
    for (int k = 0; k < count; ++k) {
      const int c = c0 + k;
      const S* column = columns + k * kMaxDense;
      for (int r = 0; r < npd; ++r) pose_cov_[c * kMaxPosesDim + r] = column[r];
      for (int q = 0; q < nq; ++q)  // Cov(newest pose, prior landmark q)
        for (int r = 0; r < 3; ++r)
          landmarks_[prior_landmarks_[q]].cross_newest(c - newest0, r) = column[npd + 3 * q + r];
    }
  }
  ZeroFixedPoseCovariance();
  newest_state_cov_ = StateCovariance(num_poses_ - 1);
  newest_pose_cov_ = newest_state_cov_.template topLeftCorner<6, 6>();
  covariances_current_ = newest_state_cov_.allFinite();
  return core::Status::kOk;
}

// A fixed pose is known exactly; its identity rows in S only stand in for "no update".
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::ZeroFixedPoseCovariance() {
  const int npd = kStateDim * num_poses_;
  for (int j = 0; j < num_poses_; ++j) {
    if (!Slot(j).fixed) continue;
    for (int k = kStateDim * j; k < kStateDim * j + kStateDim; ++k)
      for (int m = 0; m < npd; ++m)
        pose_cov_[k * kMaxPosesDim + m] = pose_cov_[m * kMaxPosesDim + k] = S(0);
  }
}

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::ComputeCovariances() {
  const core::Status status = ComputeNewestCovariance();
  if (status != core::Status::kOk) return status;
  const int npd = kStateDim * num_poses_;
  const int newest0 = npd - kStateDim;
  const int nq = static_cast<int>(prior_landmarks_.size());
  S* const columns = covariance_columns_;
  // The rest of the pose block of S^-1 (free landmarks need every pair of their poses): the
  // older states' block as X^T X from forward solves only (a third of the flops of full
  // columns; the held window's covariance was mostly these), its rows with the newest state
  // mirrored from the newest columns above, so the block is exactly symmetric.
  dense_.LeadingInverseBlock(newest0, pose_cov_, kMaxPosesDim, leading_inverse_workspace_);
  for (int c = 0; c < newest0; ++c)
    for (int r = newest0; r < npd; ++r)
      pose_cov_[c * kMaxPosesDim + r] = pose_cov_[r * kMaxPosesDim + c];
  ZeroFixedPoseCovariance();
  // A prior landmark's marginal is the diagonal block of L^-T L^-1 over its three columns c:
  // sums over rows >= c of the forward columns of L^-1 (a sixth of the InverseColumn flops),
  // kCovarianceWidth columns per solve, kCovarianceWidth landmarks per round.
  const int n = dense_.size();
  for (int q0 = 0; q0 < nq; q0 += kCovarianceWidth) {
    const int lm_count = std::min(kCovarianceWidth, nq - q0);
    const int first = npd + 3 * q0;
    for (int c0 = first; c0 < first + 3 * lm_count; c0 += kCovarianceWidth) {
      dense_.FactorInverseColumns(c0, std::min(kCovarianceWidth, first + 3 * lm_count - c0),
                                  columns + (c0 - first) * kMaxDense, kMaxDense);
    }
    for (int q = q0; q < q0 + lm_count; ++q) {
      LandmarkSlot& l = landmarks_[prior_landmarks_[q]];
      const int c0 = npd + 3 * q;
      const S* fc = columns + (c0 - first) * kMaxDense;
      for (int k = 0; k < 3; ++k) {
        for (int r = k; r < 3; ++r) {
          S sum = S(0);
          for (int i = c0 + r; i < n; ++i) sum += fc[k * kMaxDense + i] * fc[r * kMaxDense + i];
          l.covariance(r, k) = l.covariance(k, r) = sum;
        }
      }
      l.covariance_valid = l.covariance.allFinite();
    }
  }
  ForEachUsedSlot([&](int i) {
    LandmarkSlot& l = landmarks_[i];
    if (l.prior_index >= 0 || !l.invertible) return;
    Mat3<S> cross = Mat3<S>::Zero();  // sum_a sum_b W_a^T Sigma(ja, jb) W_b
    // dl = h^-1 (b - sum_a W_a^T dp_a): Cov(newest, l) = -sum_a Sigma(newest, ja) W_a h^-1
    // (W_a couples the landmark to the pose part of state ja only: its first 6 columns).
    l.cross_newest.setZero();
    const auto sigma = [&](int ja, int jb) {  // Sigma(ja, jb), pose parts
      return Eigen::Map<const Mat6<S>, Eigen::Unaligned, Eigen::OuterStride<>>(
          pose_cov_ + (kStateDim * jb) * kMaxPosesDim + kStateDim * ja,
          Eigen::OuterStride<>(kMaxPosesDim));
    };
    for (int a = l.adj_begin; a < l.adj_end; ++a) {
      const Observation& oa = ObsAt(adj_[a]);
      const Eigen::Map<const Eigen::Matrix<S, kStateDim, 6>, Eigen::Unaligned, Eigen::OuterStride<>>
          newest_a(pose_cov_ + (kStateDim * adj_[a].pose) * kMaxPosesDim + npd - kStateDim,
                   Eigen::OuterStride<>(kMaxPosesDim));
      l.cross_newest -= newest_a * oa.w_pl * l.h_inv;
      // The pose block is symmetric between different states: the pair (b, a) is the
      // transpose of (a, b), so each pair is formed once (a landmark has one measurement per
      // state, so a != b means different states).
      const Eigen::Matrix<S, 3, 6> wa_t = oa.w_pl.transpose();
      for (int b = l.adj_begin; b < a; ++b) {
        const Mat3<S> t = wa_t * sigma(adj_[a].pose, adj_[b].pose) * ObsAt(adj_[b]).w_pl;
        cross += t + t.transpose();
      }
      cross += wa_t * sigma(adj_[a].pose, adj_[a].pose) * oa.w_pl;
    }
    l.covariance = l.h_inv + l.h_inv * cross * l.h_inv;
    l.covariance_valid = l.covariance.allFinite();
  });
  return core::Status::kOk;
}

// Whitened residuals (and Jacobians) of every measurement at the current state.
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::EvaluateMeasurements(bool with_jacobians) {
  for (int j = 0; j < num_poses_; ++j) {
    PoseSlot& p = Slot(j);
    for (Observation& o : p.obs) EvaluateObservation(p.pose, &o, with_jacobians);
  }
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::EvaluateObservation(const PoseType& pose,
                                                                 Observation* o,
                                                                 bool with_jacobians) {
  Vec3<S> h;
  Mat36<S> jp;
  Mat3<S> jl;
  const LandmarkSlot& lm = landmarks_[o->landmark];
  o->valid = model_.Predict(pose, lm.anchor, lm.params, &h, with_jacobians ? &jp : nullptr, &jl);
  if (!o->valid) return;
  o->r = o->sqrt_info * (o->z - h);
  if (!o->r.allFinite()) {
    o->valid = false;
    fault_bits_ |= kFaultNonFinite;
    return;
  }
  if (with_jacobians) {
    if (options_.first_estimate_jacobians && lm.prior_index >= 0) {
      // First-estimate Jacobians: the prior fixed this landmark's linearization when it
      // entered; linearizing its later measurements elsewhere would give the prior and the
      // window different Jacobians for the same variable and create spurious information.
      Vec3<S> h_first;
      (void)model_.Predict(pose, lm.anchor, first_estimate_[lm.prior_index], &h_first, &jp, &jl);
    }
    o->jp = o->sqrt_info * jp;
    o->jl = o->sqrt_info * jl;
  }
}

// The process factor between states j - 1 and j (eq. 2), whitened: r = W e and the Jacobians
// W A, W B with respect to the two states (W^T W = Q^-1). The one linearization of the process
// model that the cost, the reduced system and marginalization all use.
template <typename Model, int K, int N, int M, int P>
auto SlidingWindowFilter<Model, K, N, M, P>::WhitenedProcessFactor(int j, StateMat* a,
                                                                   StateMat* b) const -> StateVec {
  const PoseSlot& p = Slot(j);
  const StateVec e = model_.ProcessResidual(Slot(j - 1).pose, p.pose, p.motion, a, b);
  *a = p.process_sqrt_info * *a;
  *b = p.process_sqrt_info * *b;
  return p.process_sqrt_info * e;
}

// Huber threshold from the inlier standard deviation: sigma_hat = median |r| / median of the
// chi distribution with 3 degrees of freedom (1.5382), floored at the nominal 1 and capped at
// max_robust_sigma. Without the cap the threshold follows the median up while the state
// diverges (seen on EuRoC and KITTI: tens of nominal sigmas within a few frames), and
// the data that disagrees with the drifting state gets its full weight back exactly then.
// The uncapped scale is kept as evidence for the health monitor (residual_scale_).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::UpdateRobustWeights() {
  int n = 0;
  for (int j = 0; j < num_poses_; ++j)
    for (const Observation& o : Slot(j).obs)
      if (o.valid) norms_[n++] = o.r.norm();
  if (!options_.robust || n == 0) {
    tau_ = S(1e30);
  } else {
    std::nth_element(norms_, norms_ + n / 2, norms_ + n);
    residual_scale_ = std::max(S(1), norms_[n / 2] / S(1.5382));
    tau_ = S(options_.huber_k) * std::min(residual_scale_, S(options_.max_robust_sigma));
  }
  summary_.huber_threshold = static_cast<double>(tau_);
  ApplyWeights();
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::ApplyWeights() {
  int downweighted = 0;
  for (int j = 0; j < num_poses_; ++j) {
    for (Observation& o : Slot(j).obs) {
      if (!o.valid) continue;
      const S norm = o.r.norm();
      o.weight = norm <= tau_ ? S(1) : tau_ / norm;
      downweighted += o.weight < S(1) ? 1 : 0;
    }
  }
  summary_.num_downweighted = downweighted;
}

template <typename Model, int K, int N, int M, int P>
auto SlidingWindowFilter<Model, K, N, M, P>::HuberCost(S squared_norm) const -> S {
  const S norm = std::sqrt(squared_norm);
  return norm <= tau_ ? S(0.5) * squared_norm : tau_ * norm - S(0.5) * tau_ * tau_;
}

// Robust cost of all three information sources at the current state (residuals must be
// evaluated). Used to accept or shorten steps.
template <typename Model, int K, int N, int M, int P>
auto SlidingWindowFilter<Model, K, N, M, P>::TotalCost() -> S {
  S cost = S(0);
  for (int j = 0; j < num_poses_; ++j)
    for (const Observation& o : Slot(j).obs)
      if (o.valid) cost += HuberCost(o.r.squaredNorm());
  for (int j = 1; j < num_poses_; ++j) {
    const PoseSlot& p = Slot(j);
    if (!p.has_process) continue;
    StateMat a;
    StateMat b;
    cost += S(0.5) * WhitenedProcessFactor(j, &a, &b).squaredNorm();
  }
  // 0.5 Delta^T Pi Delta - g^T Delta = Delta^T (0.5 (grad + g) - g) with grad = Pi Delta - g.
  PriorGradient();
  for (int r = 0; r < prior_dim_; ++r)
    cost += prior_delta_[r] * (S(0.5) * (prior_grad_[r] + prior_g_[r]) - prior_g_[r]);
  return cost;
}

// Builds the reduced system S dx_D = s over [poses ; prior landmarks] (free landmarks
// eliminated) and factorizes it. Measurements must be evaluated with Jacobians and weighted.
template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::BuildAndFactor() {
  const int np = num_poses_;
  const int nq = static_cast<int>(prior_landmarks_.size());
  const int lm0 = kStateDim * np;
  const int n = lm0 + 3 * nq;
  dense_.Reset(n);
  for (int i = 0; i < n; ++i) rhs_[i] = S(0);
  ForEachUsedSlot([&](int i) {
    landmarks_[i].h.setZero();
    landmarks_[i].b.setZero();
    landmarks_[i].lm_count = 0;
  });
  // Measurements (H^T R^-1 H and its right-hand side).
  for (int j = 0; j < np; ++j) {
    for (Observation& o : Slot(j).obs) {
      if (!o.valid) continue;
      const S w = o.weight;
      LandmarkSlot& l = landmarks_[o.landmark];
      dense_.AddBlock(kStateDim * j, kStateDim * j, w * o.jp.transpose() * o.jp);
      Blk<6, 1>(rhs_, kMaxDense, kStateDim * j, 0) += w * o.jp.transpose() * o.r;
      l.h += w * o.jl.transpose() * o.jl;
      l.b += w * o.jl.transpose() * o.r;
      o.w_pl = w * o.jp.transpose() * o.jl;
      if (l.prior_index >= 0)
        dense_.AddBlock(lm0 + 3 * l.prior_index, kStateDim * j, o.w_pl.transpose());
      ++l.lm_count;
    }
  }
  // Adjacency of free landmarks (counting sort by slot) for the Schur complement.
  int offset = 0;
  ForEachUsedSlot([&](int i) {
    LandmarkSlot& l = landmarks_[i];
    l.adj_begin = offset;
    offset += l.lm_count;
    l.adj_end = offset;
    l.lm_count = 0;
  });
  for (int j = 0; j < np; ++j) {
    const PoseSlot& p = Slot(j);
    for (int k = 0; k < static_cast<int>(p.obs.size()); ++k) {
      if (!p.obs[k].valid) continue;
      LandmarkSlot& l = landmarks_[p.obs[k].landmark];
      adj_[l.adj_begin + l.lm_count++] = AdjEntry{j, k};
    }
  }
  // Process model (D^T Q^-1 D).
  for (int j = 1; j < np; ++j) {
    const PoseSlot& p = Slot(j);
    if (!p.has_process) continue;
    StateMat a;
    StateMat b;
    const StateVec r = WhitenedProcessFactor(j, &a, &b);
    dense_.AddBlock(kStateDim * (j - 1), kStateDim * (j - 1), a.transpose() * a);
    dense_.AddBlock(kStateDim * j, kStateDim * j, b.transpose() * b);
    dense_.AddBlock(kStateDim * j, kStateDim * (j - 1), b.transpose() * a);
    Blk<kStateDim, 1>(rhs_, kMaxDense, kStateDim * (j - 1), 0) -= a.transpose() * r;
    Blk<kStateDim, 1>(rhs_, kMaxDense, kStateDim * j, 0) -= b.transpose() * r;
  }
  // Prior (L^T Pi L): pose block -> pose 0, landmark q -> lm0 + 3q.
  AddPrior(lm0);
  // Prior landmarks' own measurement information.
  for (int q = 0; q < nq; ++q) {
    const LandmarkSlot& l = landmarks_[prior_landmarks_[q]];
    dense_.AddBlock(lm0 + 3 * q, lm0 + 3 * q, l.h);
    Blk<3, 1>(rhs_, kMaxDense, lm0 + 3 * q, 0) += l.b;
  }
  // Schur complement of the free landmarks onto the poses.
  ForEachUsedSlot([&](int i) {
    LandmarkSlot& l = landmarks_[i];
    l.invertible = false;
    if (l.prior_index >= 0 || l.adj_begin == l.adj_end) return;
    Mat3<S> h_inv;
    if (!SpdInverse(l.h, &h_inv) || !(l.h.trace() > S(0))) {
      fault_bits_ |= kFaultDegenerateLandmark;
      return;  // held at its current estimate for this iteration
    }
    l.h_inv = h_inv;
    l.invertible = true;
    for (int a = l.adj_begin; a < l.adj_end; ++a) {
      const Observation& oa = ObsAt(adj_[a]);
      const Eigen::Matrix<S, 6, 3> x = oa.w_pl * l.h_inv;
      Blk<6, 1>(rhs_, kMaxDense, kStateDim * adj_[a].pose, 0) -= x * l.b;
      for (int b = l.adj_begin; b < l.adj_end; ++b) {
        if (adj_[a].pose < adj_[b].pose) continue;
        const Observation& ob = ObsAt(adj_[b]);
        dense_.AddBlock(kStateDim * adj_[a].pose, kStateDim * adj_[b].pose,
                        -(x * ob.w_pl.transpose()));
      }
    }
  });
  // Fixed poses: identity rows, zero right-hand side (conditioning on their value).
  for (int j = 0; j < np; ++j) {
    if (!Slot(j).fixed) continue;
    for (int k = kStateDim * j; k < kStateDim * j + kStateDim; ++k) {
      for (int c = 0; c <= k; ++c) dense_.At(k, c) = S(0);
      for (int r = k; r < n; ++r) dense_.At(r, k) = S(0);
      dense_.At(k, k) = S(1);
      rhs_[k] = S(0);
    }
  }
  summary_.dense_dimension = n;
  const core::Status status = dense_.Factorize();
  if (status != core::Status::kOk) fault_bits_ |= kFaultNotPositiveDefinite;
  return status;
}

template <typename Model, int K, int N, int M, int P>
core::Status SlidingWindowFilter<Model, K, N, M, P>::Solve() {
  int total = 0;
  for (int j = 0; j < num_poses_; ++j) total += static_cast<int>(Slot(j).obs.size());
  summary_.num_measurements = total;
  summary_.state_dimension = kStateDim * num_poses_ + 3 * num_landmarks_;
  summary_.termination = SwfTermination::kNoSolve;
  factor_current_ = false;
  if (num_poses_ == 0) return core::Status::kOk;
  core::Status status = core::Status::kOk;
  SwfTermination termination = SwfTermination::kMaxIterations;
  for (int it = 0; it < options_.max_iterations; ++it) {
    EvaluateMeasurements(true);
    UpdateRobustWeights();
    const S cost0 = TotalCost();
    if (it == 0) summary_.initial_cost = static_cast<double>(cost0);
    summary_.final_cost = static_cast<double>(cost0);
    status = BuildAndFactor();
    if (status != core::Status::kOk) {
      termination = SwfTermination::kNumericalFailure;
      break;
    }
    dense_.SolveInPlace(rhs_);
    const int lm0 = kStateDim * num_poses_;
    S max_step = S(0);
    bool finite = true;
    for (int i = 0; i < dense_.size(); ++i) {
      max_step = std::max(max_step, std::abs(rhs_[i]));
      finite = finite && std::isfinite(rhs_[i]);
    }
    ForEachUsedSlot([&](int i) {
      LandmarkSlot& l = landmarks_[i];
      if (l.prior_index >= 0) {
        l.delta = Blk<3, 1>(rhs_, kMaxDense, lm0 + 3 * l.prior_index, 0);
        return;
      }
      l.delta.setZero();
      if (!l.invertible) return;
      Vec3<S> g = l.b;
      for (int a = l.adj_begin; a < l.adj_end; ++a)
        g -= ObsAt(adj_[a]).w_pl.transpose() *
             Blk<6, 1>(rhs_, kMaxDense, kStateDim * adj_[a].pose, 0);
      l.delta = l.h_inv * g;
      max_step = std::max(max_step, l.delta.cwiseAbs().maxCoeff());
      finite = finite && l.delta.allFinite();
    });
    if (!finite) {
      fault_bits_ |= kFaultNonFinite;
      status = core::Status::kNumericalFailure;
      termination = SwfTermination::kNumericalFailure;
      break;
    }
    // Step with backtracking: accept the first step length that does not raise the cost.
    Backup();
    S alpha = S(1);
    S cost1 = S(0);
    bool accepted = false;
    for (int attempt = 0; attempt <= options_.max_backtracking; ++attempt) {
      ApplyStep(alpha);
      EvaluateMeasurements(false);
      cost1 = TotalCost();
      if (std::isfinite(cost1) && cost1 <= cost0) {
        accepted = true;
        break;
      }
      Restore();
      alpha *= S(0.5);
    }
    if (!accepted) {  // no descent along the Gauss-Newton direction: at the minimum
      termination = SwfTermination::kNoDescent;
      break;
    }
    summary_.iterations = it + 1;
    summary_.final_cost = static_cast<double>(cost1);
    if (cost0 - cost1 <= S(options_.relative_cost_tolerance) * cost0) {
      termination = SwfTermination::kCostTolerance;
      break;
    }
    if (alpha * max_step <= S(options_.step_tolerance)) {
      termination = SwfTermination::kStepTolerance;
      break;
    }
  }
  summary_.termination = termination;
  // The last iteration's factor (not overwritten by the solve) is the covariances' (above).
  factor_current_ = dense_.IsFactorized();
  if (status == core::Status::kOk && !summary_.Converged()) {
    fault_bits_ |= kFaultNotConverged;
    status = core::Status::kNotConverged;
  }
  // Leave the linearization (and weights) at the final state for marginalization/covariance.
  EvaluateMeasurements(true);
  ApplyWeights();
  return status;
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::Backup() {
  for (int j = 0; j < num_poses_; ++j) pose_backup_[j] = Slot(j).pose;
  ForEachUsedSlot([&](int i) { landmarks_[i].backup = landmarks_[i].params; });
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::Restore() {
  for (int j = 0; j < num_poses_; ++j) Slot(j).pose = pose_backup_[j];
  ForEachUsedSlot([&](int i) { landmarks_[i].params = landmarks_[i].backup; });
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::ApplyStep(S alpha) {
  for (int j = 0; j < num_poses_; ++j) {
    if (Slot(j).fixed) continue;
    const StateVec d = alpha * StateVec(Blk<kStateDim, 1>(rhs_, kMaxDense, kStateDim * j, 0));
    Slot(j).pose = Model::Retract(pose_backup_[j], d);
  }
  ForEachUsedSlot([&](int i) {
    LandmarkSlot& l = landmarks_[i];
    l.params = l.backup + alpha * l.delta;
  });
}

}  // namespace swf::estimator
