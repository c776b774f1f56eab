// InertialStereoModel: the stereo measurement model of stereo_model.hpp on an IMU-carried state,
// with the preintegrated IMU (imu_preintegration.hpp) as the process model's input: the paper's
// x_j+1 = f(x_j, u_j+1) + w with u = the IMU samples between frames j and j+1.
//
// State of a frame (NavState, 15 update coordinates, the pose first as the filter requires):
//     [rho; phi]  the IMU pose world_T_imu: t += rho (world), R = R Exp(phi)
//     dv          velocity of the IMU in the world frame (m/s):  v += dv
//     dbg, dba    gyroscope (rad/s) and accelerometer (m/s^2) biases:  b += db
// Landmarks are world points (StereoModel's parameterization).
//
// Measurement. The camera is rigidly mounted: world_T_camera = world_T_imu * imu_T_camera, with
// imu_T_camera = (R_ic, t_ic). Moving the IMU pose by (rho, phi) moves the camera by
//     rho_c = rho - R [t_ic]x phi,     phi_c = R_ic^T phi
// (R Exp(phi) R_ic = R R_ic Exp(R_ic^T phi); R Exp(phi) t_ic ~ R t_ic - R [t_ic]x phi), so the
// measurement Jacobian is StereoModel's camera-pose Jacobian times [I, -R [t_ic]x; 0, R_ic^T].
//
// Process. With the increments (dR, dv, dp) over dT corrected to the biases of state i
// (ImuPreintegration::Corrected: dR_c = dR Exp(J_Rg dbg), dv_c = dv + J_vg dbg + J_va dba, ...,
// dbg = bg_i - the integration's linearization biases) and gravity g, the residual (15, in the
// order of the update: position, rotation, velocity, gyro bias, accel bias) is
//     e_p  = R_i^T (p_j - p_i - v_i dT - 1/2 g dT^2) - dp_c
//     e_R  = Log(dR_c^T R_i^T R_j)
//     e_v  = R_i^T (v_j - v_i - g dT) - dv_c
//     e_bg = bg_j - bg_i,    e_ba = ba_j - ba_i
// Its covariance: the preintegration's (re-ordered to this order; an error of the measured
// increments enters the residual with a minus sign, which leaves it unchanged) and the bias
// random walk over dT (BiasRandomWalkCovariance). Jacobians, with a_v = R_i^T (v_j - v_i - g dT),
// a_p = R_i^T (p_j - p_i - v_i dT - 1/2 g dT^2) and Jr^-1 = RightJacobianInverseSO3(e_R):
//     de_p/drho_i = -R_i^T   de_p/dphi_i = [a_p]x   de_p/dv_i = -R_i^T dT
//     de_p/dbg_i = -J_pg     de_p/dba_i = -J_pa     de_p/drho_j = R_i^T
//     de_R/dphi_i = -Jr^-1 R_j^T R_i                de_R/dphi_j = Jr^-1
//     de_R/dbg_i = -Jr^-1 Exp(e_R)^T Jr(J_Rg dbg) J_Rg
//     de_v/dphi_i = [a_v]x   de_v/dv_i = -R_i^T     de_v/dv_j = R_i^T
//     de_v/dbg_i = -J_vg     de_v/dba_i = -J_va
//     de_b/db_i = -I         de_b/db_j = I          (each bias)
// (R_i -> R_i Exp(phi) turns R_i^T x into (I - [phi]x) R_i^T x = R_i^T x + [R_i^T x]x phi; the
// rotation rows follow as in stereo_model.hpp; the bias row from Exp(a + d) ~ Exp(a) Exp(Jr(a) d).)
// The biases are taken as constant over an interval; the first-order correction is good while
// the bias estimate stays near the integration's linearization biases, which the caller sets
// to the current estimate when it integrates each interval. When the gyroscope bias estimate of
// the interval's first state moves further, by more than reintegrate_above_rad of rotation over
// the interval (|dbg| dT; the correction leaves out terms of its square), the filter has the
// interval integrated again at the new estimate, and its process covariance with it
// (RefreshMotion, before each solve).
#pragma once

#include "swf/estimator/geometry.hpp"
#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/small_factorizations.hpp"
#include "swf/estimator/stereo_model.hpp"

