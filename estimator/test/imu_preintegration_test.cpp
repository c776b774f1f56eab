// ImuPreintegration and ImuStreamChecker: the increments against a known smooth trajectory
// (convergence at the order each hold promises), the bias Jacobians against central
// differences of re-integration, the covariance against a Monte Carlo of the sensor noise, the
// stream checker's handling of each fault, and no allocation.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/imu_stream.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::estimator {
namespace {

using core::Status;
using Sample = ImuSample<double>;
using Pim = ImuPreintegration<double>;

const Vec3<double> kGravity(0.0, 0.0, -9.81);

Mat3<double> Rx(double a) { return ExpSO3<double>(Vec3<double>(a, 0, 0)); }
Mat3<double> Ry(double a) { return ExpSO3<double>(Vec3<double>(0, a, 0)); }
Mat3<double> Rz(double a) { return ExpSO3<double>(Vec3<double>(0, 0, a)); }

// A smooth 6-DoF motion with closed-form rates: R = Rz(yaw) Ry(pitch) Rx(roll) with sinusoidal
// angles (body rate w = Rx^T Ry^T e_z yaw' + Rx^T e_y pitch' + e_x roll'), and a sinusoidal
// position, so the IMU's rate and specific force are exact at every instant.
struct SmoothTrajectory {
  static double Yaw(double t) { return 0.8 * std::sin(1.1 * t); }
  static double YawRate(double t) { return 0.88 * std::cos(1.1 * t); }
  static double Pitch(double t) { return 0.3 * std::sin(0.7 * t + 0.4); }
  static double PitchRate(double t) { return 0.21 * std::cos(0.7 * t + 0.4); }
  static double Roll(double t) { return 0.5 * std::sin(1.3 * t + 1.0); }
  static double RollRate(double t) { return 0.65 * std::cos(1.3 * t + 1.0); }

