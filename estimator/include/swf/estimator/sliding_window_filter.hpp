// SlidingWindowFilter: the estimator of Sibley, Matthies and Sukhatme, "Sliding Window Filter
// with Application to Planetary Landing" (JFR 2010), sections 2-3, as a fixed-size flight
// library. Equation numbers below refer to that paper.
//
// ----------------------------------------------------------------------------------------------
// The problem (eqs. 1-6). State x = [landmarks x_m ; window poses x_p]. Three information
// sources make the Gauss-Newton system  Lambda dx = g  (eq. 7):
//     Lambda = L^T Pi L  +  D^T Q^-1 D  +  H^T R^-1 H                                     (eq. 6)
//   measurements  z_ij = h(x_mi, x_pj) + v,  v ~ N(0, R_ij)   (Model::Predict)
//   process       x_pj+1 = f(x_pj, u_j+1) + w, w ~ N(0, Q)    (Model::ProcessResidual)
//   prior         everything marginalized so far, a quadratic in Delta = x (-) x_bar about its
//                 own linearization point x_bar:  0.5 Delta^T Pi Delta - g_Pi^T Delta
//
// Structure used by the solver (Figs. 4-8): the prior always spans {oldest window pose} and a
// set of "prior landmarks" Lp; every other ("free") landmark couples only to the poses that
// observe it, so its 3x3 block is eliminated first (Schur complement of the map onto the path):
//     S = Lambda_RR - sum_i Lambda_Ri Lambda_ii^-1 Lambda_iR,   s = g_R - sum_i Lambda_Ri
//     Lambda_ii^-1 g_i
// where R = [window poses ; prior landmarks]. S is dense (the pose block is block-tridiagonal
// plus fill-in from free landmarks and the prior) and is solved by DenseCholesky. Free landmark
// updates follow by back-substitution: dx_i = Lambda_ii^-1 (g_i - Lambda_iR dx_R).
//
// Pose states: each window "pose" is a state of Model::kStateDim coordinates whose first
// six are the pose [rho; phi] (the only part measurements see) and the rest whatever the
// process model carries per frame (with an IMU: velocity and the two biases). The measurement
// blocks are 6-wide inside the state blocks; the process factor and the prior are state-wide.
//
// Robust Gauss-Newton (section 3.1.3): measurements are whitened (r = W (z - h), W^T W = R^-1)
// and weighted by Huber's kernel, w = min(1, tau / |r|), with tau = huber_k * sigma_hat, where
// sigma_hat is the inlier standard deviation estimated each iteration from the median whitened
// residual norm (never below the nominal 1). Iterations are bounded (max_iterations), a step
// that raises the cost is halved at most max_backtracking times, and the loop stops when the
// relative cost decrease or the largest step component falls below its tolerance.
//
// Marginalization (eqs. 8-10) happens in Update() before solving:
//   * when the window holds more than K poses, the oldest pose p1 is removed. All factors that
//     touch it (its measurements, the process factor to p2, the prior) are linearized at the
//     current estimate into a local system over [p1 ; p2 ; Lp u landmarks seen from p1], and
//         Pi_new = Lambda_bb - Lambda_ba Lambda_aa^-1 Lambda_ab,   g_new = g_b - Lambda_ba
//         Lambda_aa^-1 g_a
//     becomes the new prior over [p2 ; Lp'] with x_bar = the current estimate. This is exactly
//     the fill-in of Figs. 6-8: among landmarks seen from p1, between p2 and those landmarks.
//   * every landmark with no measurement left in the window is removed the same way; if it is
//     in the prior this only touches Pi (Fig. 7c), otherwise it carries no information.
//   * first-estimate Jacobians (option, on by default; not in the paper): a landmark that enters
//     the prior keeps the estimate it had then as the point where all its later measurement
//     Jacobians are evaluated (residuals still use the current estimate). Relinearizing them
//     elsewhere gives the prior and the window inconsistent Jacobians for the same variable,
//     which on a narrow-field descent injected false information along the weakly observable
//     rotation/translation direction: SWF(3) landmark RMS 2.4x batch without, within 10% with
//     (estimator/README.md).
// Modes on the same code:
// The window holds options.window_size poses (at most the capacity K).
//   kSlidingWindow   the above (K = 1 is the EKF: marginalizing p1 through the process factor
//                    is the prediction, the solve is the (iterated) update)
//   kBatch           never marginalize; the window must hold the whole sequence (full SLAM/BA)
//   kVisualOdometry  delete the oldest pose and its measurements instead of marginalizing, and
//                    hold the new oldest pose fixed (conditioning; section 4.2.4)
//   kVsdf            marginalize with only the block diagonal of the Schur term (eq. 12)
//
// Memory: K (window), N (active landmarks), M (measurements per pose) and P (landmarks the prior
// can hold) are template parameters; every buffer is a member, so the object is large: create it
// once at start-up (e.g. std::make_unique), never on the stack. No call allocates afterwards.
// Determinism: single-threaded, fixed iteration order, no clocks; same input -> same bits.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "swf/core/assert.hpp"
#include "swf/core/static_vector.hpp"
#include "swf/core/status.hpp"
#include "swf/estimator/dense_cholesky.hpp"
#include "swf/estimator/geometry.hpp"

