// Stereo-inertial estimation: InertialStereoModel's residuals and Jacobians, and the Sliding
// Window Filter with it on a descent whose IMU samples are the exact derivatives of the
// trajectory plus white noise and constant biases (no simulator: the estimator's own tests).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "inertial_scene.hpp"
#include "swf/estimator/inertial_model.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::estimator {
namespace {

using Model = InertialStereoModel<double>;
using State = NavState<double>;
using Pim = ImuPreintegration<double>;
using testing::EdlRig;
using testing::InertialScene;
using testing::InertialSceneOptions;
using testing::MakeInertialScene;

InertialScene Scene(std::uint64_t seed, int frames) {
  InertialSceneOptions o;
  o.seed = seed;
  o.frames = frames;
  return MakeInertialScene(o);
}

// Position error (m) and the biases' errors of a state against the truth.
struct StateError {
  double position_m = 0.0;
  double gyro_bias = 0.0;
  double accel_bias = 0.0;
};
StateError ErrorOf(const State& estimate, const State& truth) {
  return {(estimate.world_T_imu.t - truth.world_T_imu.t).norm(),
          (estimate.biases.gyro_radps - truth.biases.gyro_radps).norm(),
          (estimate.biases.accel_mps2 - truth.biases.accel_mps2).norm()};
}

struct RunResult {
  std::vector<State> newest;              // the newest state after each frame
  std::vector<Mat15<double>> covariance;  // its covariance, when computed
  double landmark_rms_m = 0.0;
  int failed_updates = 0;
  std::uint64_t allocations = 0;
};

template <int K, int P>
RunResult RunFilter(const InertialScene& s, SwfMode mode, int covariance_every) {
  using Filter = SlidingWindowFilter<Model, K, 200, 200, P>;
  auto swf = std::make_unique<Filter>();
  SwfOptions options;
  options.mode = mode;
  EXPECT_EQ(swf->Configure(s.model, options), core::Status::kOk);
  // Start: the true pose and velocity known to a few cm, biases unknown (zero) with the
  // datasheet's turn-on sigmas.
  State start = s.truth[0];
  start.biases = ImuBiases<double>{};
  Vec15<double> sigma;
  sigma << Vec3<double>::Constant(0.05), Vec3<double>::Constant(0.002),
      Vec3<double>::Constant(0.05), Vec3<double>::Constant(0.01), Vec3<double>::Constant(0.1);
  EXPECT_EQ(swf->AddFirstPose(start, Mat15<double>(sigma.cwiseAbs2().asDiagonal())),
            core::Status::kOk);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / s.options.sigma_px;
  RunResult result;
  result.newest.reserve(s.truth.size());
  result.covariance.reserve(s.truth.size());
  Pim pim;
  Mat15<double> q_sqrt;
  swf::testing::AllocationScope scope;
  for (std::size_t j = 0; j < s.truth.size(); ++j) {
    if (j > 0) {
      // Integrated at the current bias estimate, so the first-order correction stays small.
      EXPECT_TRUE(testing::PreintegrateFrame(s, j, swf->NewestPose().biases, &pim, &q_sqrt));
      EXPECT_EQ(swf->AddPoseWithMotion(pim, q_sqrt), core::Status::kOk);
    }
    for (const auto& [id, z] : s.obs[j]) (void)swf->AddObservation(id, z, r_sqrt);
    const core::Status status = swf->Update();
    result.failed_updates +=
        status == core::Status::kOk || status == core::Status::kNotConverged ? 0 : 1;
    result.newest.push_back(swf->NewestPose());
    // Every covariance_every frames and at the last (0: never).
    const bool last = j + 1 == s.truth.size();
    if (covariance_every > 0 && (last || j % covariance_every == 0) &&
        swf->ComputeCovariances() == core::Status::kOk)
      result.covariance.push_back(swf->NewestStateCovariance());
  }
  result.allocations = scope.Count();
  double sum = 0.0;
  int n = 0;
  swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& position, int) {
    sum += (position - s.landmarks[static_cast<std::size_t>(id)]).squaredNorm();
    ++n;
  });
  result.landmark_rms_m = n > 0 ? std::sqrt(sum / n) : 1e9;
  return result;
}

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

