// IntegrityMonitor: decides, every frame, whether the Sliding Window Filter's navigation output
// can be trusted, and by how much. A flight estimator's first duty is to know when it is wrong:
// the filter's covariance describes its error only while its models hold (Gaussian inlier
// measurements, a process model that covers the motion, observable geometry). The monitor
// checks the evidence that those models hold and grades the output:
//   VALID     every check passed; the protection levels bound the position error with the
//             stated probability
//   DEGRADED  usable, but a check failed (few tracks, residuals larger than modelled, weak
//             geometry, no motion input, recovering from a restart): treat the protection
//             levels as indicative
//   INVALID   do not use: the solve failed, the state is implausible, the evidence says it
//             diverged, or too few measurements constrain it
// and recommends a restart when the evidence says the filter diverged.
//
// Protection levels (horizontal, vertical) from the newest pose's position covariance P, scaled
// by s = pl_inflation * max(1, inlier_sigma) (when the measurements scatter more than R says, the
// covariance is too small by that factor):
//   VPL = k_v s sqrt(u^T P u),     k_v = Phi^-1(1 - alpha/2)             (u = world up)
//   HPL = k_h s sqrt(lambda_max(P_h)), k_h = sqrt(-2 ln alpha)           (P_h: horizontal 2x2)
// HPL uses the major axis for both horizontal directions (a circular bound of the larger
// sigma), so P(|e_h| > HPL) <= alpha for a Gaussian error; alpha = integrity_risk.
//
// Flight code: no allocation, no exceptions, bounded work, deterministic.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "swf/core/status.hpp"
#include "swf/estimator/chi_square.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/estimator/small_factorizations.hpp"

namespace swf::estimator {

enum class NavIntegrity : std::uint8_t { kValid = 0, kDegraded = 1, kInvalid = 2 };

// One bit per check (values shared with nav_state_t.INTEGRITY_*); each is counted per frame.
enum IntegrityFlag : std::uint32_t {
  kFlagSolverFailed = 1u << 0,           // the update failed or the filter reset (INVALID)
  kFlagImplausibleState = 1u << 1,       // non-finite, or speed beyond the envelope (INVALID)
  kFlagDiverged = 1u << 2,               // residuals and step say the estimate left the data
  kFlagTooFewTracks = 1u << 3,           // inliers below min_valid_tracks (INVALID)
  kFlagFewTracks = 1u << 4,              // inliers below min_good_tracks
  kFlagResidualsHigh = 1u << 5,          // inlier sigma above max_inlier_sigma, or few inliers
  kFlagResidualJump = 1u << 6,           // inlier sigma rose by more than residual_jump_ratio
  kFlagLargeStep = 1u << 7,              // the solve moved the newest pose far from its prediction
  kFlagCovarianceBad = 1u << 8,          // covariance not finite / not positive (INVALID)
  kFlagCovarianceLarge = 1u << 9,        // position sigma above max_position_sigma_m
  kFlagDegenerateGeometry = 1u << 10,    // measurements bunched in a small image region / a line
  kFlagNoParallax = 1u << 11,            // median disparity too small to fix depth
  kFlagGateSuspended = 1u << 12,         // a gate stood down (prediction and data disagree)
  kFlagNoMotionInput = 1u << 13,         // constant-velocity (or still) prediction
  kFlagRecovering = 1u << 14,            // within recovery_frames of a restart or an anomaly
  kFlagMeasurementsRejected = 1u << 15,  // the gates removed a large share of the frame
  kFlagTrackLoss = 1u << 16,             // most of the last frame's tracks were lost at once
  kFlagMotionDisagrees = 1u << 17,       // the estimate left the motion input's dead reckoning
  kFlagCameraOutage = 1u << 18,          // no stereo pair this cycle: coasting on the motion input
  kFlagMotionRejected = 1u << 19,        // the motion input failed its gate and was not fused
};
inline constexpr int kNumIntegrityFlags = 20;

struct IntegrityOptions {
  double integrity_risk = 1e-3;  // alpha: probability the error exceeds a protection level
  double pl_inflation = 1.0;     // extra factor on the covariance sigma (measured consistency)
  // Bias bound added to both protection levels, per metre flown since the last absolute
  // reference (the start): the drift of visual odometry that no covariance shows (calibration,
  // rectification and model errors are biases, not noise). Stereo odometry drifts about 1 % of
  // the distance on real imagery; the filter's covariance alone claimed a third of the KITTI
  // drift (VALID frames beyond their protection levels). GNSS integrity adds such bounds the
  // same way.
  double drift_per_distance = 0.01;
  Vec3<double> up_world{0.0, 0.0, 1.0};  // the world's vertical (unit)
  int min_valid_tracks = 8;              // fewer inlier tracked measurements in the frame: INVALID
  int min_good_tracks = 25;              // fewer: DEGRADED
  double max_rejected_fraction = 0.1;    // of the frame's measurements removed by the gates
  double max_track_loss = 0.5;           // fraction of the last frame's tracks lost at once
  double max_rotation_sigma_rad = 0.1;
  // Squared Mahalanobis distance between the estimate and the motion input's dead reckoning
  // from the last (re)start, beyond which they disagree (chi-square, 3 dof, p = 0.999).
  double max_motion_disagreement = 16.27;
  double max_inlier_sigma = 3.0;  // robust residual scale in nominal sigmas
  double min_inlier_fraction = 0.5;
  double residual_jump_ratio = 4.0;
  double max_step_m = 5.0;    // newest pose step from its prediction (m) ...
  double max_step_rad = 0.2;  // ... and rad, beyond which the step is suspect
  double max_speed_mps = 300.0;
  double max_position_sigma_m = 100.0;
  double min_image_spread_px = 20.0;  // smallest principal std of the measured pixels
  double min_median_disparity_px = 1.0;
  int divergence_frames = 2;  // consecutive frames of high residuals that mean divergence
  int recovery_frames = 5;    // frames after a restart before VALID again

