// ImuPreintegration: the inertial input u_j+1 of the process model x_j+1 = f(x_j, u_j+1) + w
// (paper section 2, eq. 1), built from the IMU samples between two camera frames. Integrating
// in the frame of the first pose, not the world, makes the increments independent of the state
// (attitude, velocity, position), so the filter can relinearize the states without integrating
// again; only the biases enter, and they enter to first order through the Jacobians kept here.
//
// Frames and units. The IMU (body) frame b; samples are the gyroscope's angular rate w~ (rad/s)
// and the accelerometer's specific force a~ = R^T (a_world - g_world) (m/s^2), both in b. Biases
// b_g, b_a are additive: w = w~ - b_g, a = a~ - b_a. Poses are world_T_imu (geometry.hpp Pose).
//
// Increments over samples k = i .. j-1, each held over its step dt_k (see SampleHold), with
// E = Exp(w_k dt_k) the step's rotation and M = dR_k Exp(w_k dt_k / 2) the rotation at its middle:
//     dR_k+1 = dR_k E
//     dv_k+1 = dv_k + M a_k dt_k
//     dp_k+1 = dp_k + dv_k dt_k + 1/2 M a_k dt_k^2
// starting from (I, 0, 0). Taking the specific force at the middle of the step's rotation (not
// at its start, as the textbook discretization does) makes velocity and position second order
// in the step, like the rotation; with a first-order rotation there the midpoint hold below
// gains nothing for them (measured: their error then halves with the step, not quarters). The
// increments relate the states at the two frames by
//     R_j = R_i dR
//     v_j = v_i + g dT + R_i dv
//     p_j = p_i + v_i dT + 1/2 g dT^2 + R_i dp                          (dT = sum dt_k)
// which is f(x_i, u) for u = (dR, dv, dp, dT) (Predict below).
//
// Error state e = [dphi; dv; dp] (9), with the measured increment = true (*) error:
//     dR~ = dR Exp(dphi),  dv~ = dv + dv_err,  dp~ = dp + dp_err.
// Expanding Exp(x) ~ I + [x]x in the recursions: a gyro error n_g held over the step moves the
// end rotation by E^T dphi_k + Jr(w dt) dt n_g and the middle one (which the velocity sees) by
//     dtheta = E_h^T dphi_k + Jr(w dt / 2) dt/2 n_g          (E_h = Exp(w dt / 2))
// (Jr: right Jacobian of SO(3)), so with Ma = M [a]x dt one step is e_k+1 = A e_k + B_g n_g +
// B_a n_a:
//     A = [ E^T                  0      0 ]   B_g = [ Jr(w dt) dt                  ]
//         [ -Ma E_h^T            I      0 ]         [ -Ma Jr(w dt/2) dt/2          ]
//         [ -1/2 dt Ma E_h^T     I dt   I ]         [ -1/2 dt Ma Jr(w dt/2) dt/2   ]
//     B_a = [ 0 ; M dt ; 1/2 M dt^2 ]
// and the covariance propagates as Sigma <- A Sigma A^T + (N_g^2 / dt) B_g B_g^T +
// (N_a^2 / dt) B_a B_a^T (the discrete variance of a density N held over dt is N^2 / dt).
// A bias change db acts like a constant noise of -db, so the same expansion gives the Jacobians
// of the increments with respect to the biases (first-order bias correction, Corrected()):
//     G      = E_h^T J^R_g - Jr(w dt/2) dt/2                   (the middle rotation's)
//     J^R_g <- E^T J^R_g - Jr(w dt) dt
//     J^v_g <- J^v_g - Ma G                       J^v_a <- J^v_a - M dt
//     J^p_g <- J^p_g + J^v_g dt - 1/2 dt Ma G     J^p_a <- J^p_a + J^v_a dt - 1/2 M dt^2
// (right-hand sides at step k). Bias drift between frames (random walk) is not part of this
// covariance: it belongs to the bias states' own process noise (BiasRandomWalkCovariance).
//
// Re-integration. The increments are exactly linear in the accelerometer bias (it never enters
// the rotation), so Corrected() is exact for it; the gyroscope bias enters through the rotation,
// and the correction leaves out terms of order (|dbg| dT)^2. The steps of an interval are kept
// (up to kMaxKeptSteps), so when the estimate has moved far from the linearization biases the
// interval is integrated again at the new ones (Reintegrate) instead of being carried further by
// the correction.
//
// Time shift. Should the IMU's clock be off the cameras' by tau (the samples of an instant t
// stamped t + tau), the interval the states need is the integrated one moved by tau at both ends.
// With w_a, a_a and w_b, a_b the bias-corrected rate and force at its start and end, the
// increments move (to first order in tau; the rotation in the tangent of dR, right) by
//     dphi: w_b - dR^T w_a     dv: dR a_b - a_a - w_a x dv     dp: dv - dT a_a - w_a x dp
// (the end adds its own step, the start takes its step away and turns the frame the increments
// are expressed in by w_a tau; dp also loses the start's force over the whole interval). Zero
// for a constant rate and force: only a changing motion shows a time offset (TimeShiftJacobian).
//
// Flight code: fixed size, no allocation, no exceptions; every call bounded by its sample count.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"