namespace swf::estimator {

template <typename S>
using Mat15 = Eigen::Matrix<S, 15, 15>;
template <typename S>
using Vec15 = Eigen::Matrix<S, 15, 1>;

// Per-frame state of the stereo-inertial filter.
template <typename S>
struct NavState {
  Pose<S> world_T_imu;
  Vec3<S> velocity_world_mps = Vec3<S>::Zero();
  ImuBiases<S> biases;
};

template <typename S>
struct InertialStereoModel {
  using Scalar = S;
  using PoseType = NavState<S>;
  using MotionType = ImuPreintegration<S>;
  using LandmarkAnchor = typename StereoModel<S>::LandmarkAnchor;
  static constexpr int kStateDim = 15;
  // Offsets in the update vector (and in the process residual).
  static constexpr int kPosition = 0;
  static constexpr int kRotation = 3;
  static constexpr int kVelocity = 6;
  static constexpr int kGyroBias = 9;
  static constexpr int kAccelBias = 12;

  StereoModel<S> stereo;  // camera, depth limits
  Pose<S> imu_T_camera;   // the left camera in the IMU frame
  Vec3<S> gravity_world_mps2 = Vec3<S>(S(0), S(0), S(-9.81));
  // Prior sigmas of the first state beyond its pose (SwfOptions gives the pose's), used when
  // the filter starts without AddFirstPose's full covariance.
  S first_velocity_sigma_mps = S(1);
  S first_gyro_bias_sigma_radps = S(0.01);
  S first_accel_bias_sigma_mps2 = S(0.1);
  // Re-integration threshold (file comment): 1 mrad, where the left-out term is 0.5 urad, below
  // a tactical gyroscope's white noise over a 10 Hz frame interval (about 10 urad).
  S reintegrate_above_rad = S(1e-3);

  Pose<S> CameraPose(const PoseType& x) const { return x.world_T_imu * imu_T_camera; }

  // Covariance of the camera pose's [rho_c; phi_c] from the IMU pose's [rho; phi] (the map of
  // the file comment's measurement paragraph), for navigation outputs in the camera frame.
  Mat6<S> CameraPoseCovariance(const PoseType& x, const Mat6<S>& imu_pose_covariance) const {
    Mat6<S> j = Mat6<S>::Zero();
    j.template topLeftCorner<3, 3>().setIdentity();
    j.template topRightCorner<3, 3>() = -x.world_T_imu.R * Skew(imu_T_camera.t);
    j.template bottomRightCorner<3, 3>() = imu_T_camera.R.transpose();
    return j * imu_pose_covariance * j.transpose();
  }

  // x_j = f(x_i, u) and its covariance with nothing but the IMU: the process residual
  // e = J_i dx_i + J_j dx_j + w (w ~ ProcessCovariance(u)) held at zero gives
  // dx_j = -J_j^-1 (J_i dx_i + w), so P_j = J_j^-1 (J_i P_i J_i^T + Q) J_j^-T. For coasting
  // through a camera outage and restarting from a trusted state. False if not finite.
  bool PropagateWithCovariance(const PoseType& x, const Mat15<S>& covariance, const MotionType& u,
                               PoseType* next, Mat15<S>* next_covariance) const {
    *next = Propagate(x, u);
    Mat15<S> j_prev;
    Mat15<S> j_next;
    (void)ProcessResidual(x, *next, u, &j_prev, &j_next);
    const Mat15<S> a = PartialPivSolve(j_next, j_prev);
    const Mat15<S> b = PartialPivSolve<S, 15>(j_next, Mat15<S>::Identity());
    *next_covariance = a * covariance * a.transpose() + b * ProcessCovariance(u) * b.transpose();
    *next_covariance = S(0.5) * (*next_covariance + next_covariance->transpose());
    return next_covariance->allFinite() && next->world_T_imu.t.allFinite() &&
           next->velocity_world_mps.allFinite();
  }

  // The filter's measurement surface (see the file comment for the Jacobian).
  bool InitLandmark(const PoseType& x, const Vec3<S>& z, LandmarkAnchor* anchor,
                    Vec3<S>* params) const {
    return stereo.InitLandmark(CameraPose(x), z, anchor, params);
  }
  bool Predict(const PoseType& x, const LandmarkAnchor& anchor, const Vec3<S>& params, Vec3<S>* z,
               Mat36<S>* j_pose, Mat3<S>* j_landmark) const {
    if (!stereo.Predict(CameraPose(x), anchor, params, z, j_pose, j_landmark)) return false;
    if (j_pose != nullptr) {
      const Mat36<S> j_camera = *j_pose;
      j_pose->template leftCols<3>() = j_camera.template leftCols<3>();
      j_pose->template rightCols<3>() =
          -j_camera.template leftCols<3>() * x.world_T_imu.R * Skew(imu_T_camera.t) +
          j_camera.template rightCols<3>() * imu_T_camera.R.transpose();
    }
    return true;
  }
  static bool LandmarkPosition(const LandmarkAnchor& anchor, const Vec3<S>& params,
                               Vec3<S>* position, Mat3<S>* jacobian) {
    return StereoModel<S>::LandmarkPosition(anchor, params, position, jacobian);
  }