  core::Status Validate() const {
    const bool ok = integrity_risk > 0.0 && integrity_risk < 0.5 && pl_inflation >= 1.0 &&
                    std::abs(up_world.norm() - 1.0) < 1e-6 && min_valid_tracks >= 0 &&
                    drift_per_distance >= 0.0 && drift_per_distance < 1.0 &&
                    min_good_tracks >= min_valid_tracks && max_inlier_sigma >= 1.0 &&
                    min_inlier_fraction >= 0.0 && min_inlier_fraction <= 1.0 &&
                    residual_jump_ratio > 1.0 && max_step_m > 0.0 && max_step_rad > 0.0 &&
                    max_speed_mps > 0.0 && max_position_sigma_m > 0.0 &&
                    min_image_spread_px >= 0.0 && min_median_disparity_px >= 0.0 &&
                    divergence_frames >= 1 && recovery_frames >= 0 && max_rejected_fraction > 0.0 &&
                    max_track_loss > 0.0 && max_track_loss <= 1.0 && max_rotation_sigma_rad > 0.0 &&
                    max_motion_disagreement > 0.0;
    return ok ? core::Status::kOk : core::Status::kInvalidArgument;
  }
};

// What the monitor looks at for one frame (filled from the filter's SwfSummary, its newest pose
// covariance and the front end's measurements).
struct IntegrityEvidence {
  core::Status update_status = core::Status::kOk;
  bool filter_reset = false;  // the filter lost its state this frame
  bool gate_suspended = false;
  bool has_motion_input = false;
  bool motion_rejected = false;  // the motion input failed its gate (before or after the solve)
  int num_measurements = 0;
  int num_inliers = 0;
  // The newest frame (track checks): inliers among its measurements of landmarks seen before
  // (on the very first frame, all of its measurements), and how many the gates removed.
  int tracked_inliers = 0;
  int tracked_measurements = 0;
  int rejected_measurements = 0;
  // Squared Mahalanobis distance of the position from the motion input's dead reckoning
  // (negative: no dead reckoning, e.g. no motion input).
  double motion_disagreement = -1.0;
  double inlier_sigma = 1.0;
  double step_m = 0.0;  // SwfSummary::newest_pose_step_m
  double step_rad = 0.0;
  Vec3<double> position_world = Vec3<double>::Zero();
  Vec3<double> velocity_world = Vec3<double>::Zero();
  bool has_covariance = false;
  Mat6<double> covariance = Mat6<double>::Zero();  // [rho (world, m); phi], as the filter's
  double image_spread_px = 0.0;  // smallest principal std of the newest frame's pixels
  double distance_m = 0.0;       // flown since the last absolute reference (drift bound)
  double median_disparity_px = 0.0;
};

struct IntegrityReport {
  NavIntegrity status = NavIntegrity::kInvalid;
  std::uint32_t flags = 0;
  double hpl_m = 0.0;  // finite; 0 when there is no covariance (status INVALID)
  double vpl_m = 0.0;
  bool restart = false;  // the evidence says the filter diverged: restart from a trusted state
};

class IntegrityMonitor {
 public:
  core::Status Configure(const IntegrityOptions& options) {
    const core::Status s = options.Validate();
    if (s != core::Status::kOk) return s;
    options_ = options;
    k_vertical_ = NormalUpperQuantile(0.5 * options.integrity_risk);
    k_horizontal_ = std::sqrt(-2.0 * std::log(options.integrity_risk));
    Reset();
    return core::Status::kOk;
  }