  static Mat3<double> Rotation(double t) { return Rz(Yaw(t)) * Ry(Pitch(t)) * Rx(Roll(t)); }
  static Vec3<double> Position(double t) {
    return {2.0 * std::sin(0.9 * t), 1.5 * std::cos(0.6 * t), 0.5 * t + 0.3 * std::sin(1.7 * t)};
  }
  static Vec3<double> Velocity(double t) {
    return {1.8 * std::cos(0.9 * t), -0.9 * std::sin(0.6 * t), 0.5 + 0.51 * std::cos(1.7 * t)};
  }
  static Vec3<double> Acceleration(double t) {
    return {-1.62 * std::sin(0.9 * t), -0.54 * std::cos(0.6 * t), -0.867 * std::sin(1.7 * t)};
  }
  static Vec3<double> BodyRate(double t) {
    const Mat3<double> rx_t = Rx(Roll(t)).transpose();
    const Mat3<double> ry_t = Ry(Pitch(t)).transpose();
    return rx_t * ry_t * Vec3<double>::UnitZ() * YawRate(t) +
           rx_t * Vec3<double>::UnitY() * PitchRate(t) + Vec3<double>::UnitX() * RollRate(t);
  }
  static Vec3<double> SpecificForce(double t) {
    return Rotation(t).transpose() * (Acceleration(t) - kGravity);
  }
  static InertialState<double> State(double t) {
    InertialState<double> s;
    s.world_T_imu.R = Rotation(t);
    s.world_T_imu.t = Position(t);
    s.velocity_world_mps = Velocity(t);
    return s;
  }
};

std::vector<Sample> SampleTrajectory(double t0_s, double t1_s, double rate_hz) {
  std::vector<Sample> samples;
  const auto period_us = static_cast<std::int64_t>(std::llround(1e6 / rate_hz));
  const auto begin_us = static_cast<std::int64_t>(std::llround(t0_s * 1e6));
  for (std::int64_t t_us = begin_us, k = 0; t_us <= std::llround(t1_s * 1e6) + period_us;
       t_us += period_us, ++k) {
    Sample s;
    s.t_us = t_us;
    s.seq = k;
    s.gyro_radps = SmoothTrajectory::BodyRate(t_us * 1e-6);
    s.accel_mps2 = SmoothTrajectory::SpecificForce(t_us * 1e-6);
    samples.push_back(s);
  }
  return samples;
}

struct IncrementError {
  double rotation_rad = 0.0;
  double velocity_mps = 0.0;
  double position_m = 0.0;
};

// Preintegrates [t0, t1] at `rate_hz` and compares with the trajectory's exact increments.
IncrementError PreintegrationError(double t0, double t1, double rate_hz, SampleHold hold) {
  const std::vector<Sample> samples = SampleTrajectory(t0, t1, rate_hz);
  Pim pim;
  EXPECT_EQ(pim.Reset(ImuNoise<double>{}, ImuBiases<double>{}), Status::kOk);
  IntervalSummary summary;
  // The truth at the whole microseconds the interval is given in.
  const std::int64_t t0_us = std::llround(t0 * 1e6);
  const std::int64_t t1_us = std::llround(t1 * 1e6);
  EXPECT_EQ(PreintegrateInterval(samples.data(), static_cast<int>(samples.size()), t0_us, t1_us,
                                 hold, 1.0, &pim, &summary),
            Status::kOk);
  const InertialState<double> truth = SmoothTrajectory::State(t1_us * 1e-6);
  const InertialState<double> predicted =
      pim.Predict(SmoothTrajectory::State(t0_us * 1e-6), ImuBiases<double>{}, kGravity);
  IncrementError e;
  e.rotation_rad =
      LogSO3<double>(Mat3<double>(truth.world_T_imu.R.transpose() * predicted.world_T_imu.R))
          .norm();
  e.velocity_mps = (truth.velocity_world_mps - predicted.velocity_world_mps).norm();
  e.position_m = (truth.world_T_imu.t - predicted.world_T_imu.t).norm();
  return e;
}

TEST(ImuPreintegration, RightJacobianAgainstExponential) {
  const Vec3<double> a(0.3, -0.7, 0.2);
  const Vec3<double> d(1e-6, -2e-6, 1.5e-6);
  const Mat3<double> exact = ExpSO3<double>(Vec3<double>(a + d));
  const Mat3<double> first_order =
      ExpSO3<double>(a) * ExpSO3<double>(RightJacobianSO3<double>(a) * d);
  EXPECT_LT((exact - first_order).norm(), 1e-11);
  // Inverse of the existing inverse, also in the small-angle branch.
  for (const Vec3<double>& phi : {a, Vec3<double>(1e-7, 2e-7, -1e-7)}) {
    EXPECT_LT((RightJacobianSO3<double>(phi) * RightJacobianInverseSO3<double>(phi) -
               Mat3<double>::Identity())
                  .norm(),
              1e-12);
  }
}

// GIVEN a smooth trajectory with rates near 1 rad/s and accelerations near 2 m/s^2
// WHEN its exact samples are preintegrated over a 0.1 s frame interval at rising rates
// THEN each hold converges to the exact increments at its order, and a fine integration is exact
TEST(ImuPreintegration, MatchesKnownTrajectoryAtTheOrderOfEachHold) {
  const double t0 = 0.3;
  const double t1 = 0.4;
  const IncrementError zoh400 = PreintegrationError(t0, t1, 400.0, SampleHold::kZeroOrder);
  const IncrementError zoh800 = PreintegrationError(t0, t1, 800.0, SampleHold::kZeroOrder);
  const IncrementError mid400 = PreintegrationError(t0, t1, 400.0, SampleHold::kMidpoint);
  const IncrementError mid800 = PreintegrationError(t0, t1, 800.0, SampleHold::kMidpoint);
  // Zero-order hold: first order, the error halves with the step.
  EXPECT_NEAR(zoh400.rotation_rad / zoh800.rotation_rad, 2.0, 0.2);
  EXPECT_NEAR(zoh400.velocity_mps / zoh800.velocity_mps, 2.0, 0.2);
  EXPECT_NEAR(zoh400.position_m / zoh800.position_m, 2.0, 0.2);
  // Midpoint: second order, a quarter.
  EXPECT_NEAR(mid400.rotation_rad / mid800.rotation_rad, 4.0, 0.5);
  EXPECT_NEAR(mid400.velocity_mps / mid800.velocity_mps, 4.0, 0.5);
  EXPECT_NEAR(mid400.position_m / mid800.position_m, 4.0, 0.5);
  // At the simulator's rate the midpoint increments are good to a fraction of a micro-unit over
  // a frame (measured 5e-8 rad, 3e-7 m/s, 9e-8 m), and a fine integration is exact.
  EXPECT_LT(mid400.rotation_rad, 2e-7);
  EXPECT_LT(mid400.velocity_mps, 1e-6);
  EXPECT_LT(mid400.position_m, 3e-7);
  const IncrementError fine = PreintegrationError(t0, t1, 50000.0, SampleHold::kMidpoint);
  EXPECT_LT(fine.rotation_rad, 1e-10);
  EXPECT_LT(fine.velocity_mps, 1e-10);
  EXPECT_LT(fine.position_m, 1e-10);
}

TEST(ImuPreintegration, IntervalNotAlignedWithSamplesTakesPartialSteps) {
  // The interval's ends fall between samples (1/3 and 2/3 of a period in).
  const double t0 = 0.3 + 1.0 / 1200.0;
  const double t1 = 0.4 + 2.0 / 1200.0;
  const IncrementError e = PreintegrationError(t0, t1, 400.0, SampleHold::kMidpoint);
  EXPECT_LT(e.rotation_rad, 2e-7);
  EXPECT_LT(e.velocity_mps, 1e-6);
  EXPECT_LT(e.position_m, 3e-7);
}

Pim Integrate(const std::vector<Sample>& samples, const ImuBiases<double>& biases,
              const ImuNoise<double>& noise = {}) {
  Pim pim;
  EXPECT_EQ(pim.Reset(noise, biases), Status::kOk);
  for (std::size_t k = 0; k + 1 < samples.size(); ++k) {
    const double dt = (samples[k + 1].t_us - samples[k].t_us) * 1e-6;
    EXPECT_EQ(pim.Integrate(samples[k].gyro_radps, samples[k].accel_mps2, dt), Status::kOk);
  }
  return pim;
}

// The Jacobians are of the increments with respect to the biases; compared with central
// differences of a full re-integration, column by column.
TEST(ImuPreintegration, BiasJacobiansMatchNumericDifferences) {
  const std::vector<Sample> samples = SampleTrajectory(1.0, 1.2, 200.0);
  ImuBiases<double> bias;
  bias.gyro_radps = {0.01, -0.02, 0.015};
  bias.accel_mps2 = {0.1, 0.05, -0.08};
  const Pim pim = Integrate(samples, bias);
  const double h = 1e-6;
  for (int axis = 0; axis < 3; ++axis) {
    for (const bool gyro : {true, false}) {
      ImuBiases<double> plus = bias;
      ImuBiases<double> minus = bias;
      (gyro ? plus.gyro_radps : plus.accel_mps2)(axis) += h;
      (gyro ? minus.gyro_radps : minus.accel_mps2)(axis) -= h;
      const Pim p = Integrate(samples, plus);
      const Pim m = Integrate(samples, minus);
      const Vec3<double> d_rot = LogSO3<double>(Mat3<double>(m.Increments().rotation.transpose() *
                                                             p.Increments().rotation)) /
                                 (2 * h);
      const Vec3<double> d_vel =
          (p.Increments().velocity_mps - m.Increments().velocity_mps) / (2 * h);
      const Vec3<double> d_pos = (p.Increments().position_m - m.Increments().position_m) / (2 * h);
      if (gyro) {
        EXPECT_LT((d_rot - pim.DRotationDGyroBias().col(axis)).norm(), 1e-7) << axis;
        EXPECT_LT((d_vel - pim.DVelocityDGyroBias().col(axis)).norm(), 1e-6) << axis;
        EXPECT_LT((d_pos - pim.DPositionDGyroBias().col(axis)).norm(), 1e-7) << axis;
      } else {
        EXPECT_LT(d_rot.norm(), 1e-9) << axis;  // the accelerometer cannot turn the body
        EXPECT_LT((d_vel - pim.DVelocityDAccelBias().col(axis)).norm(), 1e-7) << axis;
        EXPECT_LT((d_pos - pim.DPositionDAccelBias().col(axis)).norm(), 1e-7) << axis;
      }
    }
  }
  // The Jacobians are not trivially small: a MEMS-sized bias error moves the increments.
  EXPECT_GT(pim.DRotationDGyroBias().norm(), 0.1);
  EXPECT_GT(pim.DPositionDAccelBias().norm(), 0.01);
}

// GIVEN the smooth 6-DoF motion sampled at 1 kHz, read with biases WHEN the interval
// [1.0, 1.2] s is integrated again moved by +-2 ms at both ends (a camera-IMU time offset)
// THEN the central difference of the increments is TimeShiftJacobian's, to the first order it
// promises (within 2 % of each block's size), and the Jacobian is not small: over this motion
// a 2 ms offset moves the rotation increment by 3.7e-4 rad
TEST(ImuPreintegration, TimeShiftJacobianMatchesMovingTheInterval) {
  std::vector<Sample> samples = SampleTrajectory(0.9, 1.3, 1000.0);
  ImuBiases<double> bias;
  bias.gyro_radps = {0.01, -0.02, 0.015};
  bias.accel_mps2 = {0.1, 0.05, -0.08};
  for (Sample& s : samples) {
    s.gyro_radps += bias.gyro_radps;
    s.accel_mps2 += bias.accel_mps2;
  }
  const auto integrate = [&](std::int64_t shift_us) {
    Pim pim;
    EXPECT_EQ(pim.Reset(ImuNoise<double>{}, bias), Status::kOk);
    IntervalSummary summary;
    EXPECT_EQ(
        PreintegrateInterval(samples.data(), static_cast<int>(samples.size()), 1000000 + shift_us,
                             1200000 + shift_us, SampleHold::kMidpoint, 1.0, &pim, &summary),
        Status::kOk);
    return pim;
  };
  const std::int64_t h_us = 2000;
  const double h = 2.0 * h_us * 1e-6;
  const Pim pim = integrate(0);
  const Pim plus = integrate(h_us);
  const Pim minus = integrate(-h_us);
  Vec9<double> numeric;
  numeric.segment<3>(Pim::kRotation) =
      LogSO3<double>(
          Mat3<double>(minus.Increments().rotation.transpose() * plus.Increments().rotation)) /
      h;
  numeric.segment<3>(Pim::kVelocity) =
      (plus.Increments().velocity_mps - minus.Increments().velocity_mps) / h;
  numeric.segment<3>(Pim::kPosition) =
      (plus.Increments().position_m - minus.Increments().position_m) / h;
  // The central difference straddles the interval: its rotation is taken about the middle.
  const Vec9<double> analytic = pim.TimeShiftJacobian();
  for (const int block : {Pim::kRotation, Pim::kVelocity, Pim::kPosition}) {
    const double size = analytic.segment<3>(block).norm();
    EXPECT_LT((numeric.segment<3>(block) - analytic.segment<3>(block)).norm(), 0.02 * size)
        << block << ": numeric " << numeric.segment<3>(block).transpose() << ", analytic "
        << analytic.segment<3>(block).transpose();
  }
  EXPECT_GT(analytic.segment<3>(Pim::kRotation).norm() * 2e-3, 3e-4);
}

TEST(ImuPreintegration, FirstOrderBiasCorrectionTracksReintegration) {
  const std::vector<Sample> samples = SampleTrajectory(2.0, 2.1, 400.0);
  const Pim pim = Integrate(samples, ImuBiases<double>{});
  ImuBiases<double> changed;
  changed.gyro_radps = {0.004, -0.003, 0.005};  // ~1000 deg/h: a large MEMS turn-on bias
  changed.accel_mps2 = {0.05, -0.04, 0.03};
  const Pim exact = Integrate(samples, changed);
  const Pim::Deltas corrected = pim.Corrected(changed);
  const auto rotation_error = [&](const Mat3<double>& r) {
    return LogSO3<double>(Mat3<double>(exact.Increments().rotation.transpose() * r)).norm();
  };
  const double uncorrected_rot = rotation_error(pim.Increments().rotation);
  const double uncorrected_pos =
      (exact.Increments().position_m - pim.Increments().position_m).norm();
  EXPECT_GT(uncorrected_rot, 1e-4);
  EXPECT_LT(rotation_error(corrected.rotation), 1e-3 * uncorrected_rot);
  EXPECT_LT((exact.Increments().velocity_mps - corrected.velocity_mps).norm(),
            1e-2 * (exact.Increments().velocity_mps - pim.Increments().velocity_mps).norm());
  EXPECT_LT((exact.Increments().position_m - corrected.position_m).norm(), 1e-2 * uncorrected_pos);
}

// GIVEN an interval integrated at zero biases while the sensor's gyroscope bias is a large
//       turn-on offset (0.3 rad/s, a consumer-grade unit's) and its accelerometer's 0.5 m/s^2
// WHEN the increments are moved to the true biases by the first-order correction, or the
//      interval is integrated again from its kept steps (Reintegrate)
// THEN the re-integration is the integration at those biases bit for bit, and the correction's
//      left-out second-order terms are measurable against the same motion without the bias
//      (over 0.3 s, 0.11 rad of bias-driven turn: 1.6e-4 rad, 6.5e-3 m/s, 4.7e-4 m; the velocity's
//      three times the interval's white noise), the
//      re-integration's are rounding; an interval longer than the kept steps is refused with
//      nothing changed
TEST(ImuPreintegration, ReintegrationReplacesTheFirstOrderCorrectionForALargeBiasChange) {
  const std::vector<Sample> samples = SampleTrajectory(2.0, 2.3, 400.0);
  ASSERT_LE(static_cast<int>(samples.size()), Pim::kMaxKeptSteps);
  ImuNoise<double> noise;
  noise.gyro_noise_density = 2e-4;
  noise.accel_noise_density = 2e-3;
  ImuBiases<double> truth;
  truth.gyro_radps = {0.3, -0.2, 0.1};
  truth.accel_mps2 = {0.5, -0.3, 0.2};
  std::vector<Sample> biased = samples;
  for (Sample& s : biased) {
    s.gyro_radps += truth.gyro_radps;
    s.accel_mps2 += truth.accel_mps2;
  }
  Pim pim = Integrate(biased, ImuBiases<double>{}, noise);
  const Pim::Deltas corrected = pim.Corrected(truth);
  const Pim exact = Integrate(biased, truth, noise);
  ASSERT_TRUE(pim.Replayable());
  ASSERT_EQ(pim.Reintegrate(truth), Status::kOk);
  EXPECT_EQ(pim.LinearizationBiases().gyro_radps, truth.gyro_radps);
  EXPECT_EQ(pim.Increments().rotation, exact.Increments().rotation);
  EXPECT_EQ(pim.Increments().velocity_mps, exact.Increments().velocity_mps);
  EXPECT_EQ(pim.Increments().position_m, exact.Increments().position_m);
  EXPECT_EQ(pim.Covariance(), exact.Covariance());
  EXPECT_EQ(pim.DVelocityDGyroBias(), exact.DVelocityDGyroBias());
  EXPECT_EQ(pim.NumSteps(), exact.NumSteps());
  EXPECT_EQ(pim.DurationS(), exact.DurationS());

  // Against the same samples without the bias, integrated at zero biases: the same motion and
  // discretization, so what remains is what the bias correction leaves out.
  const Pim unbiased = Integrate(samples, ImuBiases<double>{}, noise);
  const auto errors = [&](const Mat3<double>& r, const Vec3<double>& v, const Vec3<double>& p) {
    const Pim::Deltas& u = unbiased.Increments();
    return std::array<double, 3>{LogSO3<double>(Mat3<double>(u.rotation.transpose() * r)).norm(),
                                 (v - u.velocity_mps).norm(), (p - u.position_m).norm()};
  };
  const std::array<double, 3> first_order =
      errors(corrected.rotation, corrected.velocity_mps, corrected.position_m);
  const std::array<double, 3> replayed =
      errors(pim.Increments().rotation, pim.Increments().velocity_mps, pim.Increments().position_m);
  EXPECT_GT(first_order[0], 1e-4);
  EXPECT_GT(first_order[1], 3e-3);
  EXPECT_GT(first_order[2], 2e-4);
  // The velocity's is above the interval's own white-noise sigma (sqrt of the trace).
  EXPECT_GT(first_order[1],
            std::sqrt(unbiased.Covariance().block<3, 3>(Pim::kVelocity, Pim::kVelocity).trace()));
  for (int i = 0; i < 3; ++i) EXPECT_LT(replayed[i], 1e-12) << i;

  // Longer than the steps kept: refused, the interval as it was.
  const std::vector<Sample> long_samples = SampleTrajectory(2.0, 3.0, 400.0);
  Pim too_long = Integrate(long_samples, ImuBiases<double>{}, noise);
  ASSERT_GT(too_long.NumSteps(), Pim::kMaxKeptSteps);
  const Pim before = too_long;
  EXPECT_FALSE(too_long.Replayable());
  EXPECT_EQ(too_long.Reintegrate(truth), Status::kFull);
  EXPECT_EQ(too_long.Increments().rotation, before.Increments().rotation);
  EXPECT_EQ(too_long.LinearizationBiases().gyro_radps, before.LinearizationBiases().gyro_radps);
}

// GIVEN white gyro and accelerometer noise at stated densities on a rotating, accelerating body
// WHEN 4000 noisy copies of one 0.2 s interval are preintegrated
// THEN the spread of their errors matches the propagated covariance: diagonal within 10 %
//      (3.3 standard errors of a variance from 4000 draws), correlations within 0.06, and the
//      mean squared Mahalanobis distance within 9 +- 0.3 (about 4.5 standard errors)
TEST(ImuPreintegration, CovarianceMatchesMonteCarloOfTheNoise) {
  const double rate_hz = 200.0;
  const std::vector<Sample> samples = SampleTrajectory(0.5, 0.7, rate_hz);
  ImuNoise<double> noise;
  noise.gyro_noise_density = 2e-3;  // ten times an ADIS16448's, to be well above rounding
  noise.accel_noise_density = 2e-2;
  const Pim nominal = Integrate(samples, ImuBiases<double>{}, noise);
  const Mat9<double>& sigma = nominal.Covariance();
  const double dt = 1.0 / rate_hz;
  std::mt19937_64 engine(14);
  std::normal_distribution<double> normal;
  const int runs = 4000;
  Mat9<double> scatter = Mat9<double>::Zero();
  const Eigen::LLT<Mat9<double>> llt(sigma);
  ASSERT_EQ(llt.info(), Eigen::Success);
  double mahalanobis = 0.0;
  for (int r = 0; r < runs; ++r) {
    std::vector<Sample> noisy = samples;
    for (Sample& s : noisy) {
      for (int i = 0; i < 3; ++i) {
        s.gyro_radps(i) += noise.gyro_noise_density / std::sqrt(dt) * normal(engine);
        s.accel_mps2(i) += noise.accel_noise_density / std::sqrt(dt) * normal(engine);
      }
    }
    const Pim pim = Integrate(noisy, ImuBiases<double>{});
    Vec9<double> e;
    e.segment<3>(Pim::kRotation) = LogSO3<double>(
        Mat3<double>(nominal.Increments().rotation.transpose() * pim.Increments().rotation));
    e.segment<3>(Pim::kVelocity) =
        pim.Increments().velocity_mps - nominal.Increments().velocity_mps;
    e.segment<3>(Pim::kPosition) = pim.Increments().position_m - nominal.Increments().position_m;
    scatter += e * e.transpose();
    mahalanobis += e.dot(llt.solve(e));
  }
  const Mat9<double> sample_cov = scatter / runs;
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(sample_cov(i, i) / sigma(i, i), 1.0, 0.10) << i;
    for (int j = 0; j < i; ++j) {
      const double model = sigma(i, j) / std::sqrt(sigma(i, i) * sigma(j, j));
      const double drawn = sample_cov(i, j) / std::sqrt(sample_cov(i, i) * sample_cov(j, j));
      EXPECT_NEAR(drawn, model, 0.06) << i << "," << j;
    }
  }
  EXPECT_NEAR(mahalanobis / runs, 9.0, 0.3);
  // The blocks are coupled here (velocity-rotation, position-velocity), so the correlations
  // above test something.
  double largest_correlation = 0.0;
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < i; ++j)
      largest_correlation = std::max(largest_correlation,
                                     std::abs(sigma(i, j)) / std::sqrt(sigma(i, i) * sigma(j, j)));
  EXPECT_GT(largest_correlation, 0.5);
}