  Eigen::Matrix<S, 9, 1> FirstStateSigmas() const {
    Eigen::Matrix<S, 9, 1> sigma;
    sigma << Vec3<S>::Constant(first_velocity_sigma_mps),
        Vec3<S>::Constant(first_gyro_bias_sigma_radps),
        Vec3<S>::Constant(first_accel_bias_sigma_mps2);
    return sigma;
  }

  // f(x_i, u): the preintegrated motion from x_i with x_i's biases; the biases carry over.
  PoseType Propagate(const PoseType& x, const MotionType& u) const {
    InertialState<S> start;
    start.world_T_imu = x.world_T_imu;
    start.velocity_world_mps = x.velocity_world_mps;
    const InertialState<S> end = u.Predict(start, x.biases, gravity_world_mps2);
    PoseType next;
    next.world_T_imu = end.world_T_imu;
    next.velocity_world_mps = end.velocity_world_mps;
    next.biases = x.biases;
    return next;
  }

  // The interval u integrated again at prev's biases when their gyroscope part has moved from
  // u's linearization biases by more than reintegrate_above_rad over the interval, and the
  // process factor's square-root information recomputed from the new integration's covariance
  // (the noise propagates through the bias-corrected rotation, so it moves with the biases);
  // true when it was. An interval longer than its kept steps stays as it is; so does the
  // information should the new covariance not be positive definite (it was at the first
  // integration, and the same steps at other biases keep it so). Bounded by the kept steps and
  // one 15x15 factorization; allocates nothing.
  bool RefreshMotion(const PoseType& prev, MotionType* u, Mat15<S>* sqrt_information) const {
    const S turn =
        (prev.biases.gyro_radps - u->LinearizationBiases().gyro_radps).norm() * u->DurationS();
    if (!(turn > reintegrate_above_rad) || !u->Replayable()) return false;
    if (u->Reintegrate(prev.biases) != core::Status::kOk) return false;
    Mat15<S> w;
    if (ProcessSqrtInformation(*u, &w)) *sqrt_information = w;
    return true;
  }

  Vec15<S> ProcessResidual(const PoseType& prev, const PoseType& next, const MotionType& u,
                           Mat15<S>* j_prev, Mat15<S>* j_next) const {
    const typename MotionType::Deltas d = u.Corrected(prev.biases);
    const S dt = u.DurationS();
    const Mat3<S>& r_i = prev.world_T_imu.R;
    const Mat3<S> rt = r_i.transpose();
    const Vec3<S> a_v =
        rt * (next.velocity_world_mps - prev.velocity_world_mps - gravity_world_mps2 * dt);
    const Vec3<S> a_p = rt * (next.world_T_imu.t - prev.world_T_imu.t -
                              prev.velocity_world_mps * dt - S(0.5) * dt * dt * gravity_world_mps2);
    const Vec3<S> e_rot = LogSO3<S>(Mat3<S>(d.rotation.transpose() * rt * next.world_T_imu.R));
    Vec15<S> e;
    e.template segment<3>(kPosition) = a_p - d.position_m;
    e.template segment<3>(kRotation) = e_rot;
    e.template segment<3>(kVelocity) = a_v - d.velocity_mps;
    e.template segment<3>(kGyroBias) = next.biases.gyro_radps - prev.biases.gyro_radps;
    e.template segment<3>(kAccelBias) = next.biases.accel_mps2 - prev.biases.accel_mps2;

    const Mat3<S> jr_inv = RightJacobianInverseSO3<S>(e_rot);
    const Vec3<S> dbg = prev.biases.gyro_radps - u.LinearizationBiases().gyro_radps;
    const Mat3<S> d_rot_d_bg = -jr_inv * ExpSO3<S>(e_rot).transpose() *
                               RightJacobianSO3<S>(Vec3<S>(u.DRotationDGyroBias() * dbg)) *
                               u.DRotationDGyroBias();
    const Mat3<S> identity = Mat3<S>::Identity();
    j_prev->setZero();
    j_next->setZero();
    auto prev_block = [&](int row, int col) { return j_prev->template block<3, 3>(row, col); };
    auto next_block = [&](int row, int col) { return j_next->template block<3, 3>(row, col); };
    prev_block(kPosition, kPosition) = -rt;
    prev_block(kPosition, kRotation) = Skew(a_p);
    prev_block(kPosition, kVelocity) = -rt * dt;
    prev_block(kPosition, kGyroBias) = -u.DPositionDGyroBias();
    prev_block(kPosition, kAccelBias) = -u.DPositionDAccelBias();
    prev_block(kRotation, kRotation) = -jr_inv * next.world_T_imu.R.transpose() * r_i;
    prev_block(kRotation, kGyroBias) = d_rot_d_bg;
    prev_block(kVelocity, kRotation) = Skew(a_v);
    prev_block(kVelocity, kVelocity) = -rt;
    prev_block(kVelocity, kGyroBias) = -u.DVelocityDGyroBias();
    prev_block(kVelocity, kAccelBias) = -u.DVelocityDAccelBias();
    prev_block(kGyroBias, kGyroBias) = -identity;
    prev_block(kAccelBias, kAccelBias) = -identity;
    next_block(kPosition, kPosition) = rt;
    next_block(kRotation, kRotation) = jr_inv;
    next_block(kVelocity, kVelocity) = rt;
    next_block(kGyroBias, kGyroBias) = identity;
    next_block(kAccelBias, kAccelBias) = identity;
    return e;
  }

