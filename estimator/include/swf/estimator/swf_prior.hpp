// SlidingWindowFilter, the prior and marginalization (eqs. 8-12): the first pose's prior, the
// prior's quadratic at the current state, removing the oldest pose into the prior by the Schur
// complement (schur.hpp) and landmarks out of it, and the VO alternative of deleting instead.
// Included by sliding_window_filter.hpp; not a header to include alone.
#pragma once

#include <algorithm>

#include "swf/estimator/schur.hpp"
#include "swf/estimator/sliding_window_filter.hpp"

namespace swf::estimator {

// The prior over the very first pose: fixed (gauge) or a Gaussian around its estimate (the
// model gives the sigmas of the state beyond the pose).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::InitializePrior() {
  prior_landmarks_.clear();
  ClearPosePrior();
  prior_pose_lin_ = Slot(0).pose;
  const bool fixed = options_.fix_first_pose || options_.mode == SwfMode::kVisualOdometry;
  Slot(0).fixed = fixed;
  if (!fixed) {
    for (int i = 0; i < 3; ++i) {
      prior_[i * kPriorLd + i] =
          S(1.0 / (options_.first_pose_sigma_m * options_.first_pose_sigma_m));
      prior_[(i + 3) * kPriorLd + i + 3] =
          S(1.0 / (options_.first_pose_sigma_rad * options_.first_pose_sigma_rad));
    }
    if constexpr (kStateDim > 6) {
      const Eigen::Matrix<S, kStateDim - 6, 1> sigma = model_.FirstStateSigmas();
      for (int i = 6; i < kStateDim; ++i)
        prior_[i * kPriorLd + i] = S(1) / (sigma[i - 6] * sigma[i - 6]);
    }
  }
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::ClearPosePrior() {
  prior_dim_ = kStateDim;
  for (int c = 0; c < kStateDim; ++c)
    for (int r = 0; r < kStateDim; ++r) prior_[c * kPriorLd + r] = S(0);
  for (int i = 0; i < kStateDim; ++i) prior_g_[i] = S(0);
}

// prior_grad_ = Pi Delta - g at the current state (Delta coordinates). Accumulated column by
// column so the inner loop is contiguous. (A strided row-dot-product form of this loop was
// mis-vectorized by GCC 12 at -O3 into an aligned load of a misaligned address.)
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::PriorGradient() {
  PriorDelta();
  for (int r = 0; r < prior_dim_; ++r) prior_grad_[r] = -prior_g_[r];
  for (int c = 0; c < prior_dim_; ++c) {
    const S dc = prior_delta_[c];
    const S* column = prior_ + c * kPriorLd;
    for (int r = 0; r < prior_dim_; ++r) prior_grad_[r] += column[r] * dc;
  }
}

// Delta = x (-) x_bar for the prior's variables and the pose block's Jacobian.
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::PriorDelta() {
  const StateVec d = Model::Difference(prior_pose_lin_, Slot(0).pose, &prior_pose_jacobian_);
  for (int i = 0; i < kStateDim; ++i) prior_delta_[i] = d[i];
  for (int q = 0; q < static_cast<int>(prior_landmarks_.size()); ++q) {
    const Vec3<S> dl = landmarks_[prior_landmarks_[q]].params - prior_landmark_lin_[q];
    for (int k = 0; k < 3; ++k) prior_delta_[kStateDim + 3 * q + k] = dl[k];
  }
}

template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::AddPrior(int lm0) {
  const int nq = static_cast<int>(prior_landmarks_.size());
  PriorGradient();
  const StateMat& jp = prior_pose_jacobian_;
  const StateMat pi_pp = Blk<kStateDim, kStateDim>(prior_, kPriorLd, 0, 0);
  dense_.AddBlock(0, 0, jp.transpose() * pi_pp * jp);
  Blk<kStateDim, 1>(rhs_, kMaxDense, 0, 0) -=
      jp.transpose() * Blk<kStateDim, 1>(prior_grad_, kMaxPriorDim, 0, 0);
  for (int q = 0; q < nq; ++q) {
    const Eigen::Matrix<S, 3, kStateDim> pi_qp =
        Blk<3, kStateDim>(prior_, kPriorLd, kStateDim + 3 * q, 0);
    dense_.AddBlock(lm0 + 3 * q, 0, pi_qp * jp);
    Blk<3, 1>(rhs_, kMaxDense, lm0 + 3 * q, 0) -=
        Blk<3, 1>(prior_grad_, kMaxPriorDim, kStateDim + 3 * q, 0);
  }
  // Landmark-landmark block of Pi, copied as a whole (it is dense: Fig. 8).
  dense_.AddSymmetric(lm0, prior_ + kStateDim * kPriorLd + kStateDim, kPriorLd, 3 * nq);
}

// Removes the oldest pose by the Schur complement (eqs. 8-10), or by its block diagonal only
// in VSDF mode (eq. 12). See the file comment for the local system it forms.
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::MarginalizeOldestPose() {
  PoseSlot& p0 = Slot(0);
  PoseSlot& p1 = Slot(1);
  // Variables of the new prior: the old prior landmarks (same order), then the landmarks seen
  // from p0 that the window still measures and that the prior has room for.
  SelectPriorEntrants();
  for (const int k : prior_entrants_) {
    LandmarkSlot& l = landmarks_[p0.obs[k].landmark];
    l.prior_index = static_cast<int>(prior_landmarks_.size());
    (void)prior_landmarks_.push_back(p0.obs[k].landmark);
    prior_landmark_lin_[l.prior_index] = l.params;
    first_estimate_[l.prior_index] = l.params;
    // A new prior variable enters with zero information about itself until the Schur below.
    GrowPrior();
  }
  // The local system is the prior's own storage (prior_storage_, leading dimension kPriorLd)
  // from its first row and column: [p1 | p0 | landmarks], the prior [p0 | landmarks] in place
  // behind kStateDim rows and columns kept for p1. So the prior is not copied into a separate
  // system and back (two ~2 MB copies with an inertial window); p1 is moved to p0's place after
  // the elimination instead, O(dim) columns of kStateDim. Each element sees the operations it saw
  // in a separate local system (the Schur step is element by element), so the same bits.
  const int nq = static_cast<int>(prior_landmarks_.size());
  const int dim = 2 * kStateDim + 3 * nq;
  constexpr int kP1 = 0;          // p1's offset in the local system
  constexpr int kP0 = kStateDim;  // p0's: the prior's pose
  S* const local = prior_storage_;
  for (int c = 0; c < kStateDim; ++c)
    for (int r = 0; r < dim; ++r) local[c * kPriorLd + r] = S(0);
  for (int c = kStateDim; c < dim; ++c)
    for (int r = 0; r < kStateDim; ++r) local[c * kPriorLd + r] = S(0);
  for (int r = 0; r < dim; ++r) local_b_[r] = S(0);
  // Prior at the current estimate: Hessian J^T Pi J, right-hand side -J^T (Pi Delta - g).
  // J = blockdiag(prior_pose_jacobian_, I): scale the pose rows/columns of Pi (in place).
  PriorGradient();
  {
    const StateMat& jp = prior_pose_jacobian_;
    Blk<kStateDim, kStateDim>(local, kPriorLd, kP0, kP0) =
        jp.transpose() * Blk<kStateDim, kStateDim>(prior_, kPriorLd, 0, 0) * jp;
    for (int q = 0; q < nq; ++q) {
      const Eigen::Matrix<S, 3, kStateDim> pi_qp =
          Blk<3, kStateDim>(prior_, kPriorLd, kStateDim + 3 * q, 0);
      Blk<3, kStateDim>(local, kPriorLd, 2 * kStateDim + 3 * q, kP0) = pi_qp * jp;
      Blk<kStateDim, 3>(local, kPriorLd, kP0, 2 * kStateDim + 3 * q) = (pi_qp * jp).transpose();
    }
    Blk<kStateDim, 1>(local_b_, kMaxLocalDim, kP0, 0) =
        -(jp.transpose() * Blk<kStateDim, 1>(prior_grad_, kMaxPriorDim, 0, 0));
    for (int r = kStateDim; r < prior_dim_; ++r) local_b_[r + kStateDim] = -prior_grad_[r];
  }
  // Process factor between p0 and p1.
  if (p1.has_process) {
    StateMat a;
    StateMat b;
    const StateVec r = WhitenedProcessFactor(1, &a, &b);
    Blk<kStateDim, kStateDim>(local, kPriorLd, kP0, kP0) += a.transpose() * a;
    Blk<kStateDim, kStateDim>(local, kPriorLd, kP1, kP1) += b.transpose() * b;
    Blk<kStateDim, kStateDim>(local, kPriorLd, kP1, kP0) += b.transpose() * a;
    Blk<kStateDim, kStateDim>(local, kPriorLd, kP0, kP1) += a.transpose() * b;
    Blk<kStateDim, 1>(local_b_, kMaxLocalDim, kP0, 0) -= a.transpose() * r;
    Blk<kStateDim, 1>(local_b_, kMaxLocalDim, kP1, 0) -= b.transpose() * r;
  }
  // p0's measurements, with the weights of the last solve.
  for (const Observation& o : p0.obs) {
    if (!o.valid) continue;
    const int k = 2 * kStateDim + 3 * landmarks_[o.landmark].prior_index;
    const S norm = o.r.norm();
    const S w = norm <= tau_ ? S(1) : tau_ / norm;
    Blk<6, 6>(local, kPriorLd, kP0, kP0) += w * o.jp.transpose() * o.jp;
    Blk<3, 3>(local, kPriorLd, k, k) += w * o.jl.transpose() * o.jl;
    Blk<3, 6>(local, kPriorLd, k, kP0) += w * o.jl.transpose() * o.jp;
    Blk<6, 3>(local, kPriorLd, kP0, k) += w * o.jp.transpose() * o.jl;
    Blk<6, 1>(local_b_, kMaxLocalDim, kP0, 0) += w * o.jp.transpose() * o.r;
    Blk<3, 1>(local_b_, kMaxLocalDim, k, 0) += w * o.jl.transpose() * o.r;
  }
  // Eliminate p0 (or condition on it when it is fixed).
  if (!p0.fixed) {
    if (!EliminateFirstPose(dim)) fault_bits_ |= kFaultNotPositiveDefinite;
  }
  // The new prior is [p1 | landmarks], linearized at the current estimate: p1's rows and
  // columns move to p0's place, which is the prior's first.
  for (int c = 0; c < kStateDim; ++c) {
    for (int r = 0; r < kStateDim; ++r)
      local[(kP0 + c) * kPriorLd + kP0 + r] = local[(kP1 + c) * kPriorLd + kP1 + r];
    for (int r = 2 * kStateDim; r < dim; ++r)
      local[(kP0 + c) * kPriorLd + r] = local[(kP1 + c) * kPriorLd + r];
  }
  for (int c = 2 * kStateDim; c < dim; ++c)
    for (int r = 0; r < kStateDim; ++r)
      local[c * kPriorLd + kP0 + r] = local[c * kPriorLd + kP1 + r];
  prior_dim_ = dim - kStateDim;
  for (int r = 0; r < kStateDim; ++r) prior_g_[r] = local_b_[kP1 + r];
  for (int r = kStateDim; r < prior_dim_; ++r) prior_g_[r] = local_b_[r + kStateDim];
  prior_pose_lin_ = p1.pose;
  for (int q = 0; q < nq; ++q) prior_landmark_lin_[q] = landmarks_[prior_landmarks_[q]].params;
  // Drop p0.
  for (const Observation& o : p0.obs) --landmarks_[o.landmark].obs_in_window;
  p0.obs.clear();
  head_ = (head_ + 1) % kMaxPoses;
  --num_poses_;
  Slot(0).has_process = false;  // consumed into the prior
}

// Chooses which of p0's landmarks enter the prior (indices into p0.obs, in their order) and
// drops the measurements of those that do not. A landmark seen from p0 alone stays out: a
// stereo measurement (3 rows) of a landmark (3 parameters) tells nothing about the other states
// once the landmark is eliminated (its Schur complement, eq. 9, is zero), so it would occupy a
// prior slot only to leave right after (Fig. 7c). When more landmarks qualify than the prior
// has room for, the ones the window measures most (then the longest tracks) enter: they tie p0's
// information to the most remaining poses. The others' p0 measurements are dropped and
// reported (kFaultPriorCapacity).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::SelectPriorEntrants() {
  PoseSlot& p0 = Slot(0);
  prior_entrants_.clear();
  for (int k = 0; k < static_cast<int>(p0.obs.size()); ++k) {
    Observation& o = p0.obs[k];
    EvaluateObservation(p0.pose, &o, true);
    if (!o.valid) continue;
    const LandmarkSlot& l = landmarks_[o.landmark];
    if (l.prior_index >= 0) continue;
    if (l.obs_in_window == 1) {
      o.valid = false;
      continue;
    }
    (void)prior_entrants_.push_back(k);
  }
  const int room = P - static_cast<int>(prior_landmarks_.size());
  if (static_cast<int>(prior_entrants_.size()) <= room) return;
  fault_bits_ |= kFaultPriorCapacity;
  // A strict order (ties broken by position), so the chosen set is deterministic.
  const auto more_useful = [&](int a, int b) {
    const LandmarkSlot& la = landmarks_[p0.obs[a].landmark];
    const LandmarkSlot& lb = landmarks_[p0.obs[b].landmark];
    if (la.obs_in_window != lb.obs_in_window) return la.obs_in_window > lb.obs_in_window;
    if (la.total_obs != lb.total_obs) return la.total_obs > lb.total_obs;
    return a < b;
  };
  int* first = prior_entrants_.data();
  int* last = first + prior_entrants_.size();
  std::nth_element(first, first + room, last, more_useful);
  for (int* k = first + room; k != last; ++k) p0.obs[*k].valid = false;
  while (static_cast<int>(prior_entrants_.size()) > room) prior_entrants_.pop_back();
  std::sort(first, first + room);  // enter in p0's order, as when the prior has room
}