TEST(ImuPreintegration, RejectsBadInputWithoutChangingState) {
  Pim pim;
  ImuNoise<double> bad;
  bad.gyro_noise_density = -1.0;
  EXPECT_EQ(pim.Reset(bad, ImuBiases<double>{}), Status::kInvalidArgument);
  ASSERT_EQ(pim.Reset(ImuNoise<double>{}, ImuBiases<double>{}), Status::kOk);
  const Vec3<double> w(0.1, 0.0, 0.0);
  const Vec3<double> nan(std::nan(""), 0.0, 0.0);
  EXPECT_EQ(pim.Integrate(w, w, 0.0), Status::kInvalidArgument);
  EXPECT_EQ(pim.Integrate(w, w, -1e-3), Status::kInvalidArgument);
  EXPECT_EQ(pim.Integrate(nan, w, 1e-3), Status::kInvalidArgument);
  EXPECT_EQ(pim.Integrate(w, nan, 1e-3), Status::kInvalidArgument);
  EXPECT_EQ(pim.NumSteps(), 0);
  EXPECT_TRUE(pim.Increments().rotation.isIdentity());

  std::vector<Sample> samples = SampleTrajectory(0.0, 0.05, 200.0);
  IntervalSummary summary;
  EXPECT_EQ(PreintegrateInterval<double>(samples.data(), 0, 0, 10, SampleHold::kMidpoint, 1.0, &pim,
                                         &summary),
            Status::kEmpty);
  EXPECT_EQ(PreintegrateInterval(samples.data(), static_cast<int>(samples.size()), 10, 10,
                                 SampleHold::kMidpoint, 1.0, &pim, &summary),
            Status::kInvalidArgument);
  std::swap(samples[2], samples[3]);
  EXPECT_EQ(PreintegrateInterval(samples.data(), static_cast<int>(samples.size()), 0, 40000,
                                 SampleHold::kMidpoint, 1.0, &pim, &summary),
            Status::kInvalidArgument);
}

