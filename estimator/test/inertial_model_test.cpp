// Stereo-inertial estimation, the model and the filter's flight properties: InertialStereoModel's
// residuals and Jacobians against central differences, and the filter with it allocating
// nothing and repeating bit for bit (inertial_scenario_test.cpp has the accuracy runs).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "inertial_runner.hpp"

namespace swf::estimator::testing {
namespace {

using Model = InertialStereoModel<double>;

// ---- the model's derivatives --------------------------------------------------------------

State RandomState(std::mt19937_64* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  auto v = [&](double scale) {
    return Vec3<double>(scale * g(*rng), scale * g(*rng), scale * g(*rng));
  };
  State x;
  x.world_T_imu.R = ExpSO3<double>(v(1.0));
  x.world_T_imu.t = v(10.0);
  x.velocity_world_mps = v(2.0);
  x.biases.gyro_radps = v(0.01);
  x.biases.accel_mps2 = v(0.1);
  return x;
}

TEST(InertialModel, ProcessJacobiansMatchCentralDifferences) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  Model model;
  ImuNoise<double> noise{2e-4, 2e-3, 2e-5, 2e-4};
  ImuBiases<double> linearization;
  linearization.gyro_radps = Vec3<double>(0.004, -0.002, 0.001);
  linearization.accel_mps2 = Vec3<double>(0.02, 0.03, -0.05);
  Pim pim;
  ASSERT_EQ(pim.Reset(noise, linearization), core::Status::kOk);
  for (int k = 0; k < 40; ++k)
    ASSERT_EQ(pim.Integrate(Vec3<double>(0.3 + 0.01 * k, -0.2, 0.5),
                            Vec3<double>(0.4, 1.2 - 0.02 * k, 9.0), 0.005),
              core::Status::kOk);
  for (int trial = 0; trial < 5; ++trial) {
    const State prev = RandomState(&rng);
    // Near the prediction, as in flight, but not on it: every residual block is non-zero.
    State next = model.Propagate(prev, pim);
    Vec15<double> offset;
    for (int k = 0; k < 15; ++k) offset[k] = 0.05 * g(rng);
    next = Model::Retract(next, offset);
    Mat15<double> j_prev;
    Mat15<double> j_next;
    (void)model.ProcessResidual(prev, next, pim, &j_prev, &j_next);
    const double h = 1e-6;
    for (int k = 0; k < 15; ++k) {
      const Vec15<double> e = Vec15<double>::Unit(k) * h;
      Mat15<double> unused_a;
      Mat15<double> unused_b;
      const Vec15<double> dp =
          (model.ProcessResidual(Model::Retract(prev, e), next, pim, &unused_a, &unused_b) -
           model.ProcessResidual(Model::Retract(prev, -e), next, pim, &unused_a, &unused_b)) /
          (2 * h);
      const Vec15<double> dn =
          (model.ProcessResidual(prev, Model::Retract(next, e), pim, &unused_a, &unused_b) -
           model.ProcessResidual(prev, Model::Retract(next, -e), pim, &unused_a, &unused_b)) /
          (2 * h);
      EXPECT_LT((dp - j_prev.col(k)).cwiseAbs().maxCoeff(), 1e-6) << "prev column " << k;
      EXPECT_LT((dn - j_next.col(k)).cwiseAbs().maxCoeff(), 1e-6) << "next column " << k;
    }
  }
}

TEST(InertialModel, ResidualVanishesOnThePredictionAndCovarianceIsTheIntegrations) {
  std::mt19937_64 rng(5);
  Model model;
  ImuNoise<double> noise{2e-4, 2e-3, 2e-5, 2e-4};
  Pim pim;
  ASSERT_EQ(pim.Reset(noise, ImuBiases<double>{}), core::Status::kOk);
  for (int k = 0; k < 20; ++k)
    ASSERT_EQ(pim.Integrate(Vec3<double>(0.1, 0.2, -0.3), Vec3<double>(0.5, -0.4, 9.5), 0.005),
              core::Status::kOk);
  const State prev = RandomState(&rng);
  Mat15<double> a;
  Mat15<double> b;
  EXPECT_LT(model.ProcessResidual(prev, model.Propagate(prev, pim), pim, &a, &b).norm(), 1e-12);
  const Mat15<double> q = Model::ProcessCovariance(pim);
  const Mat3<double> rotation = q.block<3, 3>(Model::kRotation, Model::kRotation);
  const Mat3<double> position_velocity = q.block<3, 3>(Model::kPosition, Model::kVelocity);
  EXPECT_EQ(rotation, (pim.Covariance().block<3, 3>(Pim::kRotation, Pim::kRotation)));
  EXPECT_EQ(position_velocity, (pim.Covariance().block<3, 3>(Pim::kPosition, Pim::kVelocity)));
  EXPECT_DOUBLE_EQ(q(Model::kGyroBias, Model::kGyroBias), 2e-5 * 2e-5 * 0.1);
  Mat15<double> w;
  ASSERT_TRUE(Model::ProcessSqrtInformation(pim, &w));
  EXPECT_LT(((w.transpose() * w) * q - Mat15<double>::Identity()).cwiseAbs().maxCoeff(), 1e-6);
  // Without noise the covariance is singular: refused rather than inverted.
  ASSERT_EQ(pim.Reset(ImuNoise<double>{}, ImuBiases<double>{}), core::Status::kOk);
  ASSERT_EQ(pim.Integrate(Vec3<double>::Zero(), Vec3<double>(0, 0, 9.8), 0.005), core::Status::kOk);
  EXPECT_FALSE(Model::ProcessSqrtInformation(pim, &w));
}

TEST(InertialModel, MeasurementJacobianIsThroughTheLeverArm) {
  std::mt19937_64 rng(7);
  Model model;
  model.stereo.camera = EdlRig();
  model.imu_T_camera.R = ExpSO3<double>(Vec3<double>(0.1, -0.2, 0.7));
  model.imu_T_camera.t = Vec3<double>(0.4, -0.3, 0.2);
  State x = RandomState(&rng);
  x.world_T_imu.R = ExpSO3<double>(Vec3<double>(M_PI, 0.0, 0.0)) *
                    model.imu_T_camera.R.transpose();  // camera looking down
  x.world_T_imu.t = Vec3<double>(1.0, 2.0, 30.0);
  const Vec3<double> l(2.0, 1.0, 0.5);
  Vec3<double> z;
  Mat36<double> jp;
  Mat3<double> jl;
  ASSERT_TRUE(model.Predict(x, {}, l, &z, &jp, &jl));
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    const Vec15<double> e = Vec15<double>::Unit(k) * h;
    Vec3<double> zp;
    Vec3<double> zm;
    ASSERT_TRUE(model.Predict(Model::Retract(x, e), {}, l, &zp, nullptr, nullptr));
    ASSERT_TRUE(model.Predict(Model::Retract(x, -e), {}, l, &zm, nullptr, nullptr));
    EXPECT_LT(((zp - zm) / (2 * h) - jp.col(k)).cwiseAbs().maxCoeff(), 1e-4) << "column " << k;
  }
  // Velocity and biases do not move the image.
  Vec15<double> not_pose = Vec15<double>::Zero();
  not_pose.tail<9>().setOnes();
  Vec3<double> moved;
  ASSERT_TRUE(model.Predict(Model::Retract(x, not_pose), {}, l, &moved, nullptr, nullptr));
  EXPECT_EQ(moved, z);
}

