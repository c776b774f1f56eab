// ImuModel: the simulated IMU agrees with the trajectory the camera is rendered from (noiseless
// samples preintegrated between frames reproduce the true relative pose), its specific force
// agrees with the derivative of its own velocity, and its errors are the ones it records.
#include "swf/sim/imu_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "swf/estimator/imu_preintegration.hpp"

namespace swf::sim {
namespace {

using estimator::ImuBiases;
using estimator::InertialState;

// The flight demo's descent (10 Hz frames, 0.1 deg jitter) with the IMU mounted off the camera:
// rotated and 0.3 m away, so the lever arm and the extrinsic rotation are exercised. Dispersed: a
// Monte Carlo descent (80 m -> 20 m at 6 m/s, drifting 3 / -2 m/s sideways, the camera 5 / -3 /
// 20 deg off nadir and turning at 2 / -1.5 / 3 deg/s).
Trajectory Descent(bool dispersed = false) {
  Trajectory t;
  TrajectoryOptions o =
      dispersed ? DescentTrajectory(10.0, 80.0, 20.0, 6.0) : DescentTrajectory(10.0);
  o.start_time_ns = 1'000'000'000;
  o.jitter_sigma_rad = 0.5 * std::numbers::pi / 180.0;
  if (dispersed) {
    const double deg = std::numbers::pi / 180.0;
    o.velocity_world_mps.x() = 3.0;
    o.velocity_world_mps.y() = -2.0;
    o.attitude_offset_rad = Eigen::Vector3d(5.0, -3.0, 20.0) * deg;
    o.body_rate_radps = Eigen::Vector3d(2.0, -1.5, 3.0) * deg;
  }
  EXPECT_EQ(t.Configure(o), core::Status::kOk);
  return t;
}

// Each truth test on the nominal and on the dispersed descent.
class ImuOnTrajectory : public ::testing::TestWithParam<bool> {};
INSTANTIATE_TEST_SUITE_P(NominalAndDispersed, ImuOnTrajectory, ::testing::Bool());

ImuModelOptions Mounted(ImuModelOptions o) {
  o.camera_T_imu.R = estimator::ExpSO3<double>(Eigen::Vector3d(0.1, -0.2, 1.5));
  o.camera_T_imu.t = Eigen::Vector3d(0.2, -0.1, 0.2);
  return o;
}

TEST_P(ImuOnTrajectory, TruthPassesThroughEveryFramePose) {
  const Trajectory trajectory = Descent(GetParam());
  ImuModel imu;
  ASSERT_EQ(imu.Configure(Mounted(Noiseless(MemsImu())), trajectory), core::Status::kOk);
  for (std::int32_t k = 0; k < trajectory.NumFrames(); ++k) {
    const estimator::Pose<double> expected =
        trajectory.WorldTCamera(k) * Mounted(MemsImu()).camera_T_imu;
    const InertialState<double> s = imu.TrueState(trajectory.FrameTimeNs(k) * 1e-9);
    EXPECT_LT((s.world_T_imu.R - expected.R).norm(), 1e-12) << k;
    EXPECT_LT((s.world_T_imu.t - expected.t).norm(), 1e-9) << k;
  }
}

// An independent check of the analytic rate and specific force (lever arm included): central
// differences of the true attitude and velocity.
TEST_P(ImuOnTrajectory, RateAndSpecificForceAreTheDerivativesOfTheTruth) {
  const Trajectory trajectory = Descent(GetParam());
  ImuModel imu;
  ASSERT_EQ(imu.Configure(Mounted(Noiseless(MemsImu())), trajectory), core::Status::kOk);
  const double h = 1e-4;
  for (const double t : {1.03, 2.57, 4.77, 9.23}) {  // between frames (1.0 + k / 10 s)
    const InertialState<double> before = imu.TrueState(t - h);
    const InertialState<double> after = imu.TrueState(t + h);
    const InertialState<double> now = imu.TrueState(t);
    const Eigen::Vector3d rate_fd = estimator::LogSO3<double>(Eigen::Matrix3d(
                                        before.world_T_imu.R.transpose() * after.world_T_imu.R)) /
                                    (2 * h);
    EXPECT_LT((rate_fd - imu.TrueRate(t)).norm(), 1e-7) << t;
    const Eigen::Vector3d velocity_fd = (after.world_T_imu.t - before.world_T_imu.t) / (2 * h);
    EXPECT_LT((velocity_fd - now.velocity_world_mps).norm(), 1e-7) << t;
    const Eigen::Vector3d accel_fd =
        (after.velocity_world_mps - before.velocity_world_mps) / (2 * h);
    const Eigen::Vector3d force_fd =
        now.world_T_imu.R.transpose() * (accel_fd - imu.GravityWorld());
    EXPECT_LT((force_fd - imu.TrueSpecificForce(t)).norm(), 1e-6) << t;
  }
  // The lever arm and jitter make the motion non-trivial: the IMU turns and accelerates.
  EXPECT_GT(imu.TrueRate(2.5).norm(), 1e-3);
}

struct WorstErrors {
  double rotation_rad = 0.0;
  double position_m = 0.0;
  double velocity_mps = 0.0;
};

// Preintegrates the noiseless IMU between every pair of consecutive frames and compares the
// prediction from the true state at the first with the true state at the second.
WorstErrors FrameToFrameErrors(const Trajectory& trajectory, double rate_hz) {
  ImuModelOptions options = Mounted(Noiseless(MemsImu()));
  options.rate_hz = rate_hz;
  ImuModel imu;
  EXPECT_EQ(imu.Configure(options, trajectory), core::Status::kOk);
  const auto& samples = imu.Samples();
  WorstErrors worst;
  for (std::int32_t k = 0; k + 1 < trajectory.NumFrames(); ++k) {
    const std::int64_t t0_us = trajectory.FrameTimeNs(k) / 1000;
    const std::int64_t t1_us = trajectory.FrameTimeNs(k + 1) / 1000;
    estimator::ImuPreintegration<double> pim;
    EXPECT_EQ(pim.Reset(imu.NoiseModel(), ImuBiases<double>{}), core::Status::kOk);
    estimator::IntervalSummary summary;
    EXPECT_EQ(estimator::PreintegrateInterval(samples.data(), static_cast<int>(samples.size()),
                                              t0_us, t1_us, estimator::SampleHold::kMidpoint,
                                              1.5 / rate_hz, &pim, &summary),
              core::Status::kOk);
    EXPECT_EQ(summary.bridged_steps, 0);
    const InertialState<double> truth = imu.TrueState(t1_us * 1e-6);
    const InertialState<double> predicted =
        pim.Predict(imu.TrueState(t0_us * 1e-6), ImuBiases<double>{}, imu.GravityWorld());
    worst.rotation_rad =
        std::max(worst.rotation_rad,
                 estimator::LogSO3<double>(
                     Eigen::Matrix3d(truth.world_T_imu.R.transpose() * predicted.world_T_imu.R))
                     .norm());
    worst.position_m =
        std::max(worst.position_m, (truth.world_T_imu.t - predicted.world_T_imu.t).norm());
    worst.velocity_mps = std::max(worst.velocity_mps,
                                  (truth.velocity_world_mps - predicted.velocity_world_mps).norm());
  }
  return worst;
}

// GIVEN the noiseless simulated IMU on the descent with 0.5 deg attitude jitter (five times the
// demo's: angular rates to 0.1 rad/s, their second derivative to ~50 rad/s^3 at the spline knots)
// WHEN it is preintegrated between every pair of consecutive frames (0.1 s)
// THEN the prediction equals the true pose and velocity to the integration's own truncation
//      error (measured 3.3e-6 rad, 1.0e-6 m at 400 Hz, the dispersed descent's too), which falls
//      as the step squared: the samples and the trajectory are one motion, with nothing left over
TEST_P(ImuOnTrajectory, NoiselessSamplesPreintegrateToTheTrueRelativePose) {
  const Trajectory trajectory = Descent(GetParam());
  const WorstErrors at400 = FrameToFrameErrors(trajectory, 400.0);
  EXPECT_LT(at400.rotation_rad, 5e-6);  // 1 arcsecond
  EXPECT_LT(at400.position_m, 2e-6);
  EXPECT_LT(at400.velocity_mps, 1e-5);
  const WorstErrors at1600 = FrameToFrameErrors(trajectory, 1600.0);
  EXPECT_LT(at1600.rotation_rad, at400.rotation_rad / 12.0);  // 16x ideally
  EXPECT_LT(at1600.position_m, at400.position_m / 12.0);
  // Measured 12.3x nominal, 11.6x dispersed (first order would be 4x).
  EXPECT_LT(at1600.velocity_mps, at400.velocity_mps / 10.0);
}

// The recorded biases are the ones in the samples: over a frame the mean difference between
// the samples and the scaled truth is the mean recorded bias, within the white noise's mean.
TEST(ImuModel, RecordsTheBiasesAndScaleFactorsItApplies) {
  const Trajectory trajectory = Descent();
  for (const ImuModelOptions& unit : {MemsImu(), TacticalImu()}) {
    ImuModel imu;
    ImuModelOptions options = Mounted(unit);
    options.seed = 7;
    ASSERT_EQ(imu.Configure(options, trajectory), core::Status::kOk);
    const auto& samples = imu.Samples();
    const auto& biases = imu.TrueBiases();
    ASSERT_EQ(samples.size(), biases.size());
    ASSERT_GE(samples.size(), 3600u);  // 9 s at 400 Hz
    const int n = 2000;
    Eigen::Vector3d gyro_residual = Eigen::Vector3d::Zero();
    Eigen::Vector3d accel_residual = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) {
      const double t = samples[i].t_us * 1e-6;
      const Eigen::Vector3d gyro_truth =
          (Eigen::Vector3d::Ones() + imu.GyroScaleFactor()).cwiseProduct(imu.TrueRate(t));
      const Eigen::Vector3d accel_truth =
          (Eigen::Vector3d::Ones() + imu.AccelScaleFactor()).cwiseProduct(imu.TrueSpecificForce(t));
      gyro_residual += samples[i].gyro_radps - gyro_truth - biases[i].gyro_radps;
      accel_residual += samples[i].accel_mps2 - accel_truth - biases[i].accel_mps2;
      EXPECT_EQ(samples[i].flags, estimator::kImuValid);
    }
    // Mean of n white samples: sigma N sqrt(rate) / sqrt(n); 5 sigma.
    const double gyro_mean_sigma = options.gyro.noise_density * std::sqrt(400.0 / n);
    const double accel_mean_sigma = options.accel.noise_density * std::sqrt(400.0 / n);
    EXPECT_LT((gyro_residual / n).cwiseAbs().maxCoeff(), 5 * gyro_mean_sigma) << unit.part;
    EXPECT_LT((accel_residual / n).cwiseAbs().maxCoeff(), 5 * accel_mean_sigma) << unit.part;
    // The MEMS bias is there to be estimated: above what 5 s of its noise averages to.
    if (std::string(unit.part) == MemsImu().part)
      EXPECT_GT(biases[0].gyro_radps.norm(), gyro_mean_sigma) << unit.part;
  }
}

// GIVEN a descent without jitter whose camera turns at a constant body rate with a horizontal
// velocity THEN the gyroscope's truth is that rate in the IMU frame at every instant, the IMU's
// specific force is the lever arm's centripetal term plus gravity (the camera never accelerates),
// and a tail keeps sampling past the last frame.
TEST(ImuModel, AConstantBodyRateIsWhatTheGyroscopeMeasures) {
  TrajectoryOptions o = DescentTrajectory(10.0, 60.0, 20.0, 8.0);
  o.jitter_sigma_rad = 0.0;
  o.velocity_world_mps.x() = -4.0;
  o.attitude_offset_rad = Eigen::Vector3d(0.1, 0.05, -0.3);
  o.body_rate_radps = Eigen::Vector3d(0.02, -0.03, 0.05);
  Trajectory trajectory;
  ASSERT_EQ(trajectory.Configure(o), core::Status::kOk);
  ASSERT_EQ(trajectory.NumFrames(), 51);
  ImuModelOptions unit = Mounted(Noiseless(TacticalImu()));
  ImuModel imu;
  ASSERT_EQ(imu.Configure(unit, trajectory), core::Status::kOk);
  const Eigen::Vector3d lever = unit.camera_T_imu.t;
  const Eigen::Vector3d w = o.body_rate_radps;
  for (const double t : {0.0, 0.77, 2.5, 4.99}) {
    EXPECT_LT((imu.TrueRate(t) - unit.camera_T_imu.R.transpose() * w).norm(), 1e-12) << t;
    const InertialState<double> s = imu.TrueState(t);
    const Eigen::Matrix3d world_R_camera = s.world_T_imu.R * unit.camera_T_imu.R.transpose();
    const Eigen::Vector3d accel_world = world_R_camera * w.cross(w.cross(lever));
    EXPECT_LT((imu.TrueSpecificForce(t) -
               s.world_T_imu.R.transpose() * (accel_world - imu.GravityWorld()))
                  .norm(),
              1e-6)
        << t;
    EXPECT_LT((world_R_camera - SteeredAttitude(o, t)).norm(), 1e-12) << t;
  }
  EXPECT_EQ(imu.Samples().back().t_us, 5'002'500);  // 5 s, one 400 Hz sample past the last frame
  unit.tail_s = 0.05;
  ASSERT_EQ(imu.Configure(unit, trajectory), core::Status::kOk);
  EXPECT_GE(imu.Samples().back().t_us, 5'050'000);
  unit.tail_s = -1.0;
  EXPECT_EQ(imu.Configure(unit, trajectory), core::Status::kInvalidArgument);
}

TEST(ImuModel, SeededAndSaturating) {
  const Trajectory trajectory = Descent();
  ImuModel a;
  ImuModel b;
  ASSERT_EQ(a.Configure(MemsImu(), trajectory), core::Status::kOk);
  ASSERT_EQ(b.Configure(MemsImu(), trajectory), core::Status::kOk);
  for (std::size_t i = 0; i < a.Samples().size(); i += 97) {
    EXPECT_EQ(a.Samples()[i].gyro_radps, b.Samples()[i].gyro_radps);
    EXPECT_EQ(a.Samples()[i].accel_mps2, b.Samples()[i].accel_mps2);
  }
  ImuModelOptions low_range = MemsImu();
  low_range.accel.range = 1.0;  // below the Moon's 1.625 m/s^2: every sample clips
  ImuModel clipped;
  ASSERT_EQ(clipped.Configure(low_range, trajectory), core::Status::kOk);
  EXPECT_NE(clipped.Samples()[10].flags & estimator::kImuAccelSaturated, 0u);
  ImuModelOptions bad = MemsImu();
  bad.rate_hz = 0.0;
  EXPECT_EQ(clipped.Configure(bad, trajectory), core::Status::kInvalidArgument);
  bad = MemsImu();
  bad.gyro.noise_density = -1.0;
  EXPECT_EQ(clipped.Configure(bad, trajectory), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::sim