// Appending intervals is integrating their union: bit for bit when the split falls on a
// sample (the same steps), to third order in the step when it cuts one in two.
TEST(ImuPreintegration, ConsecutiveIntervalsComposeIntoTheirUnion) {
  const std::vector<Sample> samples = SampleTrajectory(0.0, 0.2, 200.0);
  const int n = static_cast<int>(samples.size());
  const ImuNoise<double> noise{1e-3, 1e-2, 0, 0};
  Pim whole;
  ASSERT_EQ(whole.Reset(noise, ImuBiases<double>{}), Status::kOk);
  IntervalSummary s;
  ASSERT_EQ(
      PreintegrateInterval(samples.data(), n, 0, 200000, SampleHold::kMidpoint, 0.01, &whole, &s),
      Status::kOk);
  EXPECT_EQ(s.samples_used, 40);
  for (const std::int64_t split_us : {75000, 77777}) {
    Pim split;
    ASSERT_EQ(split.Reset(noise, ImuBiases<double>{}), Status::kOk);
    ASSERT_EQ(PreintegrateInterval(samples.data(), n, 0, split_us, SampleHold::kMidpoint, 0.01,
                                   &split, &s),
              Status::kOk);
    ASSERT_EQ(PreintegrateInterval(samples.data(), n, split_us, 200000, SampleHold::kMidpoint, 0.01,
                                   &split, &s),
              Status::kOk);
    const double tolerance = split_us == 75000 ? 0.0 : 1e-7;
    EXPECT_LE((whole.Increments().rotation - split.Increments().rotation).norm(), tolerance);
    EXPECT_LE((whole.Increments().velocity_mps - split.Increments().velocity_mps).norm(),
              tolerance);
    EXPECT_LE((whole.Increments().position_m - split.Increments().position_m).norm(), tolerance);
    EXPECT_LE((whole.Covariance() - split.Covariance()).norm(),
              tolerance * whole.Covariance().norm());
    EXPECT_NEAR(whole.DurationS(), split.DurationS(), 1e-15);
  }
}