  void Reset() {
    high_residual_run_ = 0;
    previous_tracked_ = -1;
    frames_since_anomaly_ = options_.recovery_frames + 1;
    previous_sigma_ = 0.0;
    frames_since_restart_ = options_.recovery_frames;  // no restart yet
    for (std::int64_t& c : flag_counts_) c = 0;
    for (std::int64_t& c : status_counts_) c = 0;
    restarts_ = 0;
  }

  // The filter was restarted (from a trusted state or from scratch).
  void NoteRestart() {
    frames_since_restart_ = 0;
    previous_tracked_ = -1;
    high_residual_run_ = 0;
    previous_sigma_ = 0.0;
    ++restarts_;
  }

  IntegrityReport Assess(const IntegrityEvidence& e) {
    IntegrityReport r;
    r.flags = CheckSolve(e) | CheckTracks(e) | CheckResiduals(e) | CheckGeometry(e);
    r.flags |= ProtectionLevels(e, &r.hpl_m, &r.vpl_m);
    if (e.motion_disagreement > options_.max_motion_disagreement) r.flags |= kFlagMotionDisagrees;
    if (e.motion_rejected) r.flags |= kFlagMotionRejected;
    if (e.gate_suspended) r.flags |= kFlagGateSuspended;
    r.restart = (r.flags & (kFlagDiverged | kFlagImplausibleState)) != 0;
    constexpr std::uint32_t kInvalidating = kFlagSolverFailed | kFlagImplausibleState |
                                            kFlagDiverged | kFlagTooFewTracks | kFlagCovarianceBad;
    Finish(e, kInvalidating, &r);
    return r;
  }

  // A cycle without images (camera outage): the state was carried by the process model alone.
  // Only its plausibility and covariance are checked; it is at best DEGRADED, and INVALID once
  // its covariance leaves the envelope. The tracks of before the outage are not compared with
  // the first frame after it.
  IntegrityReport AssessCoast(const IntegrityEvidence& e) {
    IntegrityReport r;
    r.flags = kFlagCameraOutage | ProtectionLevels(e, &r.hpl_m, &r.vpl_m);
    if (!e.position_world.allFinite() || !e.velocity_world.allFinite() ||
        e.velocity_world.norm() > options_.max_speed_mps) {
      r.flags |= kFlagImplausibleState;
    }
    if (e.motion_rejected) r.flags |= kFlagMotionRejected;
    previous_tracked_ = -1;
    high_residual_run_ = 0;
    previous_sigma_ = 0.0;
    constexpr std::uint32_t kInvalidating =
        kFlagImplausibleState | kFlagCovarianceBad | kFlagCovarianceLarge;
    Finish(e, kInvalidating, &r);
    return r;
  }