// ---- the filter with the IMU ----------------------------------------------------------------

TEST(InertialSwf, AllocatesNothingAndRepeatsBitForBit) {
  const InertialScene scene = DescentScene(2, 20);
  const InertialRunResult a = RunFilter<5, 200>(scene, SwfMode::kSlidingWindow, 7);
  const InertialRunResult b = RunFilter<5, 200>(scene, SwfMode::kSlidingWindow, 7);
  EXPECT_EQ(a.allocations, 0u);
  ASSERT_EQ(a.newest.size(), b.newest.size());
  for (std::size_t j = 0; j < a.newest.size(); ++j) {
    EXPECT_EQ(a.newest[j].world_T_imu.t, b.newest[j].world_T_imu.t);
    EXPECT_EQ(a.newest[j].biases.accel_mps2, b.newest[j].biases.accel_mps2);
  }
}

// ---- re-integration and the process factor's weight ------------------------------------------

// A filter fed `scene` frames 0..frames-1: the first state the truth with its biases (stated
// tightly), every later interval integrated at `integrate_at` and weighted with the square-root
// information of the integration at `weigh_at` (nullptr: the filter's current bias estimate for
// either, as in flight). Returns the newest state's covariance after the last update.
using ReintegrationFilter = SlidingWindowFilter<Model, 5, 200, 200, 200>;
Mat15<double> NewestCovarianceAfter(const InertialScene& scene, int frames,
                                    const ImuBiases<double>* integrate_at,
                                    const ImuBiases<double>* weigh_at, int* reintegrated) {
  auto swf = std::make_unique<ReintegrationFilter>();
  SwfOptions options;
  options.mode = SwfMode::kSlidingWindow;
  EXPECT_EQ(swf->Configure(scene.model, options), core::Status::kOk);
  *reintegrated = 0;
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options.sigma_px;
  for (int j = 0; j < frames; ++j) {
    if (j == 0) {
      Mat15<double> p0 = scene::FirstPoseCovariance(0.05, 0.002);
      p0.bottomRightCorner<6, 6>() = Mat6<double>::Identity() * 1e-8;
      EXPECT_EQ(swf->AddFirstPose(scene.truth[0], p0), core::Status::kOk);
    } else {
      const ImuBiases<double> current = swf->NewestPose().biases;
      Pim pim;
      Pim weighed;
      Mat15<double> unused;
      Mat15<double> w;
      EXPECT_TRUE(PreintegrateFrame(scene, static_cast<std::size_t>(j),
                                    integrate_at != nullptr ? *integrate_at : current, &pim,
                                    &unused));
      EXPECT_TRUE(PreintegrateFrame(scene, static_cast<std::size_t>(j),
                                    weigh_at != nullptr ? *weigh_at : current, &weighed, &w));
      EXPECT_EQ(swf->AddPoseWithMotion(pim, w), core::Status::kOk);
    }
    for (const auto& [id, z] : scene.obs[static_cast<std::size_t>(j)])
      (void)swf->AddObservation(id, z, r_sqrt);
    EXPECT_FALSE(scene::UpdateFailed(swf->Update()));
    *reintegrated += swf->Summary().motions_reintegrated;
  }
  EXPECT_EQ(swf->ComputeCovariances(), core::Status::kOk);
  return swf->NewestStateCovariance();
}