TEST(ImuPreintegration, HolesAreBridgedAndCounted) {
  std::vector<Sample> samples = SampleTrajectory(0.0, 0.1, 200.0);
  // Remove four samples in the middle (a 25 ms hole) and start the interval before the data.
  samples.erase(samples.begin() + 8, samples.begin() + 12);
  Pim pim;
  ASSERT_EQ(pim.Reset(ImuNoise<double>{}, ImuBiases<double>{}), Status::kOk);
  IntervalSummary summary;
  ASSERT_EQ(PreintegrateInterval(samples.data(), static_cast<int>(samples.size()), -2000, 100000,
                                 SampleHold::kZeroOrder, 0.0075, &pim, &summary),
            Status::kOk);
  EXPECT_EQ(summary.bridged_steps, 2);  // the stretched first sample and the hole
  EXPECT_NEAR(summary.longest_step_s, 0.025, 1e-12);
  EXPECT_NEAR(pim.DurationS(), 0.102, 1e-12);
  // The increments are still close: the signal is smooth and the hold bridges it.
  const InertialState<double> end =
      pim.Predict(SmoothTrajectory::State(-0.002), ImuBiases<double>{}, kGravity);
  EXPECT_LT((end.world_T_imu.t - SmoothTrajectory::Position(0.1)).norm(), 1e-3);
}