  std::int64_t FlagCount(int bit) const { return flag_counts_[bit]; }
  std::int64_t StatusCount(NavIntegrity s) const { return status_counts_[static_cast<int>(s)]; }
  std::int64_t Restarts() const { return restarts_; }
  const IntegrityOptions& Options() const { return options_; }

 private:
  // Recovery, status and counts, common to every frame.
  void Finish(const IntegrityEvidence& e, std::uint32_t invalidating, IntegrityReport* r) {
    // An anomaly (the state or the data in doubt) keeps the output DEGRADED until
    // recovery_frames clean frames have followed it.
    constexpr std::uint32_t kAnomalies =
        kFlagResidualsHigh | kFlagResidualJump | kFlagLargeStep | kFlagMeasurementsRejected |
        kFlagTrackLoss | kFlagTooFewTracks | kFlagSolverFailed | kFlagMotionDisagrees |
        kFlagMotionRejected | kFlagCameraOutage;
    frames_since_anomaly_ = (r->flags & kAnomalies) != 0 ? 0 : frames_since_anomaly_ + 1;
    if (frames_since_restart_ < options_.recovery_frames ||
        (frames_since_anomaly_ > 0 && frames_since_anomaly_ <= options_.recovery_frames)) {
      r->flags |= kFlagRecovering;
    }
    if (!e.has_motion_input) r->flags |= kFlagNoMotionInput;
    // Flying on the process model alone is reported, not degrading: the covariance models it.
    constexpr std::uint32_t kInformational = kFlagNoMotionInput;
    r->status = (r->flags & invalidating) != 0      ? NavIntegrity::kInvalid
                : (r->flags & ~kInformational) != 0 ? NavIntegrity::kDegraded
                                                    : NavIntegrity::kValid;
    if (r->status == NavIntegrity::kInvalid) {
      r->hpl_m = 0.0;
      r->vpl_m = 0.0;
    }
    ++frames_since_restart_;
    for (int b = 0; b < kNumIntegrityFlags; ++b) flag_counts_[b] += (r->flags >> b) & 1u;
    ++status_counts_[static_cast<int>(r->status)];
  }

  std::uint32_t CheckSolve(const IntegrityEvidence& e) const {
    std::uint32_t f = 0;
    const bool solved =
        e.update_status == core::Status::kOk || e.update_status == core::Status::kNotConverged;
    if (!solved || e.filter_reset) f |= kFlagSolverFailed;
    if (!e.position_world.allFinite() || !e.velocity_world.allFinite() ||
        e.velocity_world.norm() > options_.max_speed_mps) {
      f |= kFlagImplausibleState;
    }
    if (e.step_m > options_.max_step_m || e.step_rad > options_.max_step_rad) f |= kFlagLargeStep;
    return f;
  }

  // What the newest frame itself tracked: enough inliers, not a sudden loss of most tracks,
  // not a large share removed by the gates.
  std::uint32_t CheckTracks(const IntegrityEvidence& e) {
    std::uint32_t f = 0;
    if (e.tracked_inliers < options_.min_valid_tracks) {
      f |= kFlagTooFewTracks | kFlagFewTracks;
    } else if (e.tracked_inliers < options_.min_good_tracks) {
      f |= kFlagFewTracks;
    }
    const int offered = e.tracked_measurements + e.rejected_measurements;
    if (offered > 0 && e.rejected_measurements > options_.max_rejected_fraction * offered)
      f |= kFlagMeasurementsRejected;
    if (previous_tracked_ > 0 &&
        e.tracked_measurements < (1.0 - options_.max_track_loss) * previous_tracked_) {
      f |= kFlagTrackLoss;
    }
    previous_tracked_ = e.tracked_measurements;
    return f;
  }