namespace swf::estimator {

enum class SwfMode : std::uint8_t { kSlidingWindow, kBatch, kVisualOdometry, kVsdf };

// Sticky numerical-health bits (values shared with health_t.FAULT_*).
enum SwfFault : std::uint32_t {
  kFaultNotPositiveDefinite = 1u << 0,  // a solve or marginalization found a non-SPD system
  kFaultNonFinite = 1u << 1,            // a residual or update was NaN/Inf; the step was refused
  kFaultNotConverged = 1u << 2,         // Gauss-Newton hit max_iterations
  kFaultLandmarkCapacity = 1u << 3,     // a new landmark was refused: N active landmarks
  kFaultMeasurementCapacity = 1u << 4,  // a measurement was refused: M per pose
  kFaultPriorCapacity = 1u << 7,        // a landmark could not enter the prior (P); its
                                        // measurement from the marginalized pose was dropped
  kFaultDegenerateLandmark = 1u << 8,   // a landmark's 3x3 block was singular; held fixed
  kFaultReset = 1u << 9,                // the state became non-finite; the filter was reset
  kFaultGateSuspended = 1u << 10,       // more of a frame's measurements failed their gate than
                                        // max_gated_fraction: the prediction, not the
                                        // measurements, is suspect; they were all kept
};

// Upper quantile of the chi-square distribution with `dof` degrees of freedom: the x with
// P(chi2_dof <= x) = probability. The CDF is the regularized lower incomplete gamma function
// P(dof/2, x/2), summed as its power series; the quantile by bisection (bounded, configuration
// time only). 0 for a probability outside (0, 1) or dof outside [1, 60].
inline double ChiSquareQuantile(int dof, double probability) {
  if (!(probability > 0.0 && probability < 1.0) || dof < 1 || dof > 60) return 0.0;
  const double a = 0.5 * dof;
  const auto cdf = [a](double x) {
    const double z = 0.5 * x;
    if (z <= 0.0) return 0.0;
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 1000 && term > 1e-17 * sum; ++n) {
      term *= z / (a + n);
      sum += term;
    }
    return std::exp(a * std::log(z) - z - std::lgamma(a)) * sum;
  };
  double lo = 0.0;
  double hi = 400.0;  // CDF(400) = 1 - 1e-60 for dof <= 60
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct SwfOptions {
  SwfMode mode = SwfMode::kSlidingWindow;
  int window_size = 0;                    // poses kept in the window; 0 = the capacity K
  int max_iterations = 10;                // Gauss-Newton iterations per Update (>= 1)
  int max_backtracking = 4;               // step halvings when a step raises the cost
  double relative_cost_tolerance = 1e-4;  // stop when (cost_before - cost_after) <= tol * cost
  double step_tolerance = 1e-10;          // stop when the largest update component is below
  bool robust = true;                     // Huber weighting of measurements
  double huber_k = 3.5;                   // threshold in inlier standard deviations
  double max_robust_sigma = 3.0;          // cap on the inlier sigma the threshold scales with
  bool fix_first_pose = false;            // hold the first pose fixed (gauge), else use:
  double first_pose_sigma_m = 1e-3;       // prior on the first pose: position (metres)
  double first_pose_sigma_rad = 1e-4;     // and rotation (radians), or the linear analogue
  // Evaluate measurement Jacobians of prior landmarks at their estimate when they entered the
  // prior (FEJ, Huang/Mourikis/Roumeliotis). Off = relinearize everything (the paper's SWF).
  bool first_estimate_jacobians = true;
  // Integrity gates (chi-square with 3 dof at gate_probability; 0 = no gates):
  //  * before fusion, a measurement of a known landmark is tested against its prediction with
  //    covariance R + J_p P_pose J_p^T + J_l P_l J_l^T (the predicted pose's and the landmark's
  //    marginals from the last ComputeCovariances(); without them the test is skipped and
  //    counted as unchecked);
  //  * after the solve, a measurement whose whitened residual, in units of the inlier sigma,
  //    stays above the gate is removed; a landmark whose window measurements all fail is
  //    removed with them; then the window is solved again (at most max_gate_resolves times).
  // Either gate stands down (keeps everything, kFaultGateSuspended) when more than
  // max_gated_fraction of the measurements it checks fail: then the state, not the data, is
  // wrong, and deleting the data would hide that from the health monitor.
  double gate_probability = 0.9999;
  double max_gated_fraction = 0.5;
  int max_gate_resolves = 1;
  // A new landmark's stereo triangulation must give a 3x3 information that is positive
  // definite, and (when > 0) a largest 1-sigma world position error below this (metres).
  double max_init_sigma_m = 0.0;
  // Motion gate (chi-square with 6 dof at gate_probability): before fusion, the newest pose
  // fitted to its measurements of known landmarks alone is compared with the motion
  // prediction. When they disagree, the fit has at least motion_gate_min_inliers inliers
  // and the distance exceeds motion_overrule_factor times the gate, the images overrule the
  // motion input: the fit becomes the linearization point and the caller's fallback (else the
  // input with its information scaled by motion_gate_weight^2) replaces the process factor.
  // Otherwise nobody can tell which is wrong: the failure is only reported. The factor keeps a
  // slowly biased visual solution (landmarks whose marginals are too confident) from overruling
  // a correct input while a gross glitch is still overruled (docs/integrity.md, "Motion input
  // gating").
  int motion_gate_min_inliers = 25;
  double motion_overrule_factor = 4.0;
  double motion_gate_weight = 1e-3;

  core::Status Validate() const {
    if (max_iterations < 1 || max_iterations > 100) return core::Status::kInvalidArgument;
    if (max_backtracking < 0 || max_backtracking > 20) return core::Status::kInvalidArgument;
    if (!(relative_cost_tolerance >= 0.0) || !(step_tolerance >= 0.0))
      return core::Status::kInvalidArgument;
    if (!(huber_k > 0.0) || !(max_robust_sigma >= 1.0)) return core::Status::kInvalidArgument;
    if (!fix_first_pose && !(first_pose_sigma_m > 0.0 && first_pose_sigma_rad > 0.0))
      return core::Status::kInvalidArgument;
    if (!(gate_probability >= 0.0 && gate_probability < 1.0)) return core::Status::kInvalidArgument;
    if (!(max_gated_fraction >= 0.0 && max_gated_fraction <= 1.0))
      return core::Status::kInvalidArgument;
    if (max_gate_resolves < 0 || max_gate_resolves > 5) return core::Status::kInvalidArgument;
    if (!(max_init_sigma_m >= 0.0)) return core::Status::kInvalidArgument;
    if (motion_gate_min_inliers < 0 || !(motion_gate_weight > 0.0 && motion_gate_weight <= 1.0) ||
        !(motion_overrule_factor >= 1.0)) {
      return core::Status::kInvalidArgument;
    }
    return core::Status::kOk;
  }
};

// Why the last solve's Gauss-Newton loop stopped (Ceres-style termination reason).
enum class SwfTermination {
  kNoSolve,           // nothing to solve: no pose in the window
  kCostTolerance,     // relative cost decrease <= relative_cost_tolerance: converged
  kStepTolerance,     // largest update component <= step_tolerance: converged
  kNoDescent,         // no step length lowered the cost: at the minimum, converged
  kMaxIterations,     // max_iterations used up first: not converged (kFaultNotConverged)
  kNumericalFailure,  // the reduced system was not positive definite or a step not finite
};

inline const char* TerminationName(SwfTermination t) {
  switch (t) {
    case SwfTermination::kNoSolve: return "no solve";
    case SwfTermination::kCostTolerance: return "cost tolerance";
    case SwfTermination::kStepTolerance: return "step tolerance";
    case SwfTermination::kNoDescent: return "no descent";
    case SwfTermination::kMaxIterations: return "max iterations";
    case SwfTermination::kNumericalFailure: return "numerical failure";
  }
  return "unknown";
}

struct SwfSummary {
  core::Status status = core::Status::kOk;
  int iterations = 0;
  SwfTermination termination = SwfTermination::kNoSolve;
  double initial_cost = 0.0;  // robust cost at the start of the last solve
  double final_cost = 0.0;    // robust cost at its end
  int num_measurements = 0;   // measurements in the window
  int num_downweighted = 0;   // measurements with Huber weight < 1 at the end
  double huber_threshold = 0.0;
  int poses_marginalized = 0;      // in the last Update
  int landmarks_marginalized = 0;  // in the last Update (retired landmarks)
  int landmarks_unplaced = 0;      // of those, retired without a position (inverse depth <= 0)
  int dense_dimension = 0;         // size of the reduced system S
  int state_dimension = 0;         // Model::kStateDim * poses + 3 * active landmarks
  // Evidence for the health monitor (integrity.hpp), at the end of the last solve.
  double inlier_sigma = 1.0;      // robust scale of the whitened residuals (>= 1, uncapped)
  double measurement_chi2 = 0.0;  // sum of squared whitened residuals (no robust kernel)
  int num_inliers = 0;            // measurements with Huber weight 1
  // The newest frame alone: its measurements of landmarks seen from an earlier pose, the
  // inliers among them, and its first sightings (what the frame really tracked).
  int tracked_measurements = 0;
  int tracked_inliers = 0;
  int new_landmarks = 0;
  double newest_pose_step_m = 0.0;  // how far the solve moved the newest pose from its prediction
  double newest_pose_step_rad = 0.0;
  // Gates of this frame (see SwfOptions).
  int gate_checked = 0;           // measurements of known landmarks tested before fusion
  int gate_unchecked = 0;         // ... that could not be tested (no covariances yet)
  int measurements_gated = 0;     // ... that failed and were not fused
  int measurements_rejected = 0;  // removed after the solve
  int landmarks_rejected = 0;     // removed after the solve with all their measurements
  int new_landmarks_refused = 0;  // failed the depth, disparity or triangulation check
  bool gate_suspended = false;    // a gate stood down (kFaultGateSuspended)
  // The motion gate: the squared Mahalanobis distance between the motion prediction and the
  // images' fit of the newest pose, whether it failed, and whether the images overruled it.
  double motion_chi2 = 0.0;
  bool motion_gate_failed = false;
  bool motion_overruled = false;

  // The solve stopped for one of the three converged reasons.
  bool Converged() const {
    return termination == SwfTermination::kCostTolerance ||
           termination == SwfTermination::kStepTolerance ||
           termination == SwfTermination::kNoDescent;
  }
};

// A landmark that left the estimator in the last Update (its final estimate).
template <typename S>
struct RetiredLandmark {
  std::int64_t id = 0;
  Vec3<S> position = Vec3<S>::Zero();
  int total_observations = 0;
};

template <typename Model, int K, int N, int M, int P>
class SlidingWindowFilter {
  static_assert(K >= 1 && N >= 1 && M >= 1 && P >= 1, "capacities must be positive");

 public:
  using ModelType = Model;
  using S = typename Model::Scalar;
  using PoseType = typename Model::PoseType;
  using MotionType = typename Model::MotionType;
  using LandmarkAnchor = typename Model::LandmarkAnchor;
  // Dimension of a pose state's update vector: [rho; phi] (the pose, which the measurements
  // see) and then whatever else the model keeps per pose (velocity, IMU biases).
  static constexpr int kStateDim = Model::kStateDim;
  static_assert(kStateDim >= 6 && kStateDim % 3 == 0, "state = the 6-dof pose, then 3-vectors");
  using StateVec = Eigen::Matrix<S, kStateDim, 1>;
  using StateMat = Eigen::Matrix<S, kStateDim, kStateDim>;

  static constexpr int kMaxPoses = K + 1;  // one extra while a new pose awaits marginalization
  static constexpr int kMaxDense = kStateDim * K + 3 * P;
  static constexpr int kMaxPriorDim = kStateDim + 3 * P;
  static constexpr int kMaxLocalDim = 2 * kStateDim + 3 * P;
  static constexpr int kMaxObservations = kMaxPoses * M;

  SlidingWindowFilter() = default;
  SlidingWindowFilter(const SlidingWindowFilter&) = delete;
  SlidingWindowFilter& operator=(const SlidingWindowFilter&) = delete;