Sample StreamSample(std::int64_t t_us, std::int64_t seq) {
  Sample s;
  s.t_us = t_us;
  s.seq = seq;
  s.gyro_radps = {0.01, 0.02, 0.03};
  s.accel_mps2 = {0.0, 0.0, 9.81};
  return s;
}

TEST(ImuStream, CountsAndHandlesEachFault) {
  ImuStreamChecker<double> checker;
  ImuStreamOptions<double> options;
  options.nominal_period_us = 5000;
  options.max_gap_periods = 3;
  options.gyro_range_radps = 17.45;                                                 // 1000 deg/s
  options.accel_range_mps2 = 176.0;                                                 // 18 g
  EXPECT_EQ(checker.Check(StreamSample(0, 0)), ImuSampleVerdict::kDroppedInvalid);  // unconfigured
  ASSERT_EQ(checker.Configure(options), Status::kOk);
  EXPECT_EQ(checker.Check(StreamSample(0, 0)), ImuSampleVerdict::kAccepted);
  EXPECT_EQ(checker.Check(StreamSample(5000, 1)), ImuSampleVerdict::kAccepted);
  EXPECT_EQ(checker.Check(StreamSample(5000, 1)), ImuSampleVerdict::kDroppedDuplicate);
  EXPECT_EQ(checker.Check(StreamSample(2500, 2)), ImuSampleVerdict::kDroppedOutOfOrder);
  // Within the gap threshold but the counter says two were lost: a loss.
  EXPECT_EQ(checker.Check(StreamSample(20000, 4)), ImuSampleVerdict::kAcceptedAfterGap);
  // A 100 ms hole: 19 samples missing by time (the counter agrees).
  EXPECT_EQ(checker.Check(StreamSample(120000, 24)), ImuSampleVerdict::kAcceptedAfterGap);
  // The counter jumps but the time step is normal: renumbered, nothing lost.
  EXPECT_EQ(checker.Check(StreamSample(125000, 1000)), ImuSampleVerdict::kAccepted);
  Sample clipped = StreamSample(130000, 1001);
  clipped.gyro_radps.x() = 17.45;
  EXPECT_EQ(checker.Check(clipped), ImuSampleVerdict::kDroppedSaturated);
  Sample flagged = StreamSample(135000, 1002);
  flagged.flags |= kImuAccelSaturated;
  EXPECT_EQ(checker.Check(flagged), ImuSampleVerdict::kDroppedSaturated);
  Sample not_valid = StreamSample(140000, 1003);
  not_valid.flags = 0;
  EXPECT_EQ(checker.Check(not_valid), ImuSampleVerdict::kDroppedInvalid);
  Sample nan = StreamSample(145000, 1004);
  nan.accel_mps2.y() = std::nan("");
  EXPECT_EQ(checker.Check(nan), ImuSampleVerdict::kDroppedInvalid);
  // Dropped samples still closed their holes: the next in-order sample is not a gap.
  EXPECT_EQ(checker.Check(StreamSample(150000, 1005)), ImuSampleVerdict::kAccepted);
  // Corrupt extreme stamps: no overflow, counted, the stream goes on.
  EXPECT_EQ(checker.Check(StreamSample(INT64_MAX, INT64_MAX)), ImuSampleVerdict::kAcceptedAfterGap);
  EXPECT_EQ(checker.Check(StreamSample(INT64_MIN, INT64_MIN)),
            ImuSampleVerdict::kDroppedOutOfOrder);
  checker.Restart();
  EXPECT_EQ(checker.Check(StreamSample(INT64_MIN, INT64_MIN)), ImuSampleVerdict::kAccepted);

  const ImuStreamCounts& c = checker.Counts();
  EXPECT_EQ(c.accepted, 8);
  EXPECT_EQ(c.duplicated, 1);
  EXPECT_EQ(c.out_of_order, 2);
  EXPECT_EQ(c.saturated, 2);
  EXPECT_EQ(c.invalid, 2);
  EXPECT_EQ(c.gaps, 3);
  EXPECT_EQ(c.missing_samples, 2 + 19 + (std::int64_t{1} << 40));

  ImuStreamOptions<double> bad = options;
  bad.nominal_period_us = 0;
  EXPECT_EQ(checker.Configure(bad), Status::kInvalidArgument);
}