namespace swf::estimator {

template <typename S>
using Mat9 = Eigen::Matrix<S, 9, 9>;
template <typename S>
using Mat93 = Eigen::Matrix<S, 9, 3>;
template <typename S>
using Vec9 = Eigen::Matrix<S, 9, 1>;

// Right Jacobian of SO(3): Exp(a + d) ~= Exp(a) Exp(Jr(a) d) for small d. Inverse of
// geometry.hpp's RightJacobianInverseSO3.
template <typename S>
Mat3<S> RightJacobianSO3(const Vec3<S>& phi) {
  const S theta2 = phi.squaredNorm();
  const Mat3<S> k = Skew(phi);
  if (theta2 < S(1e-10)) return Mat3<S>::Identity() - S(0.5) * k + k * k / S(6);
  const S theta = std::sqrt(theta2);
  const S a = (S(1) - std::cos(theta)) / theta2;
  const S b = (theta - std::sin(theta)) / (theta2 * theta);
  return Mat3<S>::Identity() - a * k + b * k * k;
}

// Bits of ImuSample::flags; the same values as imu_t.FLAG_* (messages/imu_t.lcm).
enum ImuFlag : std::uint32_t {
  kImuValid = 1u << 0,           // the sensor reported a good sample
  kImuGyroSaturated = 1u << 1,   // an axis of the gyroscope reached its range (value clipped)
  kImuAccelSaturated = 1u << 2,  // an axis of the accelerometer reached its range
};

// One IMU sample in the IMU frame; t_us on the camera exposure clock.
template <typename S>
struct ImuSample {
  std::int64_t t_us = 0;
  std::int64_t seq = 0;
  Vec3<S> gyro_radps = Vec3<S>::Zero();
  Vec3<S> accel_mps2 = Vec3<S>::Zero();
  std::uint32_t flags = kImuValid;
};

// Continuous-time noise of the sensor (the Allan-deviation figures of a datasheet or a
// calibration such as EuRoC's sensor.yaml).
template <typename S>
struct ImuNoise {
  S gyro_noise_density = S(0);   // rad/s/sqrt(Hz)    (angle random walk)
  S accel_noise_density = S(0);  // m/s^2/sqrt(Hz)    (velocity random walk)
  S gyro_random_walk = S(0);     // rad/s^2/sqrt(Hz)  (gyroscope bias diffusion)
  S accel_random_walk = S(0);    // m/s^3/sqrt(Hz)    (accelerometer bias diffusion)

