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
//   * with SwfOptions::hold_sightings or hold_depth_precision (not in the paper) the oldest pose
//     is held back while it sees a tracked landmark not yet in the prior that is still young
//     (fewer sightings than that, or its depth known to worse than that relative precision), up
//     to the capacity K; then every pose held back is marginalized as above, oldest first.
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
//   kVsdf            marginalize with only the block diagonal of the Schur term (eq. 12);
//                    SwfOptions::vsdf_scalar_diagonal keeps only its scalar diagonal, the
//                    paper's literal wording
//
// Memory: K (window), N (active landmarks), M (measurements per pose) and P (landmarks the prior
// can hold) are template parameters; every buffer is a member, so the object is large: create it
// once at start-up (e.g. std::make_unique), never on the stack. No call allocates afterwards.
// Determinism: single-threaded, fixed iteration order, no clocks; same input -> same bits.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <bit>
#include <concepts>
#include <cstdint>

#include "swf/core/id_map.hpp"
#include "swf/core/static_vector.hpp"
#include "swf/core/status.hpp"
#include "swf/estimator/dense_cholesky.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/estimator/schur.hpp"
#include "swf/estimator/small_factorizations.hpp"

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
  // Hold the oldest pose in the window past window_size (up to the capacity K) while it sees a
  // landmark that is not in the prior yet, is still tracked by the newest frame and has fewer
  // than this many sightings; then marginalize it. A landmark's first estimate (above) is then
  // taken where its sightings have pinned its depth down, not where its first few frames left it
  // (at long range a few frames' depth is known to ~1 %, and that error put false information
  // along the weakly observable tilt/sideways direction into the prior: docs/integrity.md,
  // "Consistency on the descent from 100 m"). 0 = the paper's fixed window. Not in VO mode.
  int hold_sightings = 0;
  // The same hold, with "young" judged by the landmark's own depth precision instead of a count:
  // while the relative 1-sigma of its depth, from the disparities of its stereo sightings
  // (sigma_Z / Z = sigma_d / d per sighting, information added over the sightings), is above
  // this. Why a precision and not a count: the weakly observable tilt/sideways direction shows
  // in a ground point's image only through the fraction of the tilt its off-axis angle and the
  // relief leave, a few per cent over a 25 deg field (mean (r/f)^2 ~ 0.026 at 4:3); a first
  // estimate whose depth is off by dZ/Z changes that signal by dZ/Z of the tilt, so the prior is
  // linearized right along it only once dZ/Z is well below those few per cent. A few sightings
  // reach that at 30 m (77 px of disparity, 0.9 % each) but not at 100 m (23 px, 3.1 % each),
  // so the window is held only where the range needs it. 0 = off; both set: held while either
  // says young. Not in VO mode.
  double hold_depth_precision = 0.0;
  // kVsdf only: apply only the scalar diagonal of the Schur term (eq. 12 read literally,
  // "only the diagonal elements") instead of its 3x3 / state blocks within each variable.
  bool vsdf_scalar_diagonal = false;
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
    if (hold_sightings < 0 || hold_sightings > 1000) return core::Status::kInvalidArgument;
    if (!(hold_depth_precision >= 0.0 && hold_depth_precision < 1.0))
      return core::Status::kInvalidArgument;
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
  int measurements_gated = 0;     // ... that failed and were not fused (with the first
                                  // sighting they contradicted, for a landmark seen twice)
  int measurements_rejected = 0;  // removed after the solve
  int landmarks_rejected = 0;     // removed with all their measurements: after the solve, or
                                  // before it when its only two sightings disagree
  int new_landmarks_refused = 0;  // failed the depth, disparity or triangulation check
  bool gate_suspended = false;    // a gate stood down (kFaultGateSuspended)
  // The motion gate: the squared Mahalanobis distance between the motion prediction and the
  // images' fit of the newest pose, whether it failed, and whether the images overruled it.
  double motion_chi2 = 0.0;
  bool motion_gate_failed = false;
  bool motion_overruled = false;
  // Process inputs integrated again at their first state's new estimate (ReintegratingModel).
  int motions_reintegrated = 0;

  // The solve stopped for one of the three converged reasons.
  bool Converged() const {
    return termination == SwfTermination::kCostTolerance ||
           termination == SwfTermination::kStepTolerance ||
           termination == SwfTermination::kNoDescent;
  }
};