// A shuffled, repeated, holed stream: what passes is strictly increasing, so it integrates.
TEST(ImuStream, WhatPassesAlwaysIntegrates) {
  std::vector<Sample> stream;
  std::mt19937_64 engine(3);
  for (std::int64_t k = 0; k < 400; ++k) {
    if (k % 37 == 5) continue;  // lost
    stream.push_back(StreamSample(k * 5000, k));
    if (k % 11 == 0) stream.push_back(StreamSample(k * 5000, k));  // repeated
  }
  for (std::size_t i = 0; i + 1 < stream.size(); i += 9) std::swap(stream[i], stream[i + 1]);
  ImuStreamChecker<double> checker;
  ASSERT_EQ(checker.Configure(ImuStreamOptions<double>{}), Status::kOk);
  std::vector<Sample> passed;
  for (const Sample& s : stream)
    if (IsAccepted(checker.Check(s))) passed.push_back(s);
  for (std::size_t i = 1; i < passed.size(); ++i) ASSERT_GT(passed[i].t_us, passed[i - 1].t_us);
  const ImuStreamCounts& c = checker.Counts();
  EXPECT_EQ(c.accepted + c.duplicated + c.out_of_order, static_cast<std::int64_t>(stream.size()));
  EXPECT_GT(c.out_of_order, 0);
  EXPECT_GT(c.duplicated, 0);
  Pim pim;
  ASSERT_EQ(pim.Reset(ImuNoise<double>{}, ImuBiases<double>{}), Status::kOk);
  IntervalSummary summary;
  EXPECT_EQ(PreintegrateInterval(passed.data(), static_cast<int>(passed.size()), 0, 1995000,
                                 SampleHold::kMidpoint, 0.0075, &pim, &summary),
            Status::kOk);
  EXPECT_NEAR(pim.DurationS(), 1.995, 1e-9);
}