// Adds three zero rows/columns to the prior for a landmark entering it.
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::GrowPrior() {
  const int d = prior_dim_;
  for (int c = 0; c < d + 3; ++c)
    for (int r = (c < d ? d : 0); r < d + 3; ++r) {
      prior_[c * kPriorLd + r] = S(0);
      prior_[r * kPriorLd + c] = S(0);
    }
  for (int r = d; r < d + 3; ++r) prior_g_[r] = S(0);
  prior_dim_ = d + 3;
}

// Schur complement of p0 (the local system's second kStateDim variables) onto the rest
// (eq. 9); in VSDF mode (eq. 12) only its blocks within p1 and within each landmark, or with
// vsdf_scalar_diagonal only its scalar diagonal. False when p0's block is not positive definite
// (nothing changed), or when the scalar diagonal left the new prior indefinite (see below).
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::EliminateFirstPose(int dim) {
  if (options_.mode != SwfMode::kVsdf) {
    for (int c = 0; c < dim / 3; ++c) local_chunk_dropped_[c] = false;
    const int p0 = kStateDim;
    return EliminateVariablesExact<kStateDim>(prior_storage_, kPriorLd, local_b_, dim, &p0, 1,
                                              local_chunk_dropped_, x_, kXRows);
  }
  // Chunks of p1 (the first kStateDim / 3) are one variable; every chunk after p0's is a
  // landmark of its own.
  const auto variable = [](int chunk) { return chunk < 2 * kStateDim / 3 ? 0 : chunk; };
  const bool scalar = options_.vsdf_scalar_diagonal;
  const bool eliminated = EliminateVariable<kStateDim>(
      prior_storage_, kPriorLd, local_b_, dim, kStateDim, x_, kXRows, [&](int r, int c) {
        if (scalar) return r == c ? SchurFill::kDiagonal : SchurFill::kNone;
        return variable(r) == variable(c) ? SchurFill::kBlock : SchurFill::kNone;
      });
  return eliminated && (!scalar || NewPriorBlocksPositiveSemidefinite(dim));
}