TEST(InertialSwf, BiasesConvergeAndTheWindowStaysNearBatch) {
  constexpr int kFrames = 40;
  const InertialScene scene = Scene(1, kFrames);
  const RunResult swf = RunFilter<5, 200>(scene, SwfMode::kSlidingWindow, 0);
  const RunResult batch = RunFilter<kFrames, 1>(scene, SwfMode::kBatch, 0);
  EXPECT_EQ(swf.failed_updates, 0);
  EXPECT_EQ(batch.failed_updates, 0);
  // Time to a stated accuracy, and staying there: gyro bias within 1.1 mrad/s and accel bias
  // within 0.035 m/s^2 (a fifth and a half of their initial errors, 5.4 mrad/s and 0.071 m/s^2).
  // What 4 s of this descent can tell: batch over the same data is no better (asserted below).
  auto settle_frame = [&](auto within) {
    int frame = -1;
    for (int j = kFrames - 1; j >= 0 && within(ErrorOf(swf.newest[j], scene.truth[j])); --j)
      frame = j;
    return frame;
  };
  const int gyro_frame = settle_frame([](const StateError& e) { return e.gyro_bias < 1.1e-3; });
  const int accel_frame = settle_frame([](const StateError& e) { return e.accel_bias < 0.035; });
  std::printf(
      "gyro bias within 1.1 mrad/s from %.1f s, accel bias within 0.035 m/s^2 from %.1f s\n",
      0.1 * gyro_frame, 0.1 * accel_frame);
  EXPECT_GE(gyro_frame, 0);
  EXPECT_LE(gyro_frame, 20);
  EXPECT_GE(accel_frame, 0);
  EXPECT_LE(accel_frame, 25);
  const StateError last = ErrorOf(swf.newest.back(), scene.truth.back());
  const StateError last_batch = ErrorOf(batch.newest.back(), scene.truth.back());
  // IMU-only dead reckoning from the same start (biases unknown: zero), for scale.
  State reckoned = scene.truth[0];
  reckoned.biases = ImuBiases<double>{};
  for (std::size_t j = 1; j < scene.truth.size(); ++j) {
    Pim pim;
    Mat15<double> unused;
    ASSERT_TRUE(testing::PreintegrateFrame(scene, j, reckoned.biases, &pim, &unused));
    reckoned = scene.model.Propagate(reckoned, pim);
  }
  const double reckoned_m = (reckoned.world_T_imu.t - scene.truth.back().world_T_imu.t).norm();
  std::printf(
      "final position error SWF(5) %.3f m, batch %.3f m, IMU alone %.3f m; landmark "
      "RMS %.3f / %.3f m\n",
      last.position_m, last_batch.position_m, reckoned_m, swf.landmark_rms_m, batch.landmark_rms_m);
  EXPECT_LT(last.position_m, 0.5 * reckoned_m);
  std::printf("final bias errors SWF(5) %.2f mrad/s %.3f m/s^2, batch %.2f mrad/s %.3f m/s^2\n",
              1e3 * last.gyro_bias, last.accel_bias, 1e3 * last_batch.gyro_bias,
              last_batch.accel_bias);
  EXPECT_LT(swf.landmark_rms_m, 1.3 * batch.landmark_rms_m);
  EXPECT_LT(last.position_m, 1.5 * last_batch.position_m + 0.02);
  EXPECT_LT(last.gyro_bias, 1.5 * last_batch.gyro_bias + 1e-4);
  EXPECT_LT(last.accel_bias, 1.5 * last_batch.accel_bias + 0.005);
}