  // d e / d tau: the process residual's change should u's interval move later by tau on the
  // IMU's clock (ImuPreintegration::TimeShiftJacobian, the increments' change, enters e_p and
  // e_v with a minus sign and e_R as the bias correction's rotation does; the biases' rows are
  // zero). What a camera-IMU time offset does to the process factor (TimeOffsetEstimator).
  Vec15<S> ProcessTimeShiftJacobian(const PoseType& prev, const PoseType& next,
                                    const MotionType& u) const {
    const typename MotionType::Deltas d = u.Corrected(prev.biases);
    const Vec3<S> e_rot = LogSO3<S>(
        Mat3<S>(d.rotation.transpose() * prev.world_T_imu.R.transpose() * next.world_T_imu.R));
    const Vec9<S> shift = u.TimeShiftJacobian();
    Vec15<S> j = Vec15<S>::Zero();
    j.template segment<3>(kPosition) = -shift.template segment<3>(MotionType::kPosition);
    j.template segment<3>(kRotation) = -RightJacobianInverseSO3<S>(e_rot) *
                                       ExpSO3<S>(e_rot).transpose() *
                                       shift.template segment<3>(MotionType::kRotation);
    j.template segment<3>(kVelocity) = -shift.template segment<3>(MotionType::kVelocity);
    return j;
  }

  // Covariance of the process residual for the interval u (file comment).
  static Mat15<S> ProcessCovariance(const MotionType& u) {
    using Pim = ImuPreintegration<S>;
    // Residual block of each increment block of the preintegration's [dphi; dv; dp].
    const int block_of[3] = {kRotation, kVelocity, kPosition};
    const int pim_of[3] = {Pim::kRotation, Pim::kVelocity, Pim::kPosition};
    Mat15<S> q = Mat15<S>::Zero();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        q.template block<3, 3>(block_of[a], block_of[b]) =
            u.Covariance().template block<3, 3>(pim_of[a], pim_of[b]);
    q.template bottomRightCorner<6, 6>() = BiasRandomWalkCovariance(u.Noise(), u.DurationS());
    return q;
  }

  // W with W^T W = ProcessCovariance(u)^-1 (the filter's process_sqrt_information); false when
  // the covariance is not positive definite (an IMU without noise or random walk, an empty
  // interval).
  static bool ProcessSqrtInformation(const MotionType& u, Mat15<S>* sqrt_information) {
    if (!InverseCholeskyFactor<S, 15>(ProcessCovariance(u), sqrt_information)) return false;
    return sqrt_information->allFinite();
  }

  static PoseType Retract(const PoseType& x, const Vec15<S>& delta) {
    PoseType out;
    out.world_T_imu = x.world_T_imu.Retract(delta.template head<6>());
    out.velocity_world_mps = x.velocity_world_mps + delta.template segment<3>(kVelocity);
    out.biases.gyro_radps = x.biases.gyro_radps + delta.template segment<3>(kGyroBias);
    out.biases.accel_mps2 = x.biases.accel_mps2 + delta.template segment<3>(kAccelBias);
    return out;
  }