// Whether a symmetric block has no eigenvalue below zero beyond round-off (relative to its
// largest). Semi-definite, not definite: a zero block is a prior that says nothing.
template <typename S, int D>
bool PositiveSemidefinite(const Eigen::Matrix<S, D, D>& a) {
  const Eigen::Matrix<S, D, 1> e = SymmetricEigenvalues(a);
  return e.minCoeff() >= -S(1e-9) * e.cwiseAbs().maxCoeff();
}

// Whether p1's block and every landmark's 3x3 block of the new prior (the local system after
// p0's elimination) are positive semi-definite; each is a principal block, so a failure means
// the prior is indefinite. Checked for the scalar diagonal of eq. 12 only: the exact complement
// and its blocks within each variable are positive semi-definite by construction, the scalar
// diagonal is not. A stereo landmark's Schur term has its line of sight in its null space, the
// term's diagonal in world coordinates does not, and along an off-axis ray it removes more than
// the landmark's weak depth information (docs/results.md, Fig. 17; the test
// Schur.VsdfScalarDiagonalLeavesAnOffAxisStereoLandmarkIndefiniteAlongItsRay). Reported at the
// marginalization that makes it, not left for a later solve to find (or, where the window's own
// measurements mask it, to miss while the prior pulls the landmark along its ray).
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::NewPriorBlocksPositiveSemidefinite(int dim) {
  if (!PositiveSemidefinite<S, kStateDim>(
          Blk<kStateDim, kStateDim>(prior_storage_, kPriorLd, 0, 0)))
    return false;
  for (int o = 2 * kStateDim; o < dim; o += 3) {
    if (!PositiveSemidefinite<S, 3>(Blk<3, 3>(prior_storage_, kPriorLd, o, o))) return false;
  }
  return true;
}