TEST(InertialSwf, NeesOfTheWholeStateIsConsistent) {
  // Over independent scenes, the newest state's 15-dimensional error against its covariance.
  double nees_sum = 0.0;
  int n = 0;
  for (std::uint64_t seed = 11; seed < 21; ++seed) {
    const InertialScene scene = Scene(seed, 25);
    const RunResult r = RunFilter<5, 200>(scene, SwfMode::kSlidingWindow, 1000);
    ASSERT_EQ(r.covariance.size(), 2u);  // the first frame's and the last's
    Mat15<double> unused;
    const Vec15<double> e = Model::Difference(scene.truth.back(), r.newest.back(), &unused);
    nees_sum += e.dot(r.covariance.back().ldlt().solve(e));
    ++n;
  }
  const double nees = nees_sum / n;
  std::printf("mean NEES of the 15-dimensional state over %d runs: %.2f (expected 15)\n", n, nees);
  EXPECT_GT(nees, 15.0 / 3);
  EXPECT_LT(nees, 15.0 * 3);
}

TEST(InertialSwf, CameraBlindForTwoSecondsTheImuCarriesTheEstimate) {
  // Frames 20-39 (2 s) without a single measurement (black images): the process factor alone
  // carries the state, its covariance grows, and the filter tracks again from frame 40.
  InertialSceneOptions o;
  o.seed = 4;
  o.frames = 60;
  InertialScene scene = MakeInertialScene(o);
  constexpr int kBlindFrom = 20;
  constexpr int kBlindTo = 39;
  for (int j = kBlindFrom; j <= kBlindTo; ++j) scene.obs[static_cast<std::size_t>(j)].clear();
  const RunResult r = RunFilter<5, 300>(scene, SwfMode::kSlidingWindow, 1);
  ASSERT_EQ(r.failed_updates, 0);
  ASSERT_EQ(r.covariance.size(), scene.truth.size());
  auto error_m = [&](int j) {
    return ErrorOf(r.newest[static_cast<std::size_t>(j)], scene.truth[static_cast<std::size_t>(j)])
        .position_m;
  };
  auto sigma_m = [&](int j) {  // largest 1-sigma position axis of the filter's own covariance
    const Mat3<double> c = r.covariance[static_cast<std::size_t>(j)].topLeftCorner<3, 3>();
    return std::sqrt(Eigen::SelfAdjointEigenSolver<Mat3<double>>(c).eigenvalues()(2));
  };
  double worst_ratio = 0.0;
  for (int j = kBlindFrom; j <= kBlindTo; ++j)
    worst_ratio = std::max(worst_ratio, error_m(j) / sigma_m(j));
  std::printf(
      "blind 2 s: position error %.3f m -> %.3f m (1-sigma %.3f -> %.3f m, worst error / "
      "sigma %.2f); 2 s after the camera returns %.3f m (1-sigma %.3f m)\n",
      error_m(kBlindFrom - 1), error_m(kBlindTo), sigma_m(kBlindFrom - 1), sigma_m(kBlindTo),
      worst_ratio, error_m(59), sigma_m(59));
  // The stated bound: the error stays within 3 sigma of the filter's own covariance all along
  // the outage, and that covariance grows (the filter says it is less sure).
  EXPECT_LT(worst_ratio, 3.0);
  EXPECT_GT(sigma_m(kBlindTo), 1.5 * sigma_m(kBlindFrom - 1));
  // Re-acquired: measurements are fused again and the uncertainty shrinks from the outage's.
  EXPECT_LT(sigma_m(59), sigma_m(kBlindTo));
  EXPECT_LT(error_m(59), 3.0 * sigma_m(59));
}

TEST(InertialSwf, AllocatesNothingAndRepeatsBitForBit) {
  const InertialScene scene = Scene(2, 30);
  const RunResult a = RunFilter<5, 200>(scene, SwfMode::kSlidingWindow, 7);
  const RunResult b = RunFilter<5, 200>(scene, SwfMode::kSlidingWindow, 7);
  EXPECT_EQ(a.allocations, 0u);
  ASSERT_EQ(a.newest.size(), b.newest.size());
  for (std::size_t j = 0; j < a.newest.size(); ++j) {
    EXPECT_EQ(a.newest[j].world_T_imu.t, b.newest[j].world_T_imu.t);
    EXPECT_EQ(a.newest[j].biases.accel_mps2, b.newest[j].biases.accel_mps2);
  }
}

}  // namespace
}  // namespace swf::estimator