  bool Valid() const {
    return gyro_noise_density >= S(0) && accel_noise_density >= S(0) && gyro_random_walk >= S(0) &&
           accel_random_walk >= S(0) && std::isfinite(gyro_noise_density) &&
           std::isfinite(accel_noise_density) && std::isfinite(gyro_random_walk) &&
           std::isfinite(accel_random_walk);
  }
};

template <typename S>
struct ImuBiases {
  Vec3<S> gyro_radps = Vec3<S>::Zero();
  Vec3<S> accel_mps2 = Vec3<S>::Zero();
};

// Attitude, position and velocity of the IMU in the world frame.
template <typename S>
struct InertialState {
  Pose<S> world_T_imu;
  Vec3<S> velocity_world_mps = Vec3<S>::Zero();
};

// Covariance (6x6, [gyro bias; accel bias]) the bias random walk adds over dt_s; the process
// noise of the filter's bias states between two frames.
template <typename S>
Mat6<S> BiasRandomWalkCovariance(const ImuNoise<S>& noise, S dt_s) {
  Mat6<S> q = Mat6<S>::Zero();
  q.template topLeftCorner<3, 3>().diagonal().setConstant(noise.gyro_random_walk *
                                                          noise.gyro_random_walk * dt_s);
  q.template bottomRightCorner<3, 3>().diagonal().setConstant(noise.accel_random_walk *
                                                              noise.accel_random_walk * dt_s);
  return q;
}

template <typename S>
class ImuPreintegration {
 public:
  // Offsets of the blocks of the 9-dimensional error state.
  static constexpr int kRotation = 0;
  static constexpr int kVelocity = 3;
  static constexpr int kPosition = 6;
  // Steps kept for Reintegrate: a frame interval at up to 2.5 kHz / 10 Hz (400 Hz: 0.64 s). A
  // longer one (a camera outage coasted on the IMU) is carried by the first-order correction.
  static constexpr int kMaxKeptSteps = 256;

  // Increments corrected to other biases (first order in the bias change).
  struct Deltas {
    Mat3<S> rotation = Mat3<S>::Identity();
    Vec3<S> velocity_mps = Vec3<S>::Zero();
    Vec3<S> position_m = Vec3<S>::Zero();
  };

  // Starts an empty interval integrated with `noise` at the bias linearization point `biases`.
  // kInvalidArgument (and the previous state kept) for negative or non-finite noise or biases.
  core::Status Reset(const ImuNoise<S>& noise, const ImuBiases<S>& biases) {
    if (!noise.Valid() || !biases.gyro_radps.allFinite() || !biases.accel_mps2.allFinite())
      return core::Status::kInvalidArgument;
    noise_ = noise;
    Restart(biases);
    num_steps_ = 0;
    return core::Status::kOk;
  }

  // Adds one step: the raw (biased) rate and specific force held over dt_s seconds.
  // kInvalidArgument, and nothing integrated, for a non-positive or non-finite dt or a
  // non-finite sample.
  core::Status Integrate(const Vec3<S>& gyro_radps, const Vec3<S>& accel_mps2, S dt_s) {
    if (!(dt_s > S(0)) || !std::isfinite(dt_s) || !gyro_radps.allFinite() ||
        !accel_mps2.allFinite())
      return core::Status::kInvalidArgument;
    if (num_steps_ < kMaxKeptSteps) kept_[num_steps_] = KeptStep{gyro_radps, accel_mps2, dt_s};
    if (num_steps_ == 0) first_ = KeptStep{gyro_radps, accel_mps2, dt_s};
    last_ = KeptStep{gyro_radps, accel_mps2, dt_s};
    Advance(gyro_radps, accel_mps2, dt_s);
    ++num_steps_;
    return core::Status::kOk;
  }

  // Whether Reintegrate can replay the whole interval (its steps were all kept).
  bool Replayable() const { return num_steps_ <= kMaxKeptSteps; }

  // The same interval integrated again from its kept steps at new linearization biases
  // (bounded by kMaxKeptSteps). kFull, and nothing changed, when the interval was longer than
  // the steps kept; kInvalidArgument for non-finite biases.
  core::Status Reintegrate(const ImuBiases<S>& biases) {
    if (!Replayable()) return core::Status::kFull;
    if (!biases.gyro_radps.allFinite() || !biases.accel_mps2.allFinite())
      return core::Status::kInvalidArgument;
    Restart(biases);
    for (int k = 0; k < num_steps_; ++k) Advance(kept_[k].gyro, kept_[k].accel, kept_[k].dt);
    return core::Status::kOk;
  }

  // The increments at the linearization biases.
  const Deltas& Increments() const { return delta_; }
  // The increments for `biases`, by the first-order correction (exact at the linearization
  // point; Reintegrate when the change grows large enough to matter).
  Deltas Corrected(const ImuBiases<S>& biases) const {
    const Vec3<S> dbg = biases.gyro_radps - biases_.gyro_radps;
    const Vec3<S> dba = biases.accel_mps2 - biases_.accel_mps2;
    Deltas d;
    d.rotation = delta_.rotation * ExpSO3<S>(Vec3<S>(d_rotation_d_gyro_bias_ * dbg));
    d.velocity_mps =
        delta_.velocity_mps + d_velocity_d_gyro_bias_ * dbg + d_velocity_d_accel_bias_ * dba;
    d.position_m =
        delta_.position_m + d_position_d_gyro_bias_ * dbg + d_position_d_accel_bias_ * dba;
    return d;
  }