  core::Status Configure(const Model& model, const SwfOptions& options) {
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

  // Forgets all state (keeps the configuration).
  void Reset() {
    num_poses_ = 0;
    head_ = 0;
    for (int i = 0; i < N; ++i) landmarks_[i].used = false;
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
    predicted_cov_valid_ = false;
    has_motion_fallback_ = false;
    retired_.clear();
  }

  // ---- adding a frame: one AddPose* call, its AddObservation calls, then Update() -----------

  // Adds a pose with an initial estimate and no process factor (bundle-adjustment style).
  core::Status AddPose(const PoseType& estimate) { return PushPose(estimate, nullptr, nullptr); }

  // Adds the first pose with a Gaussian prior of this covariance (update coordinates) instead of
  // first_pose_sigma_*: a restart from the last trusted state keeps its uncertainty, so the
  // covariances (and protection levels) after it still cover the error made before it. A
  // fixed first pose (fix_first_pose, VO) stays fixed.
  core::Status AddFirstPose(const PoseType& estimate, const StateMat& covariance) {
    if (num_poses_ != 0) return core::Status::kInvalidArgument;
    const Eigen::LLT<StateMat> llt(covariance);
    if (!covariance.allFinite() || llt.info() != Eigen::Success)
      return core::Status::kInvalidArgument;
    const core::Status status = PushPose(estimate, nullptr, nullptr);
    if (status != core::Status::kOk || Slot(0).fixed) return status;
    const StateMat information = llt.solve(StateMat::Identity());
    for (int c = 0; c < kStateDim; ++c)
      for (int r = 0; r < kStateDim; ++r) prior_[c * kMaxPriorDim + r] = information(r, c);
    return core::Status::kOk;
  }

  // Adds a pose predicted by the process model from a relative-motion input u with
  // information W^T W = Q^-1 (process_sqrt_information = W).
  core::Status AddPoseWithMotion(const MotionType& u, const StateMat& process_sqrt_information) {
    if (num_poses_ == 0) return core::Status::kInvalidArgument;
    return PushPose(model_.Propagate(Newest().pose, u), &u, &process_sqrt_information);
  }

  // What the newest pose's process factor becomes if the images overrule its motion input in
  // the motion gate (e.g. the caller's constant-velocity model); without one the input is kept
  // with its information scaled by motion_gate_weight^2. Valid until the next Update().
  core::Status SetMotionFallback(const MotionType& u, const StateMat& process_sqrt_information) {
    if (num_poses_ < 2 || !Newest().has_process) return core::Status::kInvalidArgument;
    motion_fallback_ = u;
    motion_fallback_sqrt_info_ = process_sqrt_information;
    has_motion_fallback_ = true;
    return core::Status::kOk;
  }

  // Constant-velocity fallback: repeats the last relative motion (none with a single pose).
  core::Status AddPoseConstantVelocity(const StateMat& process_sqrt_information) {
    if (num_poses_ == 0) return core::Status::kInvalidArgument;
    const PoseType& last = Newest().pose;
    const MotionType u = num_poses_ >= 2 ? model_.RelativeMotion(Slot(num_poses_ - 2).pose, last)
                                         : model_.RelativeMotion(last, last);
    return AddPoseWithMotion(u, process_sqrt_information);
  }

  // Adds a measurement z of landmark `landmark_id` from the newest pose, with information
  // W^T W = R^-1 (sqrt_information = W). A new id is initialized from z by stereo.
  core::Status AddObservation(std::int64_t landmark_id, const Vec3<S>& z,
                              const Mat3<S>& sqrt_information) {
    if (num_poses_ == 0) return core::Status::kNotConfigured;
    if (!z.allFinite() || !sqrt_information.allFinite()) return core::Status::kInvalidArgument;
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
      l.used = true;
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
    ++landmarks_[slot].obs_in_window;
    ++landmarks_[slot].total_obs;
    return core::Status::kOk;
  }

  // Marginalizes (per mode) and runs robust Gauss-Newton over the window.
  core::Status Update() {
    if (!configured_) return core::Status::kNotConfigured;
    summary_ = SwfSummary{};
    retired_.clear();
    const MotionGateResult motion_gate = GateNewestMotion();
    ApplyPredictionGate();
    summary_.motion_chi2 = motion_gate.chi2;
    summary_.motion_gate_failed = motion_gate.failed;
    summary_.motion_overruled = motion_gate.overruled;
    if (num_poses_ > window_) {
      if (options_.mode == SwfMode::kVisualOdometry) {
        DeleteOldestPose();
      } else {
        MarginalizeOldestPose();
      }
      summary_.poses_marginalized = 1;
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

  // Marginal covariances of every window pose block and active landmark at the current
  // estimate (inverse of the full information matrix, by the Schur complement). O(n^3) in the
  // reduced dimension: call it at the output rate, not inside the estimation loop.
  core::Status ComputeCovariances() {
    if (num_poses_ == 0) return core::Status::kNotConfigured;
    EvaluateMeasurements(true);
    const core::Status status = BuildAndFactor();
    if (status != core::Status::kOk) return status;
    const int npd = kStateDim * num_poses_;
    // Pose block of S^-1 (needed for free landmarks) and the prior landmarks' diagonal blocks.
    const int nq = static_cast<int>(prior_landmarks_.size());
    for (int c = 0; c < npd; ++c) {
      dense_.InverseColumn(c, column_);
      for (int r = 0; r < npd; ++r) pose_cov_[c * kMaxPosesDim + r] = column_[r];
      if (c < npd - kStateDim) continue;
      for (int q = 0; q < nq; ++q)  // Cov(newest pose, prior landmark q)
        for (int r = 0; r < 3; ++r)
          landmarks_[prior_landmarks_[q]].cross_newest(c - (npd - kStateDim), r) =
              column_[npd + 3 * q + r];
    }
    // A fixed pose is known exactly; its identity rows in S only stand in for "no update".
    for (int j = 0; j < num_poses_; ++j) {
      if (!Slot(j).fixed) continue;
      for (int k = kStateDim * j; k < kStateDim * j + kStateDim; ++k)
        for (int m = 0; m < npd; ++m)
          pose_cov_[k * kMaxPosesDim + m] = pose_cov_[m * kMaxPosesDim + k] = S(0);
    }
    for (int i = 0; i < N; ++i) landmarks_[i].covariance_valid = false;
    // A prior landmark's marginal is the diagonal block of L^-T L^-1 over its three columns c:
    // sums over rows >= c of the forward columns of L^-1 (a sixth of the InverseColumn flops).
    const int n = dense_.size();
    for (int q = 0; q < nq; ++q) {
      LandmarkSlot& l = landmarks_[prior_landmarks_[q]];
      const int c0 = npd + 3 * q;
      for (int k = 0; k < 3; ++k) dense_.FactorInverseColumn(c0 + k, factor_columns_[k]);
      for (int k = 0; k < 3; ++k) {
        for (int r = k; r < 3; ++r) {
          S sum = S(0);
          for (int i = c0 + r; i < n; ++i) sum += factor_columns_[k][i] * factor_columns_[r][i];
          l.covariance(r, k) = l.covariance(k, r) = sum;
        }
      }
      l.covariance_valid = l.covariance.allFinite();
    }
    for (int i = 0; i < N; ++i) {
      LandmarkSlot& l = landmarks_[i];
      if (!l.used || l.prior_index >= 0 || !l.invertible) continue;
      Mat3<S> cross = Mat3<S>::Zero();  // sum_a sum_b W_a^T Sigma(ja, jb) W_b
      // dl = h^-1 (b - sum_a W_a^T dp_a): Cov(newest, l) = -sum_a Sigma(newest, ja) W_a h^-1
      // (W_a couples the landmark to the pose part of state ja only: its first 6 columns).
      l.cross_newest.setZero();
      for (int a = lm_begin_[i]; a < lm_begin_[i + 1]; ++a) {
        const Observation& oa = ObsAt(adj_[a]);
        const Eigen::Map<const Eigen::Matrix<S, kStateDim, 6>, Eigen::Unaligned,
                         Eigen::OuterStride<>>
            newest_a(pose_cov_ + (kStateDim * adj_[a].pose) * kMaxPosesDim + npd - kStateDim,
                     Eigen::OuterStride<>(kMaxPosesDim));
        l.cross_newest -= newest_a * oa.w_pl * l.h_inv;
        for (int b = lm_begin_[i]; b < lm_begin_[i + 1]; ++b) {
          const Observation& ob = ObsAt(adj_[b]);
          const Eigen::Map<const Mat6<S>, Eigen::Unaligned, Eigen::OuterStride<>> sigma(
              pose_cov_ + (kStateDim * adj_[b].pose) * kMaxPosesDim + kStateDim * adj_[a].pose,
              Eigen::OuterStride<>(kMaxPosesDim));
          cross += oa.w_pl.transpose() * sigma * ob.w_pl;
        }
      }
      l.covariance = l.h_inv + l.h_inv * cross * l.h_inv;
      l.covariance_valid = l.covariance.allFinite();
    }
    newest_state_cov_ = StateCovariance(num_poses_ - 1);
    newest_pose_cov_ = newest_state_cov_.template topLeftCorner<6, 6>();
    covariances_current_ = newest_state_cov_.allFinite();
    return core::Status::kOk;
  }

  // ---- results -----------------------------------------------------------------------------
  int NumPoses() const { return num_poses_; }
  int WindowSize() const { return window_; }
  const PoseType& PoseAt(int j) const { return Slot(j).pose; }  // 0 = oldest
  const PoseType& NewestPose() const { return Slot(num_poses_ - 1).pose; }
  int NumLandmarks() const { return num_landmarks_; }
  int NumPriorLandmarks() const { return static_cast<int>(prior_landmarks_.size()); }

  // World position of an active landmark; false for an unknown id or a point the model cannot
  // place (an inverse-depth landmark at or beyond infinity).
  bool GetLandmark(std::int64_t id, Vec3<S>* position) const {
    const int slot = ids_.Find(id);
    if (slot < 0) return false;
    return Model::LandmarkPosition(landmarks_[slot].anchor, landmarks_[slot].params, position,
                                   nullptr);
  }
  // World-frame covariance (the parameters' covariance mapped through dl/dm), after
  // ComputeCovariances().
  bool GetLandmarkCovariance(std::int64_t id, Mat3<S>* covariance) const {
    const int slot = ids_.Find(id);
    if (slot < 0) return false;
    Vec3<S> position;
    Mat3<S> j;
    const LandmarkSlot& l = landmarks_[slot];
    if (!Model::LandmarkPosition(l.anchor, l.params, &position, &j)) return false;
    *covariance = j * l.covariance * j.transpose();
    return true;
  }
  // Covariance of state j's whole update vector and of its pose part ([rho; phi]), after
  // ComputeCovariances().
  StateMat StateCovariance(int j) const {
    StateMat c;
    for (int k = 0; k < kStateDim; ++k)
      for (int r = 0; r < kStateDim; ++r)
        c(r, k) = pose_cov_[(kStateDim * j + k) * kMaxPosesDim + kStateDim * j + r];
    return c;
  }
  Mat6<S> PoseCovariance(int j) const { return StateCovariance(j).template topLeftCorner<6, 6>(); }
  const Mat6<S>& NewestPoseCovariance() const { return newest_pose_cov_; }
  const StateMat& NewestStateCovariance() const { return newest_state_cov_; }

  // Calls f(id, world position, observations in window) for every active landmark the model
  // can place, in slot order.
  template <typename F>
  void ForEachLandmark(F&& f) const {
    Vec3<S> position;
    for (int i = 0; i < N; ++i) {
      const LandmarkSlot& l = landmarks_[i];
      if (l.used && Model::LandmarkPosition(l.anchor, l.params, &position, nullptr))
        f(l.id, position, l.obs_in_window);
    }
  }

  const core::StaticVector<RetiredLandmark<S>, N>& Retired() const { return retired_; }
  const SwfSummary& Summary() const { return summary_; }
  std::uint32_t FaultBits() const { return fault_bits_; }
  void ClearFaults() { fault_bits_ = 0; }
  const SwfOptions& Options() const { return options_; }

  // Total cost 0.5 * sum |W (z - h)|^2 of the measurements alone (no robust kernel, no prior,
  // no process model): the bundle-adjustment cost used to compare with other solvers.
  double MeasurementCost() {
    EvaluateMeasurements(false);
    double cost = 0.0;
    for (int j = 0; j < num_poses_; ++j)
      for (const Observation& o : Slot(j).obs)
        if (o.valid) cost += 0.5 * static_cast<double>(o.r.squaredNorm());
    return cost;
  }

 private:
  static constexpr int kMaxPosesDim = kStateDim * kMaxPoses;

  struct Observation {
    std::int32_t landmark = -1;
    Vec3<S> z = Vec3<S>::Zero();
    Mat3<S> sqrt_info = Mat3<S>::Identity();
    // Linearization workspace (whitened residual and Jacobians, Huber weight, coupling block).
    Vec3<S> r = Vec3<S>::Zero();
    Mat36<S> jp = Mat36<S>::Zero();  // with respect to the pose part of the state
    Mat3<S> jl = Mat3<S>::Zero();
    Eigen::Matrix<S, 6, 3> w_pl = Eigen::Matrix<S, 6, 3>::Zero();
    S weight = S(1);
    bool valid = false;
    bool gate_failed = false;  // failed the prediction gate when it was added
  };

  struct PoseSlot {
    PoseType pose{};
    MotionType motion{};  // process input from the previous pose, if has_process
    StateMat process_sqrt_info = StateMat::Zero();
    bool has_process = false;
    bool fixed = false;
    core::StaticVector<Observation, M> obs;
  };

  struct LandmarkSlot {
    bool used = false;
    std::int64_t id = 0;
    Vec3<S> params = Vec3<S>::Zero();  // the model's landmark parameters (stereo_model.hpp)
    LandmarkAnchor anchor{};           // constant, fixed by the model at creation
    int prior_index = -1;              // position in prior_landmarks_, or -1 for a free landmark
    int obs_in_window = 0;
    int total_obs = 0;
    // Per-iteration workspace.
    int lm_count = 0;
    Mat3<S> h = Mat3<S>::Zero();
    Vec3<S> b = Vec3<S>::Zero();
    Mat3<S> h_inv = Mat3<S>::Zero();
    Vec3<S> delta = Vec3<S>::Zero();
    bool invertible = false;
    Vec3<S> backup = Vec3<S>::Zero();
    Mat3<S> covariance = Mat3<S>::Zero();
    Eigen::Matrix<S, kStateDim, 3> cross_newest =
        Eigen::Matrix<S, kStateDim, 3>::Zero();  // Cov(newest state, l)
    bool covariance_valid = false;               // both are from the last ComputeCovariances()
  };

  struct AdjEntry {
    std::int32_t pose = 0;
    std::int32_t obs = 0;
  };

  // Fixed-capacity open-addressing map from landmark id to slot (linear probing, deletion by
  // backward shift so no tombstones accumulate).
  class IdMap {
   public:
    void Clear() {
      for (int i = 0; i < kSize; ++i) used_[i] = false;
    }
    int Find(std::int64_t key) const {
      for (int i = Hash(key), n = 0; n < kSize; i = (i + 1) & (kSize - 1), ++n) {
        if (!used_[i]) return -1;
        if (keys_[i] == key) return values_[i];
      }
      return -1;
    }
    void Insert(std::int64_t key, int value) {
      for (int i = Hash(key), n = 0; n < kSize; i = (i + 1) & (kSize - 1), ++n) {
        if (!used_[i] || keys_[i] == key) {
          used_[i] = true;
          keys_[i] = key;
          values_[i] = value;
          return;
        }
      }
      SWF_ASSERT(false);  // cannot happen: the table holds twice the landmark capacity
    }
    void Erase(std::int64_t key) {
      int i = Hash(key);
      for (int n = 0; n < kSize; ++n, i = (i + 1) & (kSize - 1)) {
        if (!used_[i]) return;
        if (keys_[i] == key) break;
      }
      if (!used_[i] || keys_[i] != key) return;
      // Backward-shift the following cluster so every remaining key stays reachable.
      int hole = i;
      for (int j = (i + 1) & (kSize - 1), n = 0; n < kSize && used_[j];
           j = (j + 1) & (kSize - 1), ++n) {
        const int home = Hash(keys_[j]);
        const bool movable = hole <= j ? (home <= hole || home > j) : (home <= hole && home > j);
        if (movable) {
          keys_[hole] = keys_[j];
          values_[hole] = values_[j];
          hole = j;
        }
      }
      used_[hole] = false;
    }

   private:
    static constexpr int kSize = [] {
      int s = 1;
      while (s < 2 * N) s <<= 1;
      return s;
    }();
    static int Hash(std::int64_t key) {
      std::uint64_t x = static_cast<std::uint64_t>(key) + 0x9e3779b97f4a7c15ull;
      x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
      x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
      x ^= x >> 31;
      return static_cast<int>(x & static_cast<std::uint64_t>(kSize - 1));
    }
    std::int64_t keys_[kSize];
    int values_[kSize];
    bool used_[kSize] = {};
  };

  template <int R, int C>
  using BlockMap = Eigen::Map<Eigen::Matrix<S, R, C>, Eigen::Unaligned, Eigen::OuterStride<>>;
  template <int R, int C>
  static BlockMap<R, C> Blk(S* a, int ld, int row, int col) {
    return BlockMap<R, C>(a + col * ld + row, Eigen::OuterStride<>(ld));
  }

  PoseSlot& Slot(int j) { return poses_[(head_ + j) % kMaxPoses]; }
  const PoseSlot& Slot(int j) const { return poses_[(head_ + j) % kMaxPoses]; }
  PoseSlot& Newest() { return Slot(num_poses_ - 1); }
  Observation& ObsAt(const AdjEntry& e) { return Slot(e.pose).obs[e.obs]; }

  core::Status PushPose(const PoseType& estimate, const MotionType* u, const StateMat* sqrt_info) {
    if (!configured_) return core::Status::kNotConfigured;
    const int limit = options_.mode == SwfMode::kBatch ? window_ : window_ + 1;
    if (num_poses_ >= limit) return core::Status::kFull;
    if (num_poses_ == 0) head_ = 0;
    ++num_poses_;
    predicted_cov_valid_ =
        u != nullptr && num_poses_ >= 2 && covariances_current_ &&
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

  // The prior over the very first pose: fixed (gauge) or a Gaussian around its estimate (the
  // model gives the sigmas of the state beyond the pose).
  void InitializePrior() {
    prior_landmarks_.clear();
    ClearPosePrior();
    prior_pose_lin_ = Slot(0).pose;
    const bool fixed = options_.fix_first_pose || options_.mode == SwfMode::kVisualOdometry;
    Slot(0).fixed = fixed;
    if (!fixed) {
      for (int i = 0; i < 3; ++i) {
        prior_[i * kMaxPriorDim + i] =
            S(1.0 / (options_.first_pose_sigma_m * options_.first_pose_sigma_m));
        prior_[(i + 3) * kMaxPriorDim + i + 3] =
            S(1.0 / (options_.first_pose_sigma_rad * options_.first_pose_sigma_rad));
      }
      if constexpr (kStateDim > 6) {
        const Eigen::Matrix<S, kStateDim - 6, 1> sigma = model_.FirstStateSigmas();
        for (int i = 6; i < kStateDim; ++i)
          prior_[i * kMaxPriorDim + i] = S(1) / (sigma[i - 6] * sigma[i - 6]);
      }
    }
  }

  void ClearPosePrior() {
    prior_dim_ = kStateDim;
    for (int c = 0; c < kStateDim; ++c)
      for (int r = 0; r < kStateDim; ++r) prior_[c * kMaxPriorDim + r] = S(0);
    for (int i = 0; i < kStateDim; ++i) prior_g_[i] = S(0);
  }

  bool StateIsFinite() const {
    for (int j = 0; j < num_poses_; ++j) {
      const StateVec d = Model::Difference(prior_pose_lin_, Slot(j).pose, &scratch_jacobian_);
      if (!d.allFinite()) return false;
    }
    for (int i = 0; i < N; ++i)
      if (landmarks_[i].used && !landmarks_[i].params.allFinite()) return false;
    for (int r = 0; r < prior_dim_; ++r)
      if (!std::isfinite(prior_g_[r])) return false;
    return true;
  }

  // ---- integrity gates (SwfOptions::gate_probability) ----------------------------------------

  static bool IsSolved(core::Status s) {
    return s == core::Status::kOk || s == core::Status::kNotConverged;
  }

  // Covariance of the pose predicted by the process model from `prev` (whose marginal is the
  // last computed newest-pose covariance): linearizing r = f(prev, next, u) ~ N(0, Q) gives
  // A d_prev + B d_next = w, so d_next = Phi d_prev + B^-1 w with Phi = -B^-1 A and
  // P_next = B^-1 (A P_prev A^T + Q) B^-T. Phi carries prev's correlation with the landmarks.
  bool PredictPoseCovariance(const PoseType& prev, const PoseType& next, const MotionType& u,
                             const StateMat& sqrt_info, StateMat* covariance,
                             StateMat* transition) const {
    StateMat a;
    StateMat b;
    (void)model_.ProcessResidual(prev, next, u, &a, &b);
    const Eigen::FullPivLU<StateMat> w(sqrt_info);
    const Eigen::FullPivLU<StateMat> lu(b);
    if (!w.isInvertible() || !lu.isInvertible()) return false;
    const StateMat w_inv = w.inverse();
    const StateMat b_inv = lu.inverse();
    *covariance = b_inv * (a * newest_state_cov_ * a.transpose() + w_inv * w_inv.transpose()) *
                  b_inv.transpose();
    *transition = -b_inv * a;
    return covariance->allFinite();
  }

  // Before fusion: the squared Mahalanobis distance of the innovation z - h against its
  // covariance R + J_p P_pose J_p^T + J_l P_l J_l^T + J_p C J_l^T + (J_p C J_l^T)^T, with
  // C = Phi Cov(prev pose, l). The correlation matters: pose and landmarks drift together, and
  // without C the gate would be loose by the whole absolute uncertainty of the path.
  bool FailsPredictionGate(const PoseType& pose, const LandmarkSlot& l, const Vec3<S>& z,
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
    const Eigen::FullPivLU<Mat3<S>> w(sqrt_info);
    if (!w.isInvertible()) return true;
    const Mat3<S> w_inv = w.inverse();
    const Mat3<S> coupling =
        jp * prediction_transition_.template topRows<6>() * l.cross_newest * jl.transpose();
    const Mat3<S> innovation_cov =
        w_inv * w_inv.transpose() +
        jp * predicted_pose_cov_.template topLeftCorner<6, 6>() * jp.transpose() +
        jl * l.covariance * jl.transpose() + coupling + coupling.transpose();
    const Eigen::LDLT<Mat3<S>> ldlt(innovation_cov);
    ++pending_.gate_checked;
    const Vec3<S> e = z - h;
    const S d2 = e.dot(ldlt.solve(e));
    return !(ldlt.info() == Eigen::Success && std::isfinite(d2) && d2 <= gate_threshold_);
  }

  // A new landmark's single stereo sighting must determine it: the 3x3 information J^T R^-1 J
  // is positive definite and, with max_init_sigma_m, its world covariance is small enough.
  bool TriangulationAcceptable(const PoseType& pose, const LandmarkAnchor& anchor,
                               const Vec3<S>& params, const Mat3<S>& sqrt_info) const {
    Vec3<S> h;
    Mat36<S> jp;  // the models fill the landmark Jacobian only together with the pose's
    Mat3<S> jl;
    if (!model_.Predict(pose, anchor, params, &h, &jp, &jl)) return false;
    const Mat3<S> jw = sqrt_info * jl;
    const Eigen::LLT<Mat3<S>> llt(jw.transpose() * jw);
    if (llt.info() != Eigen::Success) return false;
    if (options_.max_init_sigma_m <= 0.0) return true;
    Vec3<S> position;
    Mat3<S> dl_dm;
    if (!Model::LandmarkPosition(anchor, params, &position, &dl_dm)) return false;
    const Mat3<S> world_cov = dl_dm * llt.solve(Mat3<S>::Identity()) * dl_dm.transpose();
    const Eigen::SelfAdjointEigenSolver<Mat3<S>> eig(world_cov, Eigen::EigenvaluesOnly);
    const S largest = eig.eigenvalues()(2);
    return std::isfinite(largest) &&
           largest <= S(options_.max_init_sigma_m * options_.max_init_sigma_m);
  }

  // Removes the newest pose's measurements that failed the prediction gate, unless too many
  // failed (then the prediction is the suspect: keep them, flag kFaultGateSuspended).
  void ApplyPredictionGate() {
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
      --l.obs_in_window;
      --l.total_obs;
      p.obs.erase(k);
      ++summary_.measurements_gated;
    }
  }

  // After a solve: measurements whose whitened residual, in inlier sigmas, exceeds the gate
  // are removed; a landmark with every window measurement failing is removed whole. Returns
  // how many measurements went. Stands down (flags) when too many fail.
  int RejectResidualOutliers() {
    if (gate_threshold_ <= S(0)) return 0;
    const S sigma = InlierSigma();
    const S limit = gate_threshold_ * sigma * sigma;
    int checked = 0;
    int failed = 0;
    for (int i = 0; i < N; ++i) landmarks_[i].lm_count = 0;
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
    for (int i = 0; i < N; ++i) {
      LandmarkSlot& l = landmarks_[i];
      if (l.used && l.lm_count > 0 && l.lm_count == l.obs_in_window) {
        RemoveLandmark(i);
        ++summary_.landmarks_rejected;
      }
    }
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

  // Takes a landmark out with all its window measurements. A prior landmark is marginalized
  // out of the prior (what earlier measurements told about the rest stays there).
  void RemoveLandmark(int slot) {
    LandmarkSlot& l = landmarks_[slot];
    for (int j = 0; j < num_poses_; ++j) {
      PoseSlot& p = Slot(j);
      for (std::size_t k = p.obs.size(); k-- > 0;)
        if (p.obs[k].landmark == slot) p.obs.erase(k);
    }
    if (l.prior_index >= 0 && !EliminatePriorLandmark(l.prior_index))
      fault_bits_ |= kFaultNotPositiveDefinite;
    ids_.Erase(l.id);
    l.used = false;
    l.obs_in_window = 0;
    (void)free_slots_.push_back(slot);
    --num_landmarks_;
  }

  S InlierSigma() const {
    return options_.robust && tau_ < S(1e29) ? tau_ / S(options_.huber_k) : S(1);
  }

  // The health monitor's evidence from the final linearization (integrity.hpp).
  void RecordEvidence() {
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

  // The motion gate (SwfOptions::motion_gate_weight), before any measurement gate: the newest
  // pose fitted to its measurements of landmarks seen before (robust Gauss-Newton on
  // that pose alone, landmarks held) is compared with the motion prediction. When they
  // disagree beyond the gate and the fit has the inliers to be believed, the fitted pose
  // replaces the prediction as the linearization point, the process factor is down-weighted,
  // and the prediction gate (made against the bad prediction) is cleared for this frame.
  struct MotionGateResult {
    double chi2 = 0.0;
    bool failed = false;
    bool overruled = false;
  };

  MotionGateResult GateNewestMotion() {
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
      const StateMat w_inv = p.process_sqrt_info.inverse();
      covariance = (w_inv * w_inv.transpose()).template topLeftCorner<6, 6>();
    }
    const Eigen::LDLT<Mat6<S>> fit(information);
    if (fit.info() != Eigen::Success) return result;
    covariance += fit.solve(Mat6<S>::Identity());
    const Eigen::LDLT<Mat6<S>> ldlt(covariance);
    if (ldlt.info() != Eigen::Success) return result;
    const S chi2 = d.dot(ldlt.solve(d));
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
  int FitNewestPose(PoseType* pose, Mat6<S>* information) {
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
      const Eigen::LDLT<Mat6<S>> ldlt(h);
      if (ldlt.info() != Eigen::Success) return 0;
      StateVec delta = StateVec::Zero();
      delta.template head<6>() = ldlt.solve(g);
      if (!delta.allFinite()) return 0;
      *pose = Model::Retract(*pose, delta);
      if (delta.norm() < S(1e-9)) break;
    }
    return inliers;
  }

  // (R + J_l P_l J_l^T)^(-1/2) at the prediction, when the landmark's marginal is known: a
  // landmark seen from one earlier pose is far less certain than the pixel noise. Held fixed
  // over the fit's iterations so that Gauss-Newton converges as on a fixed weighting.
  Mat3<S> FitWhitening(const PoseType& prediction, const Observation& o,
                       const LandmarkSlot& l) const {
    Vec3<S> z_hat;
    Mat36<S> jp;
    Mat3<S> jl;
    if (!l.covariance_valid || !model_.Predict(prediction, l.anchor, l.params, &z_hat, &jp, &jl))
      return o.sqrt_info;
    const Mat3<S> r_inv = (o.sqrt_info.transpose() * o.sqrt_info).inverse();
    const Eigen::LLT<Mat3<S>> llt(r_inv + jl * l.covariance * jl.transpose());
    if (llt.info() != Eigen::Success) return o.sqrt_info;
    return llt.matrixL().solve(Mat3<S>::Identity());
  }

  // ---- linearization -----------------------------------------------------------------------

  // Whitened residuals (and Jacobians) of every measurement at the current state.
  void EvaluateMeasurements(bool with_jacobians) {
    for (int j = 0; j < num_poses_; ++j) {
      PoseSlot& p = Slot(j);
      for (Observation& o : p.obs) EvaluateObservation(p.pose, &o, with_jacobians);
    }
  }

  void EvaluateObservation(const PoseType& pose, Observation* o, bool with_jacobians) {
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

  // Huber threshold from the inlier standard deviation: sigma_hat = median |r| / median of the
  // chi distribution with 3 degrees of freedom (1.5382), floored at the nominal 1 and capped at
  // max_robust_sigma. Without the cap the threshold follows the median up while the state
  // diverges (seen on EuRoC and KITTI: tens of nominal sigmas within a few frames), and
  // the data that disagrees with the drifting state gets its full weight back exactly then.
  // The uncapped scale is kept as evidence for the health monitor (residual_scale_).
  void UpdateRobustWeights() {
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

  void ApplyWeights() {
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

  S HuberCost(S squared_norm) const {
    const S norm = std::sqrt(squared_norm);
    return norm <= tau_ ? S(0.5) * squared_norm : tau_ * norm - S(0.5) * tau_ * tau_;
  }

  // Robust cost of all three information sources at the current state (residuals must be
  // evaluated). Used to accept or shorten steps.
  S TotalCost() {
    S cost = S(0);
    for (int j = 0; j < num_poses_; ++j)
      for (const Observation& o : Slot(j).obs)
        if (o.valid) cost += HuberCost(o.r.squaredNorm());
    for (int j = 1; j < num_poses_; ++j) {
      const PoseSlot& p = Slot(j);
      if (!p.has_process) continue;
      StateMat a;
      StateMat b;
      const StateVec r =
          p.process_sqrt_info * model_.ProcessResidual(Slot(j - 1).pose, p.pose, p.motion, &a, &b);
      cost += S(0.5) * r.squaredNorm();
    }
    // 0.5 Delta^T Pi Delta - g^T Delta = Delta^T (0.5 (grad + g) - g) with grad = Pi Delta - g.
    PriorGradient();
    for (int r = 0; r < prior_dim_; ++r)
      cost += prior_delta_[r] * (S(0.5) * (prior_grad_[r] + prior_g_[r]) - prior_g_[r]);
    return cost;
  }

  // prior_grad_ = Pi Delta - g at the current state (Delta coordinates). Accumulated column by
  // column so the inner loop is contiguous. (A strided row-dot-product form of this loop was
  // mis-vectorized by GCC 12 at -O3 into an aligned load of a misaligned address.)
  void PriorGradient() {
    PriorDelta();
    for (int r = 0; r < prior_dim_; ++r) prior_grad_[r] = -prior_g_[r];
    for (int c = 0; c < prior_dim_; ++c) {
      const S dc = prior_delta_[c];
      const S* column = prior_ + c * kMaxPriorDim;
      for (int r = 0; r < prior_dim_; ++r) prior_grad_[r] += column[r] * dc;
    }
  }

  // Delta = x (-) x_bar for the prior's variables and the pose block's Jacobian.
  void PriorDelta() {
    const StateVec d = Model::Difference(prior_pose_lin_, Slot(0).pose, &prior_pose_jacobian_);
    for (int i = 0; i < kStateDim; ++i) prior_delta_[i] = d[i];
    for (int q = 0; q < static_cast<int>(prior_landmarks_.size()); ++q) {
      const Vec3<S> dl = landmarks_[prior_landmarks_[q]].params - prior_landmark_lin_[q];
      for (int k = 0; k < 3; ++k) prior_delta_[kStateDim + 3 * q + k] = dl[k];
    }
  }

  // Builds the reduced system S dx_D = s over [poses ; prior landmarks] (free landmarks
  // eliminated) and factorizes it. Measurements must be evaluated with Jacobians and weighted.
  core::Status BuildAndFactor() {
    const int np = num_poses_;
    const int nq = static_cast<int>(prior_landmarks_.size());
    const int lm0 = kStateDim * np;
    const int n = lm0 + 3 * nq;
    dense_.Reset(n);
    for (int i = 0; i < n; ++i) rhs_[i] = S(0);
    for (int i = 0; i < N; ++i) {
      landmarks_[i].h.setZero();
      landmarks_[i].b.setZero();
      landmarks_[i].lm_count = 0;
    }
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
    for (int i = 0; i < N; ++i) {
      lm_begin_[i] = offset;
      offset += landmarks_[i].lm_count;
      landmarks_[i].lm_count = 0;
    }
    lm_begin_[N] = offset;
    for (int j = 0; j < np; ++j) {
      const PoseSlot& p = Slot(j);
      for (int k = 0; k < static_cast<int>(p.obs.size()); ++k) {
        if (!p.obs[k].valid) continue;
        LandmarkSlot& l = landmarks_[p.obs[k].landmark];
        adj_[lm_begin_[p.obs[k].landmark] + l.lm_count++] = AdjEntry{j, k};
      }
    }
    // Process model (D^T Q^-1 D).
    for (int j = 1; j < np; ++j) {
      const PoseSlot& p = Slot(j);
      if (!p.has_process) continue;
      StateMat a;
      StateMat b;
      const StateVec e = model_.ProcessResidual(Slot(j - 1).pose, p.pose, p.motion, &a, &b);
      const StateVec r = p.process_sqrt_info * e;
      a = p.process_sqrt_info * a;
      b = p.process_sqrt_info * b;
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
    for (int i = 0; i < N; ++i) {
      LandmarkSlot& l = landmarks_[i];
      l.invertible = false;
      if (!l.used || l.prior_index >= 0 || lm_begin_[i] == lm_begin_[i + 1]) continue;
      const Eigen::LLT<Mat3<S>> llt(l.h);
      if (llt.info() != Eigen::Success || !(l.h.trace() > S(0))) {
        fault_bits_ |= kFaultDegenerateLandmark;
        continue;  // held at its current estimate for this iteration
      }
      l.h_inv = llt.solve(Mat3<S>::Identity());
      l.invertible = true;
      for (int a = lm_begin_[i]; a < lm_begin_[i + 1]; ++a) {
        const Observation& oa = ObsAt(adj_[a]);
        const Eigen::Matrix<S, 6, 3> x = oa.w_pl * l.h_inv;
        Blk<6, 1>(rhs_, kMaxDense, kStateDim * adj_[a].pose, 0) -= x * l.b;
        for (int b = lm_begin_[i]; b < lm_begin_[i + 1]; ++b) {
          if (adj_[a].pose < adj_[b].pose) continue;
          const Observation& ob = ObsAt(adj_[b]);
          dense_.AddBlock(kStateDim * adj_[a].pose, kStateDim * adj_[b].pose,
                          -(x * ob.w_pl.transpose()));
        }
      }
    }
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

  void AddPrior(int lm0) {
    const int nq = static_cast<int>(prior_landmarks_.size());
    PriorGradient();
    const StateMat& jp = prior_pose_jacobian_;
    const StateMat pi_pp = Blk<kStateDim, kStateDim>(prior_, kMaxPriorDim, 0, 0);
    dense_.AddBlock(0, 0, jp.transpose() * pi_pp * jp);
    Blk<kStateDim, 1>(rhs_, kMaxDense, 0, 0) -=
        jp.transpose() * Blk<kStateDim, 1>(prior_grad_, kMaxPriorDim, 0, 0);
    for (int q = 0; q < nq; ++q) {
      const Eigen::Matrix<S, 3, kStateDim> pi_qp =
          Blk<3, kStateDim>(prior_, kMaxPriorDim, kStateDim + 3 * q, 0);
      dense_.AddBlock(lm0 + 3 * q, 0, pi_qp * jp);
      Blk<3, 1>(rhs_, kMaxDense, lm0 + 3 * q, 0) -=
          Blk<3, 1>(prior_grad_, kMaxPriorDim, kStateDim + 3 * q, 0);
    }
    // Landmark-landmark block of Pi, copied as a whole (it is dense: Fig. 8).
    dense_.AddSymmetric(lm0, prior_ + kStateDim * kMaxPriorDim + kStateDim, kMaxPriorDim, 3 * nq);
  }

  // ---- solving -----------------------------------------------------------------------------

  core::Status Solve() {
    int total = 0;
    for (int j = 0; j < num_poses_; ++j) total += static_cast<int>(Slot(j).obs.size());
    summary_.num_measurements = total;
    summary_.state_dimension = kStateDim * num_poses_ + 3 * num_landmarks_;
    summary_.termination = SwfTermination::kNoSolve;
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
      for (int i = 0; i < N; ++i) {
        LandmarkSlot& l = landmarks_[i];
        if (!l.used) continue;
        if (l.prior_index >= 0) {
          l.delta = Blk<3, 1>(rhs_, kMaxDense, lm0 + 3 * l.prior_index, 0);
          continue;
        }
        l.delta.setZero();
        if (!l.invertible) continue;
        Vec3<S> g = l.b;
        for (int a = lm_begin_[i]; a < lm_begin_[i + 1]; ++a)
          g -= ObsAt(adj_[a]).w_pl.transpose() *
               Blk<6, 1>(rhs_, kMaxDense, kStateDim * adj_[a].pose, 0);
        l.delta = l.h_inv * g;
        max_step = std::max(max_step, l.delta.cwiseAbs().maxCoeff());
        finite = finite && l.delta.allFinite();
      }
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
    if (status == core::Status::kOk && !summary_.Converged()) {
      fault_bits_ |= kFaultNotConverged;
      status = core::Status::kNotConverged;
    }
    // Leave the linearization (and weights) at the final state for marginalization/covariance.
    EvaluateMeasurements(true);
    ApplyWeights();
    return status;
  }

  void Backup() {
    for (int j = 0; j < num_poses_; ++j) pose_backup_[j] = Slot(j).pose;
    for (int i = 0; i < N; ++i)
      if (landmarks_[i].used) landmarks_[i].backup = landmarks_[i].params;
  }
  void Restore() {
    for (int j = 0; j < num_poses_; ++j) Slot(j).pose = pose_backup_[j];
    for (int i = 0; i < N; ++i)
      if (landmarks_[i].used) landmarks_[i].params = landmarks_[i].backup;
  }
  void ApplyStep(S alpha) {
    for (int j = 0; j < num_poses_; ++j) {
      if (Slot(j).fixed) continue;
      const StateVec d = alpha * StateVec(Blk<kStateDim, 1>(rhs_, kMaxDense, kStateDim * j, 0));
      Slot(j).pose = Model::Retract(pose_backup_[j], d);
    }
    for (int i = 0; i < N; ++i) {
      LandmarkSlot& l = landmarks_[i];
      if (l.used) l.params = l.backup + alpha * l.delta;
    }
  }

  // ---- marginalization ---------------------------------------------------------------------

  // Removes the oldest pose by the Schur complement (eqs. 8-10), or by its block diagonal only
  // in VSDF mode (eq. 12). See the file comment for the local system it forms.
  void MarginalizeOldestPose() {
    PoseSlot& p0 = Slot(0);
    PoseSlot& p1 = Slot(1);
    // Variables of the new prior: the old prior landmarks (same order), then landmarks seen
    // from p0 that are not yet in the prior, as long as the prior has room.
    for (Observation& o : p0.obs) {
      EvaluateObservation(p0.pose, &o, true);
      if (!o.valid) continue;
      LandmarkSlot& l = landmarks_[o.landmark];
      if (l.prior_index >= 0) continue;
      if (prior_landmarks_.full()) {
        o.valid = false;  // its information is dropped, and reported
        fault_bits_ |= kFaultPriorCapacity;
        continue;
      }
      l.prior_index = static_cast<int>(prior_landmarks_.size());
      (void)prior_landmarks_.push_back(o.landmark);
      prior_landmark_lin_[l.prior_index] = l.params;
      first_estimate_[l.prior_index] = l.params;
      // A new prior variable enters with zero information about itself until the Schur below.
      GrowPrior();
    }
    const int nq = static_cast<int>(prior_landmarks_.size());
    const int dim = 2 * kStateDim + 3 * nq;  // [p0 | p1 | landmarks]
    for (int c = 0; c < dim; ++c)
      for (int r = 0; r < dim; ++r) local_[c * kMaxLocalDim + r] = S(0);
    for (int r = 0; r < dim; ++r) local_b_[r] = S(0);
    auto local_index = [](int prior_index) {
      return prior_index < kStateDim ? prior_index : prior_index + kStateDim;
    };
    // Prior at the current estimate: Hessian J^T Pi J, right-hand side -J^T (Pi Delta - g).
    PriorGradient();
    // J = blockdiag(prior_pose_jacobian_, I): scale the pose rows/columns of Pi.
    for (int c = 0; c < prior_dim_; ++c)
      for (int r = 0; r < prior_dim_; ++r)
        local_[local_index(c) * kMaxLocalDim + local_index(r)] = prior_[c * kMaxPriorDim + r];
    {
      const StateMat& jp = prior_pose_jacobian_;
      Blk<kStateDim, kStateDim>(local_, kMaxLocalDim, 0, 0) =
          jp.transpose() * Blk<kStateDim, kStateDim>(prior_, kMaxPriorDim, 0, 0) * jp;
      for (int q = 0; q < nq; ++q) {
        const Eigen::Matrix<S, 3, kStateDim> pi_qp =
            Blk<3, kStateDim>(prior_, kMaxPriorDim, kStateDim + 3 * q, 0);
        Blk<3, kStateDim>(local_, kMaxLocalDim, 2 * kStateDim + 3 * q, 0) = pi_qp * jp;
        Blk<kStateDim, 3>(local_, kMaxLocalDim, 0, 2 * kStateDim + 3 * q) =
            (pi_qp * jp).transpose();
      }
      Blk<kStateDim, 1>(local_b_, kMaxLocalDim, 0, 0) =
          -(jp.transpose() * Blk<kStateDim, 1>(prior_grad_, kMaxPriorDim, 0, 0));
      for (int r = kStateDim; r < prior_dim_; ++r) local_b_[r + kStateDim] = -prior_grad_[r];
    }
    // Process factor between p0 and p1.
    if (p1.has_process) {
      StateMat a;
      StateMat b;
      const StateVec e = model_.ProcessResidual(p0.pose, p1.pose, p1.motion, &a, &b);
      const StateVec r = p1.process_sqrt_info * e;
      a = p1.process_sqrt_info * a;
      b = p1.process_sqrt_info * b;
      Blk<kStateDim, kStateDim>(local_, kMaxLocalDim, 0, 0) += a.transpose() * a;
      Blk<kStateDim, kStateDim>(local_, kMaxLocalDim, kStateDim, kStateDim) += b.transpose() * b;
      Blk<kStateDim, kStateDim>(local_, kMaxLocalDim, kStateDim, 0) += b.transpose() * a;
      Blk<kStateDim, kStateDim>(local_, kMaxLocalDim, 0, kStateDim) += a.transpose() * b;
      Blk<kStateDim, 1>(local_b_, kMaxLocalDim, 0, 0) -= a.transpose() * r;
      Blk<kStateDim, 1>(local_b_, kMaxLocalDim, kStateDim, 0) -= b.transpose() * r;
    }
    // p0's measurements, with the weights of the last solve.
    for (const Observation& o : p0.obs) {
      if (!o.valid) continue;
      const int k = 2 * kStateDim + 3 * landmarks_[o.landmark].prior_index;
      const S norm = o.r.norm();
      const S w = norm <= tau_ ? S(1) : tau_ / norm;
      Blk<6, 6>(local_, kMaxLocalDim, 0, 0) += w * o.jp.transpose() * o.jp;
      Blk<3, 3>(local_, kMaxLocalDim, k, k) += w * o.jl.transpose() * o.jl;
      Blk<3, 6>(local_, kMaxLocalDim, k, 0) += w * o.jl.transpose() * o.jp;
      Blk<6, 3>(local_, kMaxLocalDim, 0, k) += w * o.jp.transpose() * o.jl;
      Blk<6, 1>(local_b_, kMaxLocalDim, 0, 0) += w * o.jp.transpose() * o.r;
      Blk<3, 1>(local_b_, kMaxLocalDim, k, 0) += w * o.jl.transpose() * o.r;
    }
    // Eliminate p0 (or condition on it when it is fixed).
    if (!p0.fixed) {
      const bool diagonal_only = options_.mode == SwfMode::kVsdf;
      if (!EliminateFirstPose(dim, diagonal_only)) fault_bits_ |= kFaultNotPositiveDefinite;
    }
    // The new prior is the [p1 | landmarks] part, linearized at the current estimate.
    prior_dim_ = dim - kStateDim;
    for (int c = 0; c < prior_dim_; ++c)
      for (int r = 0; r < prior_dim_; ++r)
        prior_[c * kMaxPriorDim + r] = local_[(c + kStateDim) * kMaxLocalDim + r + kStateDim];
    for (int r = 0; r < prior_dim_; ++r) prior_g_[r] = local_b_[r + kStateDim];
    prior_pose_lin_ = p1.pose;
    for (int q = 0; q < nq; ++q) prior_landmark_lin_[q] = landmarks_[prior_landmarks_[q]].params;
    // Drop p0.
    for (const Observation& o : p0.obs) --landmarks_[o.landmark].obs_in_window;
    p0.obs.clear();
    head_ = (head_ + 1) % kMaxPoses;
    --num_poses_;
    Slot(0).has_process = false;  // consumed into the prior
  }

  // Adds three zero rows/columns to the prior for a landmark entering it.
  void GrowPrior() {
    const int d = prior_dim_;
    for (int c = 0; c < d + 3; ++c)
      for (int r = (c < d ? d : 0); r < d + 3; ++r) {
        prior_[c * kMaxPriorDim + r] = S(0);
        prior_[r * kMaxPriorDim + c] = S(0);
      }
    for (int r = d; r < d + 3; ++r) prior_g_[r] = S(0);
    prior_dim_ = d + 3;
  }

  // Schur complement of the first kStateDim variables (p0) of the local system onto the rest
  // (eq. 9).
  bool EliminateFirstPose(int dim, bool diagonal_only) {
    const StateMat aa = Blk<kStateDim, kStateDim>(local_, kMaxLocalDim, 0, 0);
    const Eigen::LLT<StateMat> llt(aa);
    if (llt.info() != Eigen::Success) return false;
    const StateMat t = llt.solve(StateMat::Identity());
    const StateVec ba = Blk<kStateDim, 1>(local_b_, kMaxLocalDim, 0, 0);
    const int chunks = (dim - kStateDim) / 3;
    // X_r = Lambda_ra Lambda_aa^-1 for each 3-row chunk r of the remaining variables.
    for (int r = 0; r < chunks; ++r) {
      const int row = kStateDim + 3 * r;
      Eigen::Matrix<S, 3, kStateDim> x = Blk<3, kStateDim>(local_, kMaxLocalDim, row, 0) * t;
      Blk<3, kStateDim>(x_, kXRows, 3 * r, 0) = x;
      Blk<3, 1>(local_b_, kMaxLocalDim, row, 0) -= x * ba;
    }
    // Chunks 0 .. kStateDim/3 - 1 are p1 (one variable), chunk k >= kStateDim/3 is landmark k -
    // kStateDim/3.
    auto variable = [](int chunk) { return chunk < kStateDim / 3 ? 0 : chunk - kStateDim / 3 + 1; };
    for (int c = 0; c < chunks; ++c) {
      const Eigen::Matrix<S, kStateDim, 3> a_c =
          Blk<kStateDim, 3>(local_, kMaxLocalDim, 0, kStateDim + 3 * c);
      for (int r = 0; r < chunks; ++r) {
        if (diagonal_only && variable(r) != variable(c)) continue;
        Blk<3, 3>(local_, kMaxLocalDim, kStateDim + 3 * r, kStateDim + 3 * c) -=
            Eigen::Matrix<S, 3, kStateDim>(Blk<3, kStateDim>(x_, kXRows, 3 * r, 0)) * a_c;
      }
    }
    return true;
  }

  // VO mode: forget the oldest pose and everything attached to it; hold the next one fixed.
  void DeleteOldestPose() {
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
  void RetireUnsupportedLandmarks() {
    for (int i = 0; i < N; ++i) {
      LandmarkSlot& l = landmarks_[i];
      if (!l.used || l.obs_in_window > 0) continue;
      if (options_.mode == SwfMode::kBatch) continue;
      if (l.prior_index >= 0) {
        if (!EliminatePriorLandmark(l.prior_index)) fault_bits_ |= kFaultNotPositiveDefinite;
      }
      RetiredLandmark<S> r;
      r.id = l.id;
      r.total_observations = l.total_obs;
      if (Model::LandmarkPosition(l.anchor, l.params, &r.position, nullptr)) {
        (void)retired_.push_back(r);
      } else {
        ++summary_.landmarks_unplaced;  // at or beyond infinity: no position to report
      }
      ids_.Erase(l.id);
      l.used = false;
      (void)free_slots_.push_back(i);
      --num_landmarks_;
      ++summary_.landmarks_marginalized;
    }
  }

  // Schur complement of prior landmark q onto the rest of the prior, then removal of its rows.
  bool EliminatePriorLandmark(int q) {
    const int o = kStateDim + 3 * q;
    const int d = prior_dim_;
    const Mat3<S> aa = Blk<3, 3>(prior_, kMaxPriorDim, o, o);
    const Eigen::LLT<Mat3<S>> llt(aa);
    const bool ok = llt.info() == Eigen::Success;
    if (ok) {
      const Mat3<S> t = llt.solve(Mat3<S>::Identity());
      const Vec3<S> go = Blk<3, 1>(prior_g_, kMaxPriorDim, o, 0);
      for (int r = 0; r < d / 3; ++r) {
        if (3 * r == o) continue;
        const Mat3<S> x = Blk<3, 3>(prior_, kMaxPriorDim, 3 * r, o) * t;
        Blk<3, 3>(x_, kXRows, 3 * r, 0) = x;
        Blk<3, 1>(prior_g_, kMaxPriorDim, 3 * r, 0) -= x * go;
      }
      for (int c = 0; c < d / 3; ++c) {
        if (3 * c == o) continue;
        const Mat3<S> a_c = Blk<3, 3>(prior_, kMaxPriorDim, o, 3 * c);
        for (int r = 0; r < d / 3; ++r) {
          if (3 * r == o) continue;
          Blk<3, 3>(prior_, kMaxPriorDim, 3 * r, 3 * c) -=
              Mat3<S>(Blk<3, 3>(x_, kXRows, 3 * r, 0)) * a_c;
        }
      }
    }
    // Remove rows/columns o..o+2 (order kept) and renumber the later prior landmarks.
    for (int c = 0; c < d; ++c) {
      if (c >= o && c < o + 3) continue;
      const int cc = c < o ? c : c - 3;
      for (int r = 0; r < d; ++r) {
        if (r >= o && r < o + 3) continue;
        const int rr = r < o ? r : r - 3;
        prior_[cc * kMaxPriorDim + rr] = prior_[c * kMaxPriorDim + r];
      }
    }
    for (int r = o + 3; r < d; ++r) prior_g_[r - 3] = prior_g_[r];
    prior_dim_ = d - 3;
    landmarks_[prior_landmarks_[q]].prior_index = -1;
    prior_landmarks_.erase(static_cast<std::size_t>(q));
    for (int k = q; k < static_cast<int>(prior_landmarks_.size()); ++k) {
      landmarks_[prior_landmarks_[k]].prior_index = k;
      prior_landmark_lin_[k] = prior_landmark_lin_[k + 1];
      first_estimate_[k] = first_estimate_[k + 1];
    }
    return ok;
  }

  Model model_{};
  SwfOptions options_{};
  int window_ = K;
  bool configured_ = false;

  PoseSlot poses_[kMaxPoses];
  int head_ = 0;
  int num_poses_ = 0;
  std::int64_t frames_added_ = 0;

  LandmarkSlot landmarks_[N];
  core::StaticVector<int, N> free_slots_;
  IdMap ids_;
  int num_landmarks_ = 0;

  // Prior (full symmetric, column-major, leading dimension kMaxPriorDim) over
  // [oldest pose | prior landmarks], its right-hand side and linearization point.
  S prior_[kMaxPriorDim * kMaxPriorDim] = {};
  S prior_g_[kMaxPriorDim] = {};
  S prior_delta_[kMaxPriorDim] = {};
  S prior_grad_[kMaxPriorDim] = {};
  int prior_dim_ = kStateDim;
  PoseType prior_pose_lin_{};
  StateMat prior_pose_jacobian_ = StateMat::Identity();
  mutable StateMat scratch_jacobian_ = StateMat::Identity();
  core::StaticVector<int, P> prior_landmarks_;
  Vec3<S> prior_landmark_lin_[P];
  Vec3<S> first_estimate_[P];  // where each prior landmark's Jacobians are evaluated

  // Workspaces.
  DenseCholesky<S, kMaxDense> dense_;
  S rhs_[kMaxDense] = {};
  S local_[kMaxLocalDim * kMaxLocalDim] = {};
  S local_b_[kMaxLocalDim] = {};
  static constexpr int kXRows = 3 * P + kStateDim;  // rows of x_: the local system less one pose
  S x_[kXRows * kStateDim] = {};
  S norms_[kMaxObservations] = {};
  int lm_begin_[N + 1] = {};
  AdjEntry adj_[kMaxObservations] = {};
  PoseType pose_backup_[kMaxPoses];
  S pose_cov_[kMaxPosesDim * kMaxPosesDim] = {};
  S column_[kMaxDense] = {};
  S factor_columns_[3][kMaxDense] = {};  // three columns of L^-1 (ComputeCovariances)
  StateMat newest_state_cov_ = StateMat::Zero();
  Mat6<S> newest_pose_cov_ = Mat6<S>::Zero();  // its pose part

  S tau_ = S(1e30);
  S residual_scale_ = S(1);  // median-based scale of the last weighting, uncapped
  std::uint32_t fault_bits_ = 0;
  SwfSummary summary_{};
  SwfSummary pending_{};  // gate counts of the frame being added, moved to summary_ by Update
  S gate_threshold_ = S(0);
  S motion_gate_threshold_ = S(0);
  bool has_motion_fallback_ = false;
  MotionType motion_fallback_{};
  StateMat motion_fallback_sqrt_info_ = StateMat::Zero();
  bool covariances_current_ = false;  // ComputeCovariances() ran since the last Update()
  bool predicted_cov_valid_ = false;  // predicted_pose_cov_ holds the newest pose's prediction
  StateMat predicted_pose_cov_ = StateMat::Zero();
  StateMat prediction_transition_ = StateMat::Zero();  // Phi: d_newest = Phi d_prev + noise
  PoseType newest_prediction_{};
  core::StaticVector<RetiredLandmark<S>, N> retired_;
};

}  // namespace swf::estimator