// GIVEN the estimator's descent scene with a large turn-on gyroscope bias (0.3 rad/s added to
//       every sample, 30 mrad of turn per interval), the first state's biases known
// WHEN every interval is integrated at zero biases and weighted for them, so that the filter
//      integrates each one again at the first state's biases before its solve (A); or
//      integrated and weighted at those biases from the start (B: nothing to re-integrate); or
//      integrated at those biases but weighted as at zero biases (C: what a re-integration that
//      kept the old weight would solve)
// THEN A re-integrates every interval and its newest state covariance is B's (to the solver's
//      tolerance: only the first prediction of each state differs), ten times closer than C's,
//      which the stale weight moves measurably (measured: A 1.5e-8, C 2.2e-6 off B relative)
TEST(InertialSwf, ReintegrationRecomputesTheProcessFactorsWeight) {
  InertialScene scene = DescentScene(3, 8);
  const Vec3<double> offset(0.3, -0.2, 0.1);
  for (auto& sample : scene.samples) sample.gyro_radps += offset;
  scene.true_biases.gyro_radps += offset;
  for (auto& x : scene.truth) x.biases = scene.true_biases;
  const ImuBiases<double> zero;
  const int frames = static_cast<int>(scene.truth.size());
  int reintegrated_a = 0;
  int reintegrated_b = 0;
  int reintegrated_c = 0;
  const Mat15<double> a = NewestCovarianceAfter(scene, frames, &zero, &zero, &reintegrated_a);
  const Mat15<double> b = NewestCovarianceAfter(scene, frames, nullptr, nullptr, &reintegrated_b);
  const Mat15<double> c = NewestCovarianceAfter(scene, frames, nullptr, &zero, &reintegrated_c);
  EXPECT_GE(reintegrated_a, frames - 1);
  EXPECT_EQ(reintegrated_b, 0);
  EXPECT_EQ(reintegrated_c, 0);
  const double a_off = (a - b).norm() / b.norm();
  const double c_off = (c - b).norm() / b.norm();
  std::printf("newest state covariance off B's (relative Frobenius): A %.3g, C %.3g\n", a_off,
              c_off);
  EXPECT_GT(c_off, 1e-6);
  EXPECT_LT(a_off, 0.1 * c_off);
}