TEST(ImuPreintegration, NoAllocationWhileIntegratingAndChecking) {
  const std::vector<Sample> samples = SampleTrajectory(0.0, 5.0, 400.0);
  const int n = static_cast<int>(samples.size());
  Pim pim;
  ImuStreamChecker<double> checker;
  ASSERT_EQ(checker.Configure(ImuStreamOptions<double>{2500, 3, 0.0, 0.0}), Status::kOk);
  ImuNoise<double> noise{1.7e-4, 2e-3, 1.9e-5, 3e-3};
  int failures = 0;
  double checksum = 0.0;
  swf::testing::AllocationScope scope;
  for (int frame = 0; frame < 49; ++frame) {
    for (int k = frame * 40; k < (frame + 1) * 40; ++k)
      failures += IsAccepted(checker.Check(samples[k])) ? 0 : 1;
    failures += pim.Reset(noise, ImuBiases<double>{}) == Status::kOk ? 0 : 1;
    IntervalSummary summary;
    failures += PreintegrateInterval(samples.data(), n, frame * 100000LL, (frame + 1) * 100000LL,
                                     SampleHold::kMidpoint, 0.01, &pim, &summary) == Status::kOk
                    ? 0
                    : 1;
    checksum += pim.Corrected(ImuBiases<double>{}).position_m.norm() + pim.Covariance().trace();
  }
  EXPECT_EQ(scope.Count(), 0u);
  EXPECT_EQ(failures, 0);
  EXPECT_GT(checksum, 0.0);
}

}  // namespace
}  // namespace swf::estimator