  // f(x_i, u): the state at the end of the interval from the state at its start, with the
  // increments corrected to `biases` and gravity g_world (m/s^2, e.g. (0, 0, -9.81)).
  InertialState<S> Predict(const InertialState<S>& start, const ImuBiases<S>& biases,
                           const Vec3<S>& gravity_world_mps2) const {
    const Deltas d = Corrected(biases);
    const Mat3<S>& r_i = start.world_T_imu.R;
    const Vec3<S>& v_i = start.velocity_world_mps;
    InertialState<S> end;
    end.world_T_imu.R = r_i * d.rotation;
    end.velocity_world_mps = v_i + gravity_world_mps2 * dt_s_ + r_i * d.velocity_mps;
    end.world_T_imu.t = start.world_T_imu.t + v_i * dt_s_ +
                        S(0.5) * dt_s_ * dt_s_ * gravity_world_mps2 + r_i * d.position_m;
    return end;
  }

  // d [dphi; dv; dp] / d tau for the interval moved later by tau at both ends, at the
  // linearization biases (file comment, "Time shift"); zero for an empty interval.
  Vec9<S> TimeShiftJacobian() const {
    Vec9<S> j = Vec9<S>::Zero();
    if (num_steps_ == 0) return j;
    const Vec3<S> w_a = first_.gyro - biases_.gyro_radps;
    const Vec3<S> a_a = first_.accel - biases_.accel_mps2;
    const Vec3<S> w_b = last_.gyro - biases_.gyro_radps;
    const Vec3<S> a_b = last_.accel - biases_.accel_mps2;
    j.template segment<3>(kRotation) = w_b - delta_.rotation.transpose() * w_a;
    j.template segment<3>(kVelocity) = delta_.rotation * a_b - a_a - w_a.cross(delta_.velocity_mps);
    j.template segment<3>(kPosition) =
        delta_.velocity_mps - dt_s_ * a_a - w_a.cross(delta_.position_m);
    return j;
  }

  // Covariance of [dphi; dv; dp] from the white sensor noise (see the file comment).
  const Mat9<S>& Covariance() const { return covariance_; }
  // d increment / d bias at the linearization biases (rotation: in the tangent of dR, right).
  const Mat3<S>& DRotationDGyroBias() const { return d_rotation_d_gyro_bias_; }
  const Mat3<S>& DVelocityDGyroBias() const { return d_velocity_d_gyro_bias_; }
  const Mat3<S>& DVelocityDAccelBias() const { return d_velocity_d_accel_bias_; }
  const Mat3<S>& DPositionDGyroBias() const { return d_position_d_gyro_bias_; }
  const Mat3<S>& DPositionDAccelBias() const { return d_position_d_accel_bias_; }

  const ImuBiases<S>& LinearizationBiases() const { return biases_; }
  const ImuNoise<S>& Noise() const { return noise_; }
  S DurationS() const { return dt_s_; }
  int NumSteps() const { return num_steps_; }

 private:
  // One step's factors, shared by the covariance and the bias Jacobians (file comment).
  struct Step {
    S dt;
    Mat3<S> rotation;         // E = Exp(w dt)
    Mat3<S> jr_dt;            // Jr(w dt) dt
    Mat3<S> half_rotation_t;  // E_h^T
    Mat3<S> half_jr_dt;       // Jr(w dt / 2) dt / 2
    Mat3<S> mid_dt;           // M dt
    Mat3<S> mid_a_skew_dt;    // M [a]x dt
  };