// VO mode: forget the oldest pose and everything attached to it; hold the next one fixed.
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::DeleteOldestPose() {
  PoseSlot& p0 = Slot(0);
  for (const Observation& o : p0.obs) --landmarks_[o.landmark].obs_in_window;
  p0.obs.clear();
  head_ = (head_ + 1) % kMaxPoses;
  --num_poses_;
  Slot(0).has_process = false;
  Slot(0).fixed = true;
  ClearPosePrior();
  prior_pose_lin_ = Slot(0).pose;
}

// Landmarks with no measurement left in the window leave the estimator (Fig. 7c).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::RetireUnsupportedLandmarks() {
  leaving_prior_.clear();
  if (options_.mode == SwfMode::kBatch) return;
  ForEachUsedSlot([&](int i) {
    LandmarkSlot& l = landmarks_[i];
    if (l.obs_in_window > 0) return;
    if (l.prior_index >= 0) (void)leaving_prior_.push_back(l.prior_index);
    RetiredLandmark<S> r;
    r.id = l.id;
    r.total_observations = l.total_obs;
    if (Model::LandmarkPosition(l.anchor, l.params, &r.position, nullptr)) {
      (void)retired_.push_back(r);
    } else {
      ++summary_.landmarks_unplaced;  // at or beyond infinity: no position to report
    }
    ids_.Erase(l.id);
    SetUsed(i, false);
    (void)free_slots_.push_back(i);
    --num_landmarks_;
    ++summary_.landmarks_marginalized;
  });
  if (!EliminatePriorLandmarks()) fault_bits_ |= kFaultNotPositiveDefinite;
}