  // Residuals against their chi-square expectation (the robust scale is ~1 nominal sigma when
  // R is right), their jump from the last frame, and the divergence rule: high residuals for
  // divergence_frames frames running, or high residuals together with a large step.
  std::uint32_t CheckResiduals(const IntegrityEvidence& e) {
    std::uint32_t f = 0;
    const double inlier_fraction =
        e.num_measurements > 0 ? static_cast<double>(e.num_inliers) / e.num_measurements : 0.0;
    const bool high = !(e.inlier_sigma <= options_.max_inlier_sigma) ||
                      (e.num_measurements > 0 && inlier_fraction < options_.min_inlier_fraction);
    if (high) f |= kFlagResidualsHigh;
    if (previous_sigma_ > 0.0 && e.inlier_sigma > options_.residual_jump_ratio * previous_sigma_)
      f |= kFlagResidualJump;
    previous_sigma_ = e.inlier_sigma;
    high_residual_run_ = high ? high_residual_run_ + 1 : 0;
    const bool large_step = e.step_m > options_.max_step_m || e.step_rad > options_.max_step_rad;
    if (high_residual_run_ >= options_.divergence_frames || (high && large_step))
      f |= kFlagDiverged;
    return f;
  }

  std::uint32_t CheckGeometry(const IntegrityEvidence& e) const {
    std::uint32_t f = 0;
    if (e.num_measurements > 0 && e.image_spread_px < options_.min_image_spread_px)
      f |= kFlagDegenerateGeometry;
    if (e.num_measurements > 0 && e.median_disparity_px < options_.min_median_disparity_px)
      f |= kFlagNoParallax;
    return f;
  }

  std::uint32_t ProtectionLevels(const IntegrityEvidence& e, double* hpl, double* vpl) const {
    *hpl = 0.0;
    *vpl = 0.0;
    if (!e.has_covariance) return kFlagCovarianceBad;
    const Mat3<double> p = e.covariance.topLeftCorner<3, 3>();
    const Vec3<double>& up = options_.up_world;
    // Horizontal basis: any two unit vectors orthogonal to up.
    const Vec3<double> seed =
        std::abs(up.x()) < 0.9 ? Vec3<double>::UnitX() : Vec3<double>::UnitY();
    const Vec3<double> h1 = (seed - up * up.dot(seed)).normalized();
    const Vec3<double> h2 = up.cross(h1);
    Eigen::Matrix<double, 3, 2> h;
    h << h1, h2;
    const Eigen::Matrix2d ph = h.transpose() * p * h;
    const double pv = up.dot(p * up);
    const Vec2<double> eigenvalues = SymmetricEigenvalues(ph);
    const double major = eigenvalues(1);
    const double minor = eigenvalues(0);
    if (!p.allFinite() || !(pv >= 0.0) || !(minor >= 0.0) || !std::isfinite(major))
      return kFlagCovarianceBad;
    const double scale = options_.pl_inflation * std::max(1.0, e.inlier_sigma);
    const double drift_m = options_.drift_per_distance * std::max(0.0, e.distance_m);
    *hpl = k_horizontal_ * scale * std::sqrt(major) + drift_m;
    *vpl = k_vertical_ * scale * std::sqrt(pv) + drift_m;
    if (!std::isfinite(*hpl) || !std::isfinite(*vpl)) {
      *hpl = 0.0;
      *vpl = 0.0;
      return kFlagCovarianceBad;
    }
    const double sigma = std::sqrt(std::max(major, pv));
    const double rotation_sigma =
        std::sqrt(std::max(0.0, e.covariance.bottomRightCorner<3, 3>().diagonal().maxCoeff()));
    const bool large = sigma > options_.max_position_sigma_m ||
                       !(rotation_sigma <= options_.max_rotation_sigma_rad);
    return large ? kFlagCovarianceLarge : 0u;
  }

  IntegrityOptions options_{};
  double k_vertical_ = 0.0;
  double k_horizontal_ = 0.0;
  int high_residual_run_ = 0;
  int previous_tracked_ = -1;
  int frames_since_anomaly_ = 0;
  double previous_sigma_ = 0.0;
  int frames_since_restart_ = 0;
  std::int64_t flag_counts_[kNumIntegrityFlags] = {};
  std::int64_t status_counts_[3] = {};
  std::int64_t restarts_ = 0;
};

}  // namespace swf::estimator