  // One step at the current linearization biases (file comment); the caller checked it.
  void Advance(const Vec3<S>& gyro_radps, const Vec3<S>& accel_mps2, S dt_s) {
    const Vec3<S> a = accel_mps2 - biases_.accel_mps2;
    const Vec3<S> phi = (gyro_radps - biases_.gyro_radps) * dt_s;
    Step step;
    step.dt = dt_s;
    step.rotation = ExpSO3<S>(phi);
    step.jr_dt = RightJacobianSO3<S>(phi) * dt_s;
    const Vec3<S> half_phi = S(0.5) * phi;
    step.half_rotation_t = ExpSO3<S>(half_phi).transpose();
    step.half_jr_dt = RightJacobianSO3<S>(half_phi) * (S(0.5) * dt_s);
    step.mid_dt = delta_.rotation * step.half_rotation_t.transpose() * dt_s;
    step.mid_a_skew_dt = step.mid_dt * Skew(a);

    PropagateCovariance(step);
    PropagateBiasJacobians(step);

    const Vec3<S> dv_step = step.mid_dt * a;
    delta_.position_m += dt_s * delta_.velocity_mps + S(0.5) * dt_s * dv_step;
    delta_.velocity_mps += dv_step;
    delta_.rotation = delta_.rotation * step.rotation;
    dt_s_ += dt_s;
  }

  // Empty increments, covariance and Jacobians at `biases` (the kept steps stay).
  void Restart(const ImuBiases<S>& biases) {
    biases_ = biases;
    delta_ = Deltas{};
    dt_s_ = S(0);
    covariance_.setZero();
    d_rotation_d_gyro_bias_.setZero();
    d_velocity_d_gyro_bias_.setZero();
    d_velocity_d_accel_bias_.setZero();
    d_position_d_gyro_bias_.setZero();
    d_position_d_accel_bias_.setZero();
  }

  void PropagateCovariance(const Step& step) {
    const S dt = step.dt;
    Mat9<S> a = Mat9<S>::Identity();
    a.template block<3, 3>(kRotation, kRotation) = step.rotation.transpose();
    const Mat3<S> v_phi = -step.mid_a_skew_dt * step.half_rotation_t;
    a.template block<3, 3>(kVelocity, kRotation) = v_phi;
    a.template block<3, 3>(kPosition, kRotation) = S(0.5) * dt * v_phi;
    a.template block<3, 3>(kPosition, kVelocity) = Mat3<S>::Identity() * dt;
    Mat93<S> b_gyro;
    b_gyro.template block<3, 3>(kRotation, 0) = step.jr_dt;
    const Mat3<S> v_gyro = -step.mid_a_skew_dt * step.half_jr_dt;
    b_gyro.template block<3, 3>(kVelocity, 0) = v_gyro;
    b_gyro.template block<3, 3>(kPosition, 0) = S(0.5) * dt * v_gyro;
    Mat93<S> b_accel;
    b_accel.template block<3, 3>(kRotation, 0).setZero();
    b_accel.template block<3, 3>(kVelocity, 0) = step.mid_dt;
    b_accel.template block<3, 3>(kPosition, 0) = S(0.5) * dt * step.mid_dt;
    // Discrete variance N^2 / dt of a density N held over dt.
    const S var_gyro = noise_.gyro_noise_density * noise_.gyro_noise_density / dt;
    const S var_accel = noise_.accel_noise_density * noise_.accel_noise_density / dt;
    const Mat9<S> propagated = a * covariance_ * a.transpose();
    covariance_ = propagated + var_gyro * (b_gyro * b_gyro.transpose()) +
                  var_accel * (b_accel * b_accel.transpose());
  }

  // Before the increments move: every right-hand side is at step k.
  void PropagateBiasJacobians(const Step& step) {
    const S dt = step.dt;
    const Mat3<S> mid_rotation_d_gyro_bias =
        step.half_rotation_t * d_rotation_d_gyro_bias_ - step.half_jr_dt;
    const Mat3<S> dv_gyro = -step.mid_a_skew_dt * mid_rotation_d_gyro_bias;
    d_position_d_gyro_bias_ += dt * d_velocity_d_gyro_bias_ + S(0.5) * dt * dv_gyro;
    d_position_d_accel_bias_ += dt * d_velocity_d_accel_bias_ - S(0.5) * dt * step.mid_dt;
    d_velocity_d_gyro_bias_ += dv_gyro;
    d_velocity_d_accel_bias_ -= step.mid_dt;
    d_rotation_d_gyro_bias_ = step.rotation.transpose() * d_rotation_d_gyro_bias_ - step.jr_dt;
  }

  struct KeptStep {
    Vec3<S> gyro;
    Vec3<S> accel;
    S dt;
  };