// Schur complement of each prior landmark in leaving_prior_ (prior indices, eliminated in that
// order) onto the rest of the prior, then the removal of all their rows at once. Each
// elimination skips the rows of those before it, which are never read again for a kept element,
// so every kept element sees the operations of eliminating and dropping the landmarks one at a
// time, in the same order (the same bits), while the prior is compacted, an O(dim^2) pass, once
// instead of once per landmark; and up to kEliminationBatch of them update the prior in one
// pass over it (EliminateVariablesExact). A landmark whose block is not positive definite is
// removed without its complement (false).
template <typename Model, int K, int N, int M, int P>
bool SlidingWindowFilter<Model, K, N, M, P>::EliminatePriorLandmarks() {
  if (leaving_prior_.empty()) return true;
  const int chunks = prior_dim_ / 3;
  for (int c = 0; c < chunks; ++c) prior_chunk_dropped_[c] = false;
  bool ok = true;
  const int leaving = static_cast<int>(leaving_prior_.size());
  for (int b = 0; b < leaving; b += kEliminationBatch) {
    const int count = std::min(kEliminationBatch, leaving - b);
    int offsets[kEliminationBatch];
    for (int i = 0; i < count; ++i) offsets[i] = kStateDim + 3 * leaving_prior_[b + i];
    ok = EliminateVariablesExact<3>(prior_, kPriorLd, prior_g_, prior_dim_, offsets, count,
                                    prior_chunk_dropped_, x_, kXRows) &&
         ok;
  }
  prior_dim_ = DropChunks(prior_, kPriorLd, prior_g_, prior_dim_, prior_chunk_dropped_);
  int kept = 0;
  for (int q = 0; q < static_cast<int>(prior_landmarks_.size()); ++q) {
    LandmarkSlot& l = landmarks_[prior_landmarks_[q]];
    if (prior_chunk_dropped_[(kStateDim + 3 * q) / 3]) {
      l.prior_index = -1;
      continue;
    }
    l.prior_index = kept;
    prior_landmarks_[kept] = prior_landmarks_[q];
    prior_landmark_lin_[kept] = prior_landmark_lin_[q];
    first_estimate_[kept] = first_estimate_[q];
    ++kept;
  }
  while (static_cast<int>(prior_landmarks_.size()) > kept) prior_landmarks_.pop_back();
  leaving_prior_.clear();
  return ok;
}

// Takes a landmark out with all its window measurements. A prior landmark is marginalized
// out of the prior (what earlier measurements told about the rest stays there).
template <typename Model, int K, int N, int M, int P>
void SlidingWindowFilter<Model, K, N, M, P>::RemoveLandmark(int slot) {
  LandmarkSlot& l = landmarks_[slot];
  for (int j = 0; j < num_poses_; ++j) {
    PoseSlot& p = Slot(j);
    for (std::size_t k = p.obs.size(); k-- > 0;)
      if (p.obs[k].landmark == slot) p.obs.erase(k);
  }
  leaving_prior_.clear();
  if (l.prior_index >= 0) (void)leaving_prior_.push_back(l.prior_index);
  if (!EliminatePriorLandmarks()) fault_bits_ |= kFaultNotPositiveDefinite;
  ids_.Erase(l.id);
  SetUsed(slot, false);
  l.obs_in_window = 0;
  (void)free_slots_.push_back(slot);
  --num_landmarks_;
}

}  // namespace swf::estimator
