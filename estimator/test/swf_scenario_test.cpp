// Scenario tests of the paper's experiments (scaled down): convergence against batch and the
// modes it compares. Host-only: they are too slow for the emulated aarch64 run.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <memory>
#include <vector>

#include "scene_runner.hpp"

namespace swf::estimator {
namespace {

using testing::InverseDepthSwf;
using testing::ModeOptions;
using testing::RunResult;
using testing::RunScene;
using testing::SceneOptions;
using testing::StereoSwf;
using testing::SyntheticScene;

// One filter instance and its options, run on a scene for its landmark RMS (m).
struct FilterRun {
  double (*rms_m)(const SyntheticScene& scene, const SwfOptions& options);
  SwfOptions options;
};
template <typename Filter>
double LandmarkRms(const SyntheticScene& scene, const SwfOptions& options) {
  return RunScene(std::make_unique<Filter>().get(), scene, options).rms_m;
}
template <typename Filter>
FilterRun RunOf(const SwfOptions& options) {
  return {&LandmarkRms<Filter>, options};
}
template <typename Filter>
FilterRun RunOf(SwfMode mode) {
  return RunOf<Filter>(ModeOptions(mode));
}

// Each run's landmark RMS averaged over the scenes `so` makes with each of `seeds`.
template <std::size_t N>
std::array<double, N> MeanRms(SceneOptions so, std::initializer_list<std::uint64_t> seeds,
                              const std::array<FilterRun, N>& runs) {
  std::array<double, N> mean{};
  for (std::uint64_t seed : seeds) {
    so.seed = seed;
    const SyntheticScene scene(so);
    for (std::size_t i = 0; i < N; ++i) {
      mean[i] += runs[i].rms_m(scene, runs[i].options) / static_cast<double>(seeds.size());
    }
  }
  return mean;
}

// Paper Fig. 13 setting (scaled): 150 landmarks tracked over a 100 m -> 41.5 m descent with an
// IMU-like relative-motion input. The test prints each filter's RMS error; the numbers, with and
// without first-estimate Jacobians, are in estimator/README.md.
TEST(SwfScenario, DescentWindowOfTenApproachesBatchAndBeatsVisualOdometry) {
  const auto [batch, swf3, swf5, swf10, vo5, vsdf5] = MeanRms<6>(
      SceneOptions{}, {1, 2},
      {RunOf<StereoSwf<40>>(SwfMode::kBatch), RunOf<StereoSwf<3>>(SwfMode::kSlidingWindow),
       RunOf<StereoSwf<5>>(SwfMode::kSlidingWindow), RunOf<StereoSwf<10>>(SwfMode::kSlidingWindow),
       RunOf<StereoSwf<5>>(SwfMode::kVisualOdometry), RunOf<StereoSwf<5>>(SwfMode::kVsdf)});
  std::printf(
      "descent landmark RMS (m): batch %.4f  SWF(3) %.4f  SWF(5) %.4f  SWF(10) %.4f  "
      "VO(5) %.4f  VSDF(5) %.4f\n",
      batch, swf3, swf5, swf10, vo5, vsdf5);
  EXPECT_LE(swf3, 1.10 * batch);
  EXPECT_LE(swf5, 1.10 * batch);
  EXPECT_LE(swf10, 1.10 * batch);
  EXPECT_GT(vo5, 1.5 * swf5);
  EXPECT_GT(swf3, 0.85 * batch);  // a window cannot beat the full smoother by more than noise
}

// Paper Fig. 15: sideways motion (~85% overlap), 2-frame window. With plain relinearization
// (the paper's SWF) early marginalization of world-point landmarks is far worse than batch, as
// the paper warns; inverse depth (its suggested remedy) halves that; first-estimate Jacobians
// remove most of it in either parameterization. The test prints the RMS of each variant; the
// numbers are in estimator/README.md and swf-eval's Fig. 15 section.
TEST(SwfScenario, SidewaysEarlyMarginalizationInverseDepthAndFirstEstimates) {
  SwfOptions plain = ModeOptions(SwfMode::kSlidingWindow);
  plain.first_estimate_jacobians = false;
  const SwfOptions fej = ModeOptions(SwfMode::kSlidingWindow);
  const auto [batch, xyz, inv, xyz_fej, inv_fej] = MeanRms<5>(
      testing::Fig15Sideways(), {1, 2},
      {RunOf<StereoSwf<40>>(SwfMode::kBatch), RunOf<StereoSwf<2>>(plain),
       RunOf<InverseDepthSwf<2>>(plain), RunOf<StereoSwf<2>>(fej), RunOf<InverseDepthSwf<2>>(fej)});
  std::printf(
      "sideways landmark RMS, mean of 2 seeds (m): batch %.4f; SWF(2) world point %.4f, inverse "
      "depth %.4f; with first-estimate Jacobians %.4f / %.4f\n",
      batch, xyz, inv, xyz_fej, inv_fej);
  EXPECT_GT(xyz, 2.0 * batch);
  EXPECT_LT(inv, 0.7 * xyz);
  EXPECT_LT(xyz_fej, 1.3 * batch);
  EXPECT_LT(inv_fej, 1.3 * batch);
}

// Paper section 4.2.4 on the static rig (every landmark seen in every frame): deleting instead
// of marginalizing stops convergence; the paper reports SWF error ~76% below VO.
TEST(SwfScenario, StaticRigVisualOdometryStopsConverging) {
  const auto [batch, swf3, vo3, vsdf3] = MeanRms<4>(
      testing::StaticRig(), {1, 2, 3},
      {RunOf<StereoSwf<40>>(SwfMode::kBatch), RunOf<StereoSwf<3>>(SwfMode::kSlidingWindow),
       RunOf<StereoSwf<3>>(SwfMode::kVisualOdometry), RunOf<StereoSwf<3>>(SwfMode::kVsdf)});
  std::printf(
      "static landmark RMS (m): batch %.4f  SWF(3) %.4f  VO(3) %.4f (SWF %.0f%% below VO)"
      "  VSDF(3) %.4f\n",
      batch, swf3, vo3, 100.0 * (1.0 - swf3 / vo3), vsdf3);
  EXPECT_LE(swf3, 1.05 * batch);
  EXPECT_GT(vo3, 2.0 * swf3);
}

// Paper Fig. 12: static cameras, 30 landmarks: squared error falls like 1/m.
TEST(SwfScenario, StaticCamerasConvergeLikeOneOverM) {
  std::vector<double> mse(40, 0.0);
  const int runs = 6;
  for (int seed = 1; seed <= runs; ++seed) {
    SceneOptions so = testing::StaticRig();
    so.seed = static_cast<std::uint64_t>(seed);
    const SyntheticScene scene(so);
    const RunResult r = RunScene(std::make_unique<StereoSwf<5>>().get(), scene,
                                 ModeOptions(SwfMode::kSlidingWindow));
    for (int m = 0; m < 40; ++m) mse[m] += r.mse_m2[m] / runs;
  }
  for (int m : {5, 10, 20, 40}) {
    const double ratio = mse[m - 1] * m / mse[0];  // 1 for exact 1/m convergence
    std::printf("static: m=%d  mse*m/mse(1) = %.3f\n", m, ratio);
    EXPECT_GT(ratio, 0.4) << m;
    EXPECT_LT(ratio, 2.0) << m;
  }
}

// The constant-velocity fallback on a descent at constant speed (no motion input at all).
TEST(SwfScenario, ConstantVelocityFallbackTracksASteadyDescent) {
  SceneOptions so;
  so.frames = 30;
  so.jitter_rad = 0.0;
  so.num_landmarks = 100;
  so.landmark_radius_m = 4.0;
  const SyntheticScene scene(so);
  auto swf = std::make_unique<StereoSwf<5>>();
  StereoModel<double> model;
  model.camera = scene.camera();
  ASSERT_EQ(swf->Configure(model, ModeOptions(SwfMode::kSlidingWindow)), core::Status::kOk);
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  q_sqrt.diagonal() << Vec3<double>::Constant(1 / 0.2), Vec3<double>::Constant(1 / 0.01);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / so.sigma_px;
  double worst = 0.0;
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    const auto& f = scene.frames()[j];
    // The first step has no velocity yet: give the filter the first relative motion.
    const Pose<double> first_motion = scene.frames()[0].truth.Inverse() * scene.frames()[1].truth;
    const core::Status added = j == 0   ? swf->AddPose(f.truth)
                               : j == 1 ? swf->AddPoseWithMotion(first_motion, q_sqrt)
                                        : swf->AddPoseConstantVelocity(q_sqrt);
    ASSERT_EQ(added, core::Status::kOk);
    for (const auto& o : f.obs) (void)swf->AddObservation(o.id, o.z, r_sqrt);
    const core::Status s = swf->Update();
    ASSERT_TRUE(s == core::Status::kOk || s == core::Status::kNotConverged) << j;
    worst = std::max(worst, (swf->NewestPose().t - f.truth.t).norm());
  }
  std::printf("constant velocity: worst position error %.3f m over %d frames\n", worst, so.frames);
  EXPECT_LT(worst, 5.0);  // a runaway goes beyond 20 m
}

// How the window is held (SwfOptions::hold_sightings, hold_depth_precision).
struct Hold {
  int sightings = 0;
  double depth_precision = 0.0;
};

struct HeldDescent {
  double nees = 0.0;        // newest pose, mean over frames 2-40 and the runs
  double x_error_m2 = 0.0;  // squared x error at the last frame, mean over the runs
  double mean_poses = 0.0;  // poses in the window after each Update
  int max_poses = 0;
};

// SWF(5) on `runs` descents of 40 frames over 40 landmarks, the newest pose's NEES each frame.
HeldDescent RunHeldDescent(SceneOptions so, int runs, const Hold& hold) {
  so.frames = 40;
  so.num_landmarks = 40;
  HeldDescent result;
  for (int seed = 1; seed <= runs; ++seed) {
    so.seed = static_cast<std::uint64_t>(seed);
    const SyntheticScene scene(so);
    SwfOptions options = ModeOptions(SwfMode::kSlidingWindow);
    options.window_size = 5;
    options.hold_sightings = hold.sightings;
    options.hold_depth_precision = hold.depth_precision;
    auto swf = std::make_unique<StereoSwf<40>>();
    const auto nees = [&](StereoSwf<40>* filter, std::size_t j) {
      ASSERT_EQ(filter->ComputeNewestCovariance(), core::Status::kOk);
      const Vec6<double> e = filter->NewestPose().LocalDifference(scene.frames()[j].truth);
      if (j > 0) result.nees += e.dot(filter->NewestPoseCovariance().ldlt().solve(e));
      if (j + 1 == scene.frames().size()) result.x_error_m2 += e[0] * e[0] / runs;
      result.mean_poses += filter->NumPoses() / static_cast<double>(runs * so.frames);
      result.max_poses = std::max(result.max_poses, filter->NumPoses());
    };
    const RunResult r = scene::RunScene(
        swf.get(), scene, options,
        scene::MotionInput(scene::MotionInput::kSigmaM, scene::MotionInput::kSigmaRad,
                           static_cast<std::uint64_t>(seed) + 1000),
        nees);
    EXPECT_EQ(r.configured, core::Status::kOk);
    EXPECT_EQ(r.rejected_poses, 0);
  }
  result.nees /= runs * (so.frames - 1);
  return result;
}

// The descent from 100 m (docs/integrity.md, "Consistency on the descent from 100 m"): a
// landmark's first estimate after five frames knows its depth to ~1.4 %, and the prior built at
// it holds information along the weakly observable tilt/sideways direction that the data do not
// (SWF(5) pose NEES ~2x its 6). Holding the oldest pose until its tracked landmarks have 25
// sightings (hold_sightings), or until their sightings know their depth to 0.5 %
// (hold_depth_precision), makes the same filter consistent, and more accurate, not less.
TEST(SwfScenario, DescentFromHundredMetresIsConsistentWhileYoungLandmarksHoldTheWindow) {
  constexpr int kRuns = 8;
  const SceneOptions so;
  const HeldDescent fixed = RunHeldDescent(so, kRuns, {});
  const HeldDescent count = RunHeldDescent(so, kRuns, {25, 0.0});
  const HeldDescent depth = RunHeldDescent(so, kRuns, {0, 0.005});
  // Two-sided 95 % band of an 8-run mean of a chi-square(6): chi2(48) / 8.
  const double lower = 30.755 / kRuns;
  const double upper = 69.023 / kRuns;
  std::printf(
      "descent from 100 m, SWF(5), %d runs: pose NEES %.2f fixed window, %.2f held by count, "
      "%.2f by depth precision (band [%.2f, %.2f]); RMS x error at the last frame %.3f / %.3f / "
      "%.3f m; window mean %.1f / %.1f / %.1f, at most %d / %d / %d poses\n",
      kRuns, fixed.nees, count.nees, depth.nees, lower, upper, std::sqrt(fixed.x_error_m2),
      std::sqrt(count.x_error_m2), std::sqrt(depth.x_error_m2), fixed.mean_poses, count.mean_poses,
      depth.mean_poses, fixed.max_poses, count.max_poses, depth.max_poses);
  EXPECT_GT(fixed.nees, upper);
  for (const HeldDescent* held : {&count, &depth}) {
    EXPECT_GT(held->nees, lower);
    EXPECT_LT(held->nees, upper);
    EXPECT_LE(held->x_error_m2, fixed.x_error_m2);
    EXPECT_GT(held->max_poses, fixed.max_poses);
  }
}

// At 30 m the disparity is 3.3x that at 100 m: five sightings already know a landmark's depth
// to 0.4 %. The depth criterion then holds nothing, while a sighting count holds the window
// there just as long as at 100 m.
TEST(SwfScenario, DepthPrecisionHoldsTheWindowOnlyWhereTheRangeNeedsIt) {
  SceneOptions so;
  so.start_altitude_m = 30.0;
  so.step_m = 0.5;
  constexpr int kRuns = 2;
  const HeldDescent count = RunHeldDescent(so, kRuns, {25, 0.0});
  const HeldDescent depth = RunHeldDescent(so, kRuns, {0, 0.005});
  std::printf(
      "descent from 30 m, SWF(5): window mean %.1f / %.1f, at most %d / %d poses held by count "
      "/ by depth precision\n",
      count.mean_poses, depth.mean_poses, count.max_poses, depth.max_poses);
  EXPECT_GT(count.max_poses, 10);
  EXPECT_LE(depth.max_poses, 7);
  EXPECT_LT(depth.mean_poses, count.mean_poses - 2.0);
}

// The held window stops at the capacity K (then the oldest pose goes whatever it sees), and
// batch mode, which never marginalizes, is the same filter with the option set or not.
TEST(SwfScenario, HeldWindowStopsAtTheCapacityAndLeavesBatchAlone) {
  SceneOptions so;
  so.frames = 20;
  so.num_landmarks = 40;
  so.seed = 3;
  const SyntheticScene scene(so);
  SwfOptions options = ModeOptions(SwfMode::kSlidingWindow);
  options.window_size = 2;
  // Never converged, by either criterion: only the capacity ends the hold.
  for (const Hold& hold : {Hold{1000, 0.0}, Hold{0, 1e-6}}) {
    options.hold_sightings = hold.sightings;
    options.hold_depth_precision = hold.depth_precision;
    int most = 0;
    int last = 0;
    int marginalized = 0;
    const RunResult held = scene::RunScene(
        std::make_unique<StereoSwf<5>>().get(), scene, options,
        scene::MotionInput(scene::MotionInput::kSigmaM, scene::MotionInput::kSigmaRad, 1003),
        [&](StereoSwf<5>* swf, std::size_t) {
          most = std::max(most, swf->NumPoses());
          last = swf->NumPoses();
          marginalized += swf->Summary().poses_marginalized;
        });
    EXPECT_EQ(held.failures, 0);
    EXPECT_EQ(held.rejected_poses, 0);
    EXPECT_EQ(most, 5) << hold.sightings << " " << hold.depth_precision;
    EXPECT_EQ(marginalized, so.frames - last);  // every pose held back was marginalized later
  }
  SwfOptions batch = ModeOptions(SwfMode::kBatch);
  const double plain = RunScene(std::make_unique<StereoSwf<40>>().get(), scene, batch).rms_m;
  batch.hold_sightings = 25;
  batch.hold_depth_precision = 0.005;
  EXPECT_EQ(RunScene(std::make_unique<StereoSwf<40>>().get(), scene, batch).rms_m, plain);
}

}  // namespace
}  // namespace swf::estimator