  ImuNoise<S> noise_;
  ImuBiases<S> biases_;
  Deltas delta_;
  S dt_s_ = S(0);
  int num_steps_ = 0;
  Mat9<S> covariance_ = Mat9<S>::Zero();
  Mat3<S> d_rotation_d_gyro_bias_ = Mat3<S>::Zero();
  Mat3<S> d_velocity_d_gyro_bias_ = Mat3<S>::Zero();
  Mat3<S> d_velocity_d_accel_bias_ = Mat3<S>::Zero();
  Mat3<S> d_position_d_gyro_bias_ = Mat3<S>::Zero();
  Mat3<S> d_position_d_accel_bias_ = Mat3<S>::Zero();
  std::array<KeptStep, kMaxKeptSteps> kept_{};
  KeptStep first_{};  // the interval's first and last steps, for TimeShiftJacobian
  KeptStep last_{};
};

// How a sample stands for the signal between its time and the next sample's.
enum class SampleHold : std::uint8_t {
  kZeroOrder,  // sample k over [t_k, t_k+1): first order in the step (the textbook form)
  kMidpoint,   // the line through samples k and k+1 taken at the middle of each step: second
               // order for a smooth signal sampled at instants (the simulator, EuRoC)
};

struct IntervalSummary {
  int samples_used = 0;
  // Steps held longer than max_step_s (a gap the stream checker let through) and the sample
  // before the interval that had to be stretched backwards because none was at or before it.
  int bridged_steps = 0;
  double longest_step_s = 0.0;
};

// Integrates the signal over [t_begin_us, t_end_us] from `samples` (strictly increasing times,
// as ImuStreamChecker passes them; count <= the caller's buffer), appending to `pim`.
// The sample at or before an instant covers it; before the first sample the first one is held
// (counted as bridged). Samples after t_end_us are ignored. Returns kInvalidArgument for an
// empty interval or unsorted samples, kEmpty when no sample is given.
template <typename S>
core::Status PreintegrateInterval(const ImuSample<S>* samples, int count, std::int64_t t_begin_us,
                                  std::int64_t t_end_us, SampleHold hold, S max_step_s,
                                  ImuPreintegration<S>* pim, IntervalSummary* summary) {
  *summary = IntervalSummary{};
  if (count <= 0) return core::Status::kEmpty;
  if (!(t_end_us > t_begin_us)) return core::Status::kInvalidArgument;
  for (int k = 1; k < count; ++k)
    if (!(samples[k].t_us > samples[k - 1].t_us)) return core::Status::kInvalidArgument;
  // The last sample at or before t_begin (or the first one, held backwards).
  int k = 0;
  while (k + 1 < count && samples[k + 1].t_us <= t_begin_us) ++k;
  std::int64_t t = t_begin_us;
  if (samples[k].t_us > t_begin_us) ++summary->bridged_steps;
  while (t < t_end_us) {
    const bool has_next = k + 1 < count;
    const std::int64_t t_next = has_next ? std::min(samples[k + 1].t_us, t_end_us) : t_end_us;
    const S dt_s = S(t_next - t) * S(1e-6);
    Vec3<S> gyro = samples[k].gyro_radps;
    Vec3<S> accel = samples[k].accel_mps2;
    if (hold == SampleHold::kMidpoint && has_next) {
      // The straight line between the two samples at the middle of the piece (the mean of the
      // two for a whole step; partial steps at the interval's ends take their own part).
      const S span = S(samples[k + 1].t_us - samples[k].t_us);
      const S mid = S(0.5) * S((t - samples[k].t_us) + (t_next - samples[k].t_us));
      const S w = std::clamp(mid / span, S(0), S(1));
      gyro += w * (samples[k + 1].gyro_radps - gyro);
      accel += w * (samples[k + 1].accel_mps2 - accel);
    }
    const core::Status s = pim->Integrate(gyro, accel, dt_s);
    if (s != core::Status::kOk) return s;
    ++summary->samples_used;
    if (dt_s > max_step_s) ++summary->bridged_steps;
    summary->longest_step_s = std::max(summary->longest_step_s, double(dt_s));
    t = t_next;
    if (has_next && samples[k + 1].t_us <= t) ++k;
  }
  return core::Status::kOk;
}

}  // namespace swf::estimator