// A model whose process input is a relative motion between two poses (StereoModel; not the
// IMU's): it has a constant-velocity fallback.
template <typename Model>
concept RelativeMotionModel = requires(const Model& m, const typename Model::PoseType& p) {
  m.RelativeMotion(p, p);
};

// A model whose process input is integrated at a linearization point of the state it starts
// from (the IMU's biases) and can be integrated again at that state's current estimate, with
// the process factor's square-root information recomputed for it
// (InertialStereoModel::RefreshMotion; true when it did).
template <typename Model>
concept ReintegratingModel =
    requires(const Model& m, const typename Model::PoseType& p, typename Model::MotionType* u,
             Eigen::Matrix<typename Model::Scalar, Model::kStateDim, Model::kStateDim>* w) {
  { m.RefreshMotion(p, u, w) } -> std::same_as<bool>;
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

  // Takes the model and the options (validated; the window must fit the capacity K) and
  // resets. Call once at start-up, before any other call.
  core::Status Configure(const Model& model, const SwfOptions& options);

  // Forgets all state (keeps the configuration).
  void Reset();

  // ---- adding a frame: one AddPose* call, its AddObservation calls, then Update() -----------

  // Adds a pose with an initial estimate and no process factor (bundle-adjustment style).
  core::Status AddPose(const PoseType& estimate) { return PushPose(estimate, nullptr, nullptr); }

  // Adds the first pose with a Gaussian prior of this covariance (update coordinates) instead of
  // first_pose_sigma_*: a restart from the last trusted state keeps its uncertainty, so the
  // covariances (and protection levels) after it still cover the error made before it. A
  // fixed first pose (fix_first_pose, VO) stays fixed.
  core::Status AddFirstPose(const PoseType& estimate, const StateMat& covariance);

  // Adds a pose predicted by the process model from a relative-motion input u with
  // information W^T W = Q^-1 (process_sqrt_information = W). For a ReintegratingModel W is the
  // model's for u (InertialStereoModel::ProcessSqrtInformation): a re-integration recomputes it.
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
  // Only for models with a relative-motion input; on the IMU's model the call fails at its
  // constraint, not deep in this body.
  template <RelativeMotionModel CvModel = Model>
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
                              const Mat3<S>& sqrt_information);

  // Replaces the value of the newest pose's measurement of a landmark (same information), e.g.
  // by the front end's re-refinement after Update() (paper 4.1.2); the next Update() solves
  // with it. kEmpty when the newest pose holds no measurement of it (unknown id, or taken out
  // by a gate); kInvalidArgument for a non-finite z or the landmark's first sighting (its
  // measurement placed the landmark: a re-measurement would need a new initialization). O(M).
  core::Status ReplaceNewestObservation(std::int64_t landmark_id, const Vec3<S>& z);

  // Marginalizes (per mode) and runs robust Gauss-Newton over the window.
  core::Status Update();

  // Marginal covariances of every window pose block and active landmark (inverse of the full
  // information matrix, by the Schur complement). After Update(): at the linearization point of
  // its last Gauss-Newton iteration, from that iteration's factor (the final estimate is one
  // converged step further; as an iterated EKF reports it). When the window or its measurements
  // changed since, at the current estimate, factorized here. O(n^3) in the reduced dimension:
  // call it at the output rate, not inside the estimation loop.
  core::Status ComputeCovariances();

  // Only the newest state's covariance (NewestStateCovariance, NewestPoseCovariance) and its
  // correlation with the window: kStateDim columns of the inverse, O(n^2) each, from the factor
  // above (after Update() no factorization; else one at the current estimate, O(n^3 / 3)). The
  // other poses' blocks and every landmark's marginal stay invalid (the prediction gate then
  // skips, counted as unchecked) until ComputeCovariances(), which runs this first and gives the
  // same bits for these blocks.
  core::Status ComputeNewestCovariance();

  // ---- results -----------------------------------------------------------------------------
  int NumPoses() const { return num_poses_; }
  int WindowSize() const { return window_; }
  const PoseType& PoseAt(int j) const { return Slot(j).pose; }  // 0 = oldest
  const PoseType& NewestPose() const { return Slot(num_poses_ - 1).pose; }
  // The process factor into window state j (its input and square-root information, as the last
  // Update solved with them); false when state j has none (the oldest, a first pose).
  bool ProcessFactorInto(int j, const MotionType** u, const StateMat** sqrt_information) const {
    if (j < 1 || j >= num_poses_ || !Slot(j).has_process) return false;
    *u = &Slot(j).motion;
    *sqrt_information = &Slot(j).process_sqrt_info;
    return true;
  }
  // f(landmark id) for each measurement of the newest pose still in the window: after Update(),
  // the ones the prediction and residual gates let through (a display of what was fused).
  template <typename F>
  void ForEachNewestObservation(F&& f) const {
    if (num_poses_ == 0) return;
    for (const Observation& o : Slot(num_poses_ - 1).obs) f(landmarks_[o.landmark].id);
  }
  int NumLandmarks() const { return num_landmarks_; }
  int NumPriorLandmarks() const { return static_cast<int>(prior_landmarks_.size()); }

  // World position of an active landmark; false for an unknown id or a point the model cannot
  // place (an inverse-depth landmark at or beyond infinity).
  bool GetLandmark(std::int64_t id, Vec3<S>* position) const;
  // How many sightings an active landmark has had since it entered (0 for an unknown id).
  int LandmarkSightings(std::int64_t id) const {
    const int slot = ids_.Find(id);
    return slot < 0 ? 0 : landmarks_[slot].total_obs;
  }
  // World-frame covariance (the parameters' covariance mapped through dl/dm), after
  // ComputeCovariances().
  bool GetLandmarkCovariance(std::int64_t id, Mat3<S>* covariance) const;
  // Covariance of state j's whole update vector and of its pose part ([rho; phi]), after
  // ComputeCovariances() (the newest state's also after ComputeNewestCovariance()).
  StateMat StateCovariance(int j) const;
  Mat6<S> PoseCovariance(int j) const { return StateCovariance(j).template topLeftCorner<6, 6>(); }
  const Mat6<S>& NewestPoseCovariance() const { return newest_pose_cov_; }
  const StateMat& NewestStateCovariance() const { return newest_state_cov_; }

  // Calls f(id, world position, observations in window) for every active landmark the model
  // can place, in slot order.
  template <typename F>
  void ForEachLandmark(F&& f) const {
    Vec3<S> position;
    ForEachUsedSlot([&](int i) {
      const LandmarkSlot& l = landmarks_[i];
      if (Model::LandmarkPosition(l.anchor, l.params, &position, nullptr))
        f(l.id, position, l.obs_in_window);
    });
  }

  const core::StaticVector<RetiredLandmark<S>, N>& Retired() const { return retired_; }
  const SwfSummary& Summary() const { return summary_; }
  std::uint32_t FaultBits() const { return fault_bits_; }
  void ClearFaults() { fault_bits_ = 0; }
  const SwfOptions& Options() const { return options_; }

  // Total cost 0.5 * sum |W (z - h)|^2 of the measurements alone (no robust kernel, no prior,
  // no process model): the bundle-adjustment cost used to compare with other solvers.
  double MeasurementCost();

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
    std::int64_t last_frame = 0;  // frames_added_ when it was last measured
    // Sum over its sightings of (disparity / its sigma)^2: the inverse square of the relative
    // depth precision its stereo measurements give (SwfOptions::hold_depth_precision).
    S depth_information = S(0);
    // Per-iteration workspace; adj_[adj_begin, adj_end) are its measurements (BuildAndFactor).
    int lm_count = 0;
    int adj_begin = 0;
    int adj_end = 0;
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

  template <int R, int C>
  static auto Blk(S* a, int ld, int row, int col) {
    return DenseBlock<S, R, C>(a, ld, row, col);
  }
  PoseSlot& Slot(int j) { return poses_[(head_ + j) % kMaxPoses]; }
  const PoseSlot& Slot(int j) const { return poses_[(head_ + j) % kMaxPoses]; }
  PoseSlot& Newest() { return Slot(num_poses_ - 1); }
  // f(slot) for every used landmark slot, in slot order (the order the reduced system's sums are
  // formed in): O(N / 64 + used) instead of a pass over all N slots, each its own cache lines.
  template <typename F>
  void ForEachUsedSlot(F&& f) const {
    for (int w = 0; w < kSlotWords; ++w) {
      std::uint64_t bits = used_slots_[w];
      while (bits != 0) {
        const int b = std::countr_zero(bits);
        bits &= bits - 1;
        f(64 * w + b);
      }
    }
  }
  void SetUsed(int slot, bool used) {
    landmarks_[slot].used = used;
    const std::uint64_t bit = std::uint64_t{1} << (slot % 64);
    used_slots_[slot / 64] = used ? used_slots_[slot / 64] | bit : used_slots_[slot / 64] & ~bit;
  }
  Observation& ObsAt(const AdjEntry& e) { return Slot(e.pose).obs[e.obs]; }
  static bool IsSolved(core::Status s) {
    return s == core::Status::kOk || s == core::Status::kNotConverged;
  }
  S InlierSigma() const {
    return options_.robust && tau_ < S(1e29) ? tau_ / S(options_.huber_k) : S(1);
  }

  // The frame cycle (swf_frame_cycle.hpp).
  core::Status PushPose(const PoseType& estimate, const MotionType* u, const StateMat* sqrt_info);
  bool StateIsFinite() const;
  bool HoldEnabled() const;
  bool HoldsOldestPose() const;
  void RefreshMotions();
  bool IsYoung(const LandmarkSlot& l) const;
  static void AddDepthInformation(const Vec3<S>& z, const Mat3<S>& sqrt_information,
                                  LandmarkSlot* l);
  void RecordEvidence();
  void ZeroFixedPoseCovariance();

  // Integrity gates (swf_gates.hpp).
  struct MotionGateResult {
    double chi2 = 0.0;
    bool failed = false;
    bool overruled = false;
  };
  bool PredictPoseCovariance(const PoseType& prev, const PoseType& next, const MotionType& u,
                             const StateMat& sqrt_info, StateMat* covariance,
                             StateMat* transition) const;
  bool FailsPredictionGate(const PoseType& pose, const LandmarkSlot& l, const Vec3<S>& z,
                           const Mat3<S>& sqrt_info);
  bool TriangulationAcceptable(const PoseType& pose, const LandmarkAnchor& anchor,
                               const Vec3<S>& params, const Mat3<S>& sqrt_info) const;
  void ApplyPredictionGate();
  int RejectResidualOutliers();
  MotionGateResult GateNewestMotion();
  int FitNewestPose(PoseType* pose, Mat6<S>* information);
  Mat3<S> FitWhitening(const PoseType& prediction, const Observation& o,
                       const LandmarkSlot& l) const;

  // Robust Gauss-Newton (swf_gauss_newton.hpp).
  void EvaluateMeasurements(bool with_jacobians);
  void EvaluateObservation(const PoseType& pose, Observation* o, bool with_jacobians);
  StateVec WhitenedProcessFactor(int j, StateMat* a, StateMat* b) const;
  void UpdateRobustWeights();
  void ApplyWeights();
  S HuberCost(S squared_norm) const;
  S TotalCost();
  core::Status BuildAndFactor();
  core::Status Solve();
  void Backup();
  void Restore();
  void ApplyStep(S alpha);

  // The prior and marginalization (swf_prior.hpp).
  void InitializePrior();
  void ClearPosePrior();
  void PriorGradient();
  void PriorDelta();
  void AddPrior(int lm0);
  void MarginalizeOldestPose();
  void SelectPriorEntrants();
  void GrowPrior();
  bool EliminateFirstPose(int dim);
  bool NewPriorBlocksPositiveSemidefinite(int dim);
  void DeleteOldestPose();
  void RetireUnsupportedLandmarks();
  bool EliminatePriorLandmarks();
  void RemoveLandmark(int slot);

  Model model_{};
  SwfOptions options_{};
  int window_ = K;
  bool configured_ = false;

  PoseSlot poses_[kMaxPoses];
  int head_ = 0;
  int num_poses_ = 0;
  std::int64_t frames_added_ = 0;

  LandmarkSlot landmarks_[N];
  static constexpr int kSlotWords = (N + 63) / 64;
  std::uint64_t used_slots_[kSlotWords] = {};  // bit i: landmarks_[i].used
  core::StaticVector<int, N> free_slots_;
  core::IdMap<N> ids_;  // landmark id -> slot
  int num_landmarks_ = 0;

  // Prior (full symmetric, column-major, leading dimension kPriorLd) over
  // [oldest pose | prior landmarks], its right-hand side and linearization point. It lives at
  // row and column kStateDim of prior_storage_: the rows and columns before it are where
  // MarginalizeOldestPose puts the next pose, so that its local system is the prior itself.
  static constexpr int kPriorLd = kMaxLocalDim;
  S prior_storage_[kPriorLd * kPriorLd] = {};
  S* const prior_ = prior_storage_ + kStateDim * kPriorLd + kStateDim;
  S prior_g_[kMaxPriorDim] = {};
  S prior_delta_[kMaxPriorDim] = {};
  S prior_grad_[kMaxPriorDim] = {};
  int prior_dim_ = kStateDim;
  PoseType prior_pose_lin_{};
  StateMat prior_pose_jacobian_ = StateMat::Identity();
  mutable StateMat scratch_jacobian_ = StateMat::Identity();
  core::StaticVector<int, P> prior_landmarks_;
  core::StaticVector<int, M> prior_entrants_;  // MarginalizeOldestPose's workspace
  // EliminatePriorLandmarks' workspace: the prior indices leaving, and the prior's 3-wide chunks
  // they occupy.
  core::StaticVector<int, P> leaving_prior_;
  bool prior_chunk_dropped_[kMaxPriorDim / 3] = {};
  // Prior landmarks eliminated per pass over the prior (EliminateVariablesExact, schur.hpp).
  static constexpr int kEliminationBatch = 8;
  Vec3<S> prior_landmark_lin_[P];
  Vec3<S> first_estimate_[P];  // where each prior landmark's Jacobians are evaluated

  // Workspaces.
  DenseCholesky<S, kMaxDense> dense_;
  S rhs_[kMaxDense] = {};
  S local_b_[kMaxLocalDim] = {};
  bool local_chunk_dropped_[kMaxLocalDim / 3] = {};  // EliminateFirstPose's (none but p0's)
  // x_: Lambda_ro Lambda_oo^-1 of the pose or of a batch of prior landmarks (schur.hpp).
  static constexpr int kXRows = kMaxLocalDim;
  static constexpr int kXColumns = std::max(kStateDim, 3 * kEliminationBatch);
  S x_[kXRows * kXColumns] = {};
  S norms_[kMaxObservations] = {};
  AdjEntry adj_[kMaxObservations] = {};
  PoseType pose_backup_[kMaxPoses];
  S pose_cov_[kMaxPosesDim * kMaxPosesDim] = {};
  // Columns of S^-1 or L^-1 (ComputeCovariances): kCovarianceWidth per solve, 3 per prior
  // landmark for kCovarianceWidth landmarks per round.
  static constexpr int kCovarianceWidth = DenseCholesky<S, kMaxDense>::kBlock;
  S covariance_columns_[3 * kCovarianceWidth * kMaxDense] = {};
  // X = the first columns of L^-1 for the older states' covariance block (LeadingInverseBlock).
  alignas(64) S leading_inverse_workspace_[DenseCholesky<S, kMaxDense>::LeadingInverseWorkspace(
      kStateDim * K)] = {};
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
  // dense_ holds the factor of the reduced system of the current window and measurements: the
  // last Gauss-Newton iteration's, or ComputeNewestCovariance()'s when none was current.
  bool factor_current_ = false;
  bool predicted_cov_valid_ = false;  // predicted_pose_cov_ holds the newest pose's prediction
  StateMat predicted_pose_cov_ = StateMat::Zero();
  StateMat prediction_transition_ = StateMat::Zero();  // Phi: d_newest = Phi d_prev + noise
  PoseType newest_prediction_{};
  core::StaticVector<RetiredLandmark<S>, N> retired_;
};

}  // namespace swf::estimator

#include "swf/estimator/swf_frame_cycle.hpp"
#include "swf/estimator/swf_gates.hpp"
#include "swf/estimator/swf_gauss_newton.hpp"
#include "swf/estimator/swf_prior.hpp"