  // Delta = x "minus" base in the update's coordinates, and dDelta/d delta_x.
  static Vec15<S> Difference(const PoseType& base, const PoseType& x, Mat15<S>* jacobian) {
    Vec15<S> d;
    d.template head<6>() = base.world_T_imu.LocalDifference(x.world_T_imu);
    d.template segment<3>(kVelocity) = x.velocity_world_mps - base.velocity_world_mps;
    d.template segment<3>(kGyroBias) = x.biases.gyro_radps - base.biases.gyro_radps;
    d.template segment<3>(kAccelBias) = x.biases.accel_mps2 - base.biases.accel_mps2;
    jacobian->setIdentity();
    jacobian->template block<3, 3>(kRotation, kRotation) =
        RightJacobianInverseSO3<S>(Vec3<S>(d.template segment<3>(kRotation)));
    return d;
  }
};

// Static alignment: an IMU at rest reads its gyroscope bias as the mean rate, and minus gravity
// as the mean specific force (f = R^T (a - g) with a = 0). Given the attitude guidance hands
// over (world_R_imu), the mean force rotated into the world must point along -g: the smallest
// rotation doing so (about a horizontal axis, so the guidance's heading is kept: a tactical or
// MEMS gyroscope cannot find north from the Earth's or a planet's rotation) levels it. Refused
// (false) when the samples do not look static: fewer than min_samples, a rate or force spread
// (standard deviation per axis) above the bounds, or a mean force whose norm is more than
// max_gravity_error from |g|. The biases' and attitude's uncertainty stay the caller's to state.
template <typename S>
struct StaticAlignmentOptions {
  int min_samples = 50;
  S max_rate_std_radps = S(0.01);
  S max_force_std_mps2 = S(0.2);
  S max_gravity_error_mps2 = S(0.3);
};

template <typename S>
struct StaticAlignment {
  Mat3<S> world_R_imu = Mat3<S>::Identity();
  Vec3<S> gyro_bias_radps = Vec3<S>::Zero();
  S tilt_correction_rad = S(0);  // angle of the levelling rotation applied to the guidance
  S duration_s = S(0);
};

template <typename S>
bool AlignStatic(const ImuSample<S>* samples, int count, const Mat3<S>& guess_world_R_imu,
                 const Vec3<S>& gravity_world_mps2, const StaticAlignmentOptions<S>& options,
                 StaticAlignment<S>* out) {
  if (count < options.min_samples || count < 2) return false;
  Vec3<S> rate_sum = Vec3<S>::Zero();
  Vec3<S> force_sum = Vec3<S>::Zero();
  Vec3<S> rate_sq = Vec3<S>::Zero();
  Vec3<S> force_sq = Vec3<S>::Zero();
  for (int k = 0; k < count; ++k) {
    rate_sum += samples[k].gyro_radps;
    force_sum += samples[k].accel_mps2;
    rate_sq += samples[k].gyro_radps.cwiseAbs2();
    force_sq += samples[k].accel_mps2.cwiseAbs2();
  }
  const S n = S(count);
  const Vec3<S> rate = rate_sum / n;
  const Vec3<S> force = force_sum / n;
  const Vec3<S> rate_var = (rate_sq / n - rate.cwiseAbs2()).cwiseMax(S(0));
  const Vec3<S> force_var = (force_sq / n - force.cwiseAbs2()).cwiseMax(S(0));
  const S g = gravity_world_mps2.norm();
  if (!rate.allFinite() || !force.allFinite() || !(g > S(0)) ||
      rate_var.cwiseSqrt().maxCoeff() > options.max_rate_std_radps ||
      force_var.cwiseSqrt().maxCoeff() > options.max_force_std_mps2 ||
      std::abs(force.norm() - g) > options.max_gravity_error_mps2) {
    return false;
  }
  // Rotate the world force direction onto -g (the up direction) by the smallest rotation.
  const Vec3<S> measured_up = (guess_world_R_imu * force).normalized();
  const Vec3<S> up = -gravity_world_mps2 / g;
  const Vec3<S> axis = measured_up.cross(up);
  const S angle = std::atan2(axis.norm(), measured_up.dot(up));
  const Vec3<S> phi = axis.norm() > S(0) ? Vec3<S>(axis.normalized() * angle) : Vec3<S>::Zero();
  out->world_R_imu = ExpSO3<S>(phi) * guess_world_R_imu;
  out->gyro_bias_radps = rate;
  out->tilt_correction_rad = angle;
  out->duration_s = S(samples[count - 1].t_us - samples[0].t_us) * S(1e-6);
  return true;
}

}  // namespace swf::estimator