// GIVEN 2 s of a tilted IMU at rest (noise, a gyroscope bias) and a guidance attitude 50 mrad off
// in tilt and 0.3 rad off in heading WHEN aligned THEN the tilt is levelled to the accelerometer's
// noise, the heading is the guidance's, and the gyroscope bias is the mean rate; a vibrating or
// accelerating IMU, and too few samples, are refused.
TEST(StaticAlignmentTest, LevelsTheGuidanceAttitudeAndReadsTheGyroBias) {
  const Vec3<double> gravity(0.0, 0.0, -1.625);
  const Mat3<double> truth = ExpSO3<double>(Vec3<double>(0.2, -0.1, 1.0));
  const Vec3<double> bias(0.002, -0.001, 0.003);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<ImuSample<double>> samples(400);
  for (int k = 0; k < 400; ++k) {
    samples[k].t_us = 5000 * k;
    samples[k].seq = k;
    for (int i = 0; i < 3; ++i) {
      samples[k].gyro_radps[i] = bias[i] + 1e-3 * noise(rng);
      samples[k].accel_mps2[i] = (truth.transpose() * -gravity)[i] + 5e-3 * noise(rng);
    }
  }
  const Mat3<double> guess =
      ExpSO3<double>(Vec3<double>(0.05, 0.0, 0.3)) * truth;  // tilt and heading errors
  StaticAlignment<double> a;
  ASSERT_TRUE(
      AlignStatic(samples.data(), 400, guess, gravity, StaticAlignmentOptions<double>{}, &a));
  const Vec3<double> up_error =
      (a.world_R_imu * truth.transpose() * Vec3<double>::UnitZ()) - Vec3<double>::UnitZ();
  EXPECT_LT(up_error.norm(), 1e-3);  // levelled: 5e-3 / 1.625 / sqrt(400) ~ 2e-4 rad per axis
  EXPECT_NEAR(a.tilt_correction_rad, 0.05, 0.01);
  // The heading stays the guidance's: the x axis' horizontal direction is the guess's.
  const Vec3<double> x_aligned = a.world_R_imu.col(0);
  const Vec3<double> x_guess = guess.col(0);
  EXPECT_NEAR(std::atan2(x_aligned.y(), x_aligned.x()), std::atan2(x_guess.y(), x_guess.x()), 0.01);
  EXPECT_LT((a.gyro_bias_radps - bias).norm(), 3e-4);  // 1e-3 / sqrt(400) = 5e-5 per axis
  EXPECT_NEAR(a.duration_s, 1.995, 1e-9);

  std::vector<ImuSample<double>> shaken = samples;
  for (int k = 0; k < 400; ++k) shaken[k].accel_mps2.x() += (k % 2 == 0 ? 1.0 : -1.0);
  EXPECT_FALSE(
      AlignStatic(shaken.data(), 400, guess, gravity, StaticAlignmentOptions<double>{}, &a));
  std::vector<ImuSample<double>> turning = samples;
  for (int k = 0; k < 400; ++k) turning[k].gyro_radps.z() += 0.1 * std::sin(0.05 * k);
  EXPECT_FALSE(
      AlignStatic(turning.data(), 400, guess, gravity, StaticAlignmentOptions<double>{}, &a));
  std::vector<ImuSample<double>> pushed = samples;
  for (ImuSample<double>& s : pushed) s.accel_mps2 *= 1.5;  // accelerating along the force
  EXPECT_FALSE(
      AlignStatic(pushed.data(), 400, guess, gravity, StaticAlignmentOptions<double>{}, &a));
  EXPECT_FALSE(
      AlignStatic(samples.data(), 10, guess, gravity, StaticAlignmentOptions<double>{}, &a));
}

}  // namespace
}  // namespace swf::estimator::testing
