// Integrity of the Sliding Window Filter: the measurement gates before and after fusion, the
// new-landmark checks, the restart prior, and the IntegrityMonitor's grading and protection
// levels, on synthetic scenes with exact truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "scene_runner.hpp"
#include "swf/estimator/integrity.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::estimator {
namespace {

using testing::ModeOptions;
using testing::SceneOptions;
using testing::SyntheticScene;
using Filter = SlidingWindowFilter<StereoModel<double>, 5, 400, 200, 200>;

TEST(Integrity, QuantilesMatchTables) {
  EXPECT_NEAR(ChiSquareQuantile(3, 0.95), 7.8147, 1e-4);
  EXPECT_NEAR(ChiSquareQuantile(3, 0.9999), 21.1075, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(6, 0.9999), 27.8563, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(1, 0.99), 6.6349, 1e-4);
  EXPECT_EQ(ChiSquareQuantile(3, 1.0), 0.0);
  EXPECT_NEAR(NormalUpperQuantile(0.0005), 3.2905, 1e-4);
}

SceneOptions Descent() {
  SceneOptions so;
  so.frames = 16;
  so.start_altitude_m = 60.0;
  so.num_landmarks = 80;
  so.landmark_radius_m = 6.0;
  so.seed = 4;
  return so;
}

const auto kExactMotion = [](int, Pose<double>*) {};

// Runs the scene with the motion input the truth gives and covariances every frame (as the
// flight pipeline does); `corrupt(frame, id, z)` may change a measurement before it is added,
// `corrupt_motion(frame, u)` the motion input.
template <typename Corrupt, typename CorruptMotion = decltype(kExactMotion)>
std::vector<SwfSummary> RunGated(Filter* swf, const SyntheticScene& scene,
                                 const SwfOptions& options, const Corrupt& corrupt,
                                 bool covariances = true,
                                 const CorruptMotion& corrupt_motion = kExactMotion) {
  StereoModel<double> model;
  model.camera = scene.camera();
  EXPECT_EQ(swf->Configure(model, options), core::Status::kOk);
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  // An IMU-grade motion input: 2 cm and 0.2 mrad per frame (0.8 px and 0.5 px at 60 m).
  q_sqrt.diagonal() << Vec3<double>::Constant(50.0), Vec3<double>::Constant(5000.0);
  Mat6<double> cv_sqrt = Mat6<double>::Zero();
  cv_sqrt.diagonal() << Vec3<double>::Constant(2.0), Vec3<double>::Constant(100.0);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options().sigma_px;
  std::vector<SwfSummary> summaries;
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    const testing::SceneFrame& f = scene.frames()[j];
    if (j == 0) {
      EXPECT_EQ(swf->AddPose(f.truth), core::Status::kOk);
    } else {
      Pose<double> u = scene.frames()[j - 1].truth.Inverse() * f.truth;
      corrupt_motion(static_cast<int>(j), &u);
      EXPECT_EQ(swf->AddPoseWithMotion(u, q_sqrt), core::Status::kOk);
      // The flight pipeline's fallback: constant velocity, 0.5 m and 10 mrad per frame.
      if (j >= 2) {
        const Pose<double> previous =
            scene.frames()[j - 2].truth.Inverse() * scene.frames()[j - 1].truth;
        EXPECT_EQ(swf->SetMotionFallback(previous, cv_sqrt), core::Status::kOk);
      }
    }
    for (const testing::SceneObservation& o : f.obs) {
      Vec3<double> z = o.z;
      corrupt(static_cast<int>(j), o.id, &z);
      (void)swf->AddObservation(o.id, z, r_sqrt);
    }
    const core::Status s = swf->Update();
    EXPECT_TRUE(s == core::Status::kOk || s == core::Status::kNotConverged);
    if (covariances) {
      EXPECT_EQ(swf->ComputeCovariances(), core::Status::kOk);
    }
    summaries.push_back(swf->Summary());
  }
  return summaries;
}

const auto kClean = [](int, std::int64_t, Vec3<double>*) {};

// A look-alike: one known landmark's measurement lands 25 px along the row (same disparity) in
// frame 10. The prediction gate refuses it; the estimate stays where the clean run's is (it
// lacks one true measurement), closer than without the gate.
TEST(Integrity, PredictionGateRefusesALookAlike) {
  const SyntheticScene scene(Descent());
  auto clean = std::make_unique<Filter>();
  auto planted = std::make_unique<Filter>();
  const auto clean_summaries =
      RunGated(clean.get(), scene, ModeOptions(SwfMode::kSlidingWindow), kClean);
  const std::int64_t victim = scene.frames()[10].obs[3].id;
  const auto look_alike = [&](int frame, std::int64_t id, Vec3<double>* z) {
    if (frame == 10 && id == victim) {
      (*z)[0] += 25.0;
      (*z)[1] += 25.0;
    }
  };
  const auto summaries =
      RunGated(planted.get(), scene, ModeOptions(SwfMode::kSlidingWindow), look_alike);
  EXPECT_GT(summaries[10].gate_checked, 20);
  EXPECT_EQ(summaries[10].gate_unchecked, 0);
  EXPECT_EQ(summaries[10].measurements_gated, 1);
  EXPECT_EQ(clean_summaries[10].measurements_gated, 0);
  EXPECT_FALSE(summaries[10].gate_suspended);
  const double gated_shift_m = (planted->NewestPose().t - clean->NewestPose().t).norm();
  EXPECT_LT(gated_shift_m, 1e-4);
  // Without the gate the look-alike is fused (Huber only) and moves the estimate.
  SwfOptions off = ModeOptions(SwfMode::kSlidingWindow);
  off.gate_probability = 0.0;
  auto ungated = std::make_unique<Filter>();
  const auto ungated_summaries = RunGated(ungated.get(), scene, off, look_alike);
  EXPECT_EQ(ungated_summaries[10].measurements_gated, 0);
  EXPECT_GT((ungated->NewestPose().t - clean->NewestPose().t).norm(), 3.0 * gated_shift_m);
}

// A motion-input glitch of 1 m (50 sigma) in frame 10, against a frame full of tracks: the
// motion gate fails, the images overrule the input (constant velocity takes its place), and the
// estimate stays consistent with its covariance; fused, the glitch makes it overconfident. No
// clean frame fails the gate.
TEST(Integrity, MotionGateLetsTheImagesOverruleAGlitch) {
  const SyntheticScene scene(Descent());
  // The glitch enters frame 10; frame 10's estimate and covariance are read when frame 11's
  // motion is made: the squared Mahalanobis distance of its position error.
  const auto run = [&](const SwfOptions& options, bool with_glitch, double* nees) {
    auto swf = std::make_unique<Filter>();
    const auto motion = [&](int frame, Pose<double>* u) {
      if (frame == 10 && with_glitch) u->t += Vec3<double>(1.0, 0.0, 0.0);
      if (frame != 11) return;
      const Vec3<double> e = swf->NewestPose().t - scene.frames()[10].truth.t;
      *nees = e.dot(swf->NewestPoseCovariance().topLeftCorner<3, 3>().ldlt().solve(e));
    };
    return RunGated(swf.get(), scene, options, kClean, true, motion);
  };
  SwfOptions options = ModeOptions(SwfMode::kSlidingWindow);
  options.motion_gate_min_inliers = 10;
  double clean_nees = 0.0;
  for (const SwfSummary& s : run(options, false, &clean_nees)) EXPECT_FALSE(s.motion_gate_failed);
  double overruled_nees = 0.0;
  const auto overruled = run(options, true, &overruled_nees);
  EXPECT_TRUE(overruled[10].motion_gate_failed);
  EXPECT_TRUE(overruled[10].motion_overruled);
  EXPECT_GT(overruled[10].motion_chi2, 100.0);
  // The same glitch with too few tracks to overrule it: reported, not overruled, and fused.
  options.motion_gate_min_inliers = 100000;
  double fused_nees = 0.0;
  const auto fused = run(options, true, &fused_nees);
  EXPECT_TRUE(fused[10].motion_gate_failed);
  EXPECT_FALSE(fused[10].motion_overruled);
  // Overruled, the estimate is as consistent with its covariance as the clean one (chi-square
  // 3 dof, p = 0.999); fused, the glitch makes it overconfident.
  EXPECT_LT(clean_nees, 16.27);
  EXPECT_LT(overruled_nees, 16.27);
  EXPECT_GT(fused_nees, 16.27);
  std::printf("frame 10 position NEES: clean %.2f, glitch overruled %.2f, glitch fused %.2f\n",
              clean_nees, overruled_nees, fused_nees);
  // The overrule needs the distance beyond motion_overrule_factor gates: a failure closer than
  // that is reported and the input kept (the visual fit may be the biased one).
  options.motion_gate_min_inliers = 10;
  const double gate = ChiSquareQuantile(6, options.gate_probability);
  options.motion_overrule_factor = 2.0 * overruled[10].motion_chi2 / gate;
  ASSERT_EQ(options.Validate(), core::Status::kOk);
  double kept_nees = 0.0;
  const auto kept = run(options, true, &kept_nees);
  EXPECT_TRUE(kept[10].motion_gate_failed);
  EXPECT_FALSE(kept[10].motion_overruled);
  options.motion_overrule_factor = 0.5;  // inside the gate itself: meaningless
  EXPECT_EQ(options.Validate(), core::Status::kInvalidArgument);
}

// A landmark that moves (a dust plume, a shadow edge): consistent across frames, so no single
// measurement looks wrong before fusion without covariances, but its residuals stay above the
// gate after the solve. It is removed whole, and counted.
TEST(Integrity, ResidualGateRemovesAMovingLandmark) {
  const SyntheticScene scene(Descent());
  const std::int64_t mover = scene.frames()[0].obs[0].id;
  const auto drift = [&](int frame, std::int64_t id, Vec3<double>* z) {
    if (id == mover) {
      (*z)[0] += 3.0 * frame;  // 3 px more per frame, both images: a point sliding sideways
      (*z)[1] += 3.0 * frame;
    }
  };
  auto swf = std::make_unique<Filter>();
  const auto summaries = RunGated(swf.get(), scene, ModeOptions(SwfMode::kSlidingWindow), drift,
                                  /*covariances=*/false);
  int rejected = 0;
  int unchecked = 0;
  for (const SwfSummary& s : summaries) {
    rejected += s.landmarks_rejected + s.measurements_rejected;
    unchecked += s.gate_unchecked;
  }
  EXPECT_GT(unchecked, 0);  // no covariances: the prediction gate could not test
  EXPECT_GT(rejected, 0);
  Vec3<double> p;
  EXPECT_FALSE(swf->GetLandmark(mover, &p) && (p - scene.landmarks()[mover]).norm() < 1e-3);
  EXPECT_LT((swf->NewestPose().t - scene.frames().back().truth.t).norm(), 0.5);
}

// Every measurement of frame 10 shifted 30 px: the data and the prediction disagree wholesale.
// A uniform shift is what a rotation of 30 px / f = 13 mrad looks like, over ten times the
// 0.2 mrad the motion input allows. With the motion gate the images' fit overrules the input
// (reported); without it the measurement gate stands down (keeps them, flags) rather than
// silently coasting on the prediction.
TEST(Integrity, WholesaleDisagreementIsReported) {
  const SyntheticScene scene(Descent());
  const auto shift = [](int frame, std::int64_t, Vec3<double>* z) {
    if (frame == 10) {
      (*z)[0] += 30.0;
      (*z)[1] += 30.0;
    }
  };
  auto swf = std::make_unique<Filter>();
  const auto summaries = RunGated(swf.get(), scene, ModeOptions(SwfMode::kSlidingWindow), shift);
  EXPECT_TRUE(summaries[10].motion_gate_failed);
  EXPECT_TRUE(summaries[10].motion_overruled);
  EXPECT_EQ(summaries[10].measurements_gated, 0);
  EXPECT_GT(summaries[10].newest_pose_step_rad, 0.002);
  SwfOptions no_motion_gate = ModeOptions(SwfMode::kSlidingWindow);
  no_motion_gate.motion_gate_min_inliers = 100000;
  auto plain = std::make_unique<Filter>();
  const auto plain_summaries = RunGated(plain.get(), scene, no_motion_gate, shift);
  EXPECT_TRUE(plain_summaries[10].motion_gate_failed);
  EXPECT_FALSE(plain_summaries[10].motion_overruled);
  EXPECT_TRUE(plain_summaries[10].gate_suspended);
  EXPECT_EQ(plain_summaries[10].measurements_gated, 0);
  EXPECT_NE(plain->FaultBits() & kFaultGateSuspended, 0u);
  EXPECT_GT(plain_summaries[10].newest_pose_step_rad, 0.002);
}

TEST(Integrity, NewLandmarksNeedAGoodTriangulation) {
  StereoModel<double> model;
  model.camera = testing::EdlRig();
  SwfOptions options = ModeOptions(SwfMode::kSlidingWindow);
  options.max_init_sigma_m = 2.0;
  auto swf = std::make_unique<Filter>();
  ASSERT_EQ(swf->Configure(model, options), core::Status::kOk);
  Pose<double> start;
  start.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  start.t = Vec3<double>(0, 0, 50);
  ASSERT_EQ(swf->AddPose(start), core::Status::kOk);
  const Mat3<double> r = Mat3<double>::Identity() * 2.0;  // 0.5 px
  // Swapped images: negative disparity.
  EXPECT_EQ(swf->AddObservation(1, Vec3<double>(480, 500, 300), r), core::Status::kInvalidArgument);
  // 20 px of disparity at f = 2309 px, b = 1 m: 115 m away, depth sigma ~4 m > 2 m.
  EXPECT_EQ(swf->AddObservation(2, Vec3<double>(500, 480, 300), r), core::Status::kInvalidArgument);
  // 200 px: 11.5 m, sigma 0.04 m.
  EXPECT_EQ(swf->AddObservation(3, Vec3<double>(500, 300, 300), r), core::Status::kOk);
  EXPECT_EQ(swf->Update(), core::Status::kOk);
  EXPECT_EQ(swf->Summary().new_landmarks_refused, 2);
}

TEST(Integrity, RestartPriorCarriesItsCovariance) {
  StereoModel<double> model;
  model.camera = testing::EdlRig();
  auto swf = std::make_unique<Filter>();
  ASSERT_EQ(swf->Configure(model, ModeOptions(SwfMode::kSlidingWindow)), core::Status::kOk);
  Mat6<double> cov = Mat6<double>::Zero();
  cov.diagonal() << 4.0, 1.0, 0.25, 1e-4, 1e-4, 4e-4;
  Pose<double> start;
  start.t = Vec3<double>(1, 2, 3);
  EXPECT_EQ(swf->AddFirstPose(start, -cov), core::Status::kInvalidArgument);
  ASSERT_EQ(swf->AddFirstPose(start, cov), core::Status::kOk);
  EXPECT_EQ(swf->AddFirstPose(start, cov), core::Status::kInvalidArgument);
  ASSERT_EQ(swf->Update(), core::Status::kOk);
  ASSERT_EQ(swf->ComputeCovariances(), core::Status::kOk);
  EXPECT_LT((swf->NewestPoseCovariance() - cov).norm(), 1e-9);
}

TEST(Integrity, GatedFramesAllocateNothing) {
  const SyntheticScene scene(Descent());
  auto swf = std::make_unique<Filter>();
  std::vector<SwfSummary> warm =
      RunGated(swf.get(), scene, ModeOptions(SwfMode::kSlidingWindow), kClean);
  ASSERT_FALSE(warm.empty());
  std::uint64_t count = 0;
  {
    const auto plant = [](int frame, std::int64_t id, Vec3<double>* z) {
      if (frame > 3 && id % 7 == 0) (*z)[0] += 25.0;
    };
    StereoModel<double> model;
    model.camera = scene.camera();
    ASSERT_EQ(swf->Configure(model, ModeOptions(SwfMode::kSlidingWindow)), core::Status::kOk);
    Mat6<double> q_sqrt = Mat6<double>::Identity() * 10.0;
    const Mat3<double> r_sqrt = Mat3<double>::Identity() * 2.0;
    int gated = 0;
    swf::testing::AllocationScope scope;
    for (std::size_t j = 0; j < scene.frames().size(); ++j) {
      const auto& f = scene.frames()[j];
      (void)(j == 0
                 ? swf->AddPose(f.truth)
                 : swf->AddPoseWithMotion(scene.frames()[j - 1].truth.Inverse() * f.truth, q_sqrt));
      for (const auto& o : f.obs) {
        Vec3<double> z = o.z;
        plant(static_cast<int>(j), o.id, &z);
        (void)swf->AddObservation(o.id, z, r_sqrt);
      }
      (void)swf->Update();
      (void)swf->ComputeCovariances();
      gated += swf->Summary().measurements_gated + swf->Summary().measurements_rejected;
    }
    count = scope.Count();
    EXPECT_GT(gated, 0);
  }
  EXPECT_EQ(count, 0u);
}

// ---- IntegrityMonitor ----------------------------------------------------------------------

IntegrityEvidence Healthy() {
  IntegrityEvidence e;
  e.has_motion_input = true;
  e.num_measurements = 100;
  e.num_inliers = 98;
  e.tracked_measurements = 60;
  e.tracked_inliers = 59;
  e.inlier_sigma = 1.0;
  e.has_covariance = true;
  e.covariance.diagonal() << 1.0, 4.0, 9.0, 1e-6, 1e-6, 1e-6;
  e.image_spread_px = 100.0;
  e.median_disparity_px = 20.0;
  return e;
}

TEST(IntegrityMonitor, ProtectionLevelsFromTheCovariance) {
  IntegrityMonitor m;
  ASSERT_EQ(m.Configure(IntegrityOptions{}), core::Status::kOk);
  const IntegrityReport r = m.Assess(Healthy());
  EXPECT_EQ(r.status, NavIntegrity::kValid);
  EXPECT_EQ(r.flags, 0u);
  // alpha = 1e-3: k_v = 3.2905 on sigma_z = 3; k_h = sqrt(-2 ln 1e-3) = 3.7169 on the major
  // horizontal sigma 2.
  EXPECT_NEAR(r.vpl_m, 3.2905 * 3.0, 1e-3);
  EXPECT_NEAR(r.hpl_m, 3.7169 * 2.0, 1e-3);
  // Residuals twice their model: the levels grow with them, and the frame is DEGRADED.
  IntegrityEvidence noisy = Healthy();
  noisy.inlier_sigma = 3.5;
  const IntegrityReport n = m.Assess(noisy);
  EXPECT_EQ(n.status, NavIntegrity::kDegraded);
  EXPECT_NE(n.flags & kFlagResidualsHigh, 0u);
  EXPECT_NEAR(n.vpl_m, 3.5 * r.vpl_m, 1e-9);
  IntegrityOptions bad;
  bad.integrity_risk = 0.0;
  EXPECT_EQ(m.Configure(bad), core::Status::kInvalidArgument);
}

TEST(IntegrityMonitor, GradesEachCheck) {
  IntegrityMonitor m;
  ASSERT_EQ(m.Configure(IntegrityOptions{}), core::Status::kOk);
  IntegrityEvidence few = Healthy();
  few.tracked_inliers = 3;
  few.tracked_measurements = 3;
  EXPECT_EQ(m.Assess(Healthy()).status, NavIntegrity::kValid);
  const IntegrityReport lost = m.Assess(few);
  EXPECT_EQ(lost.status, NavIntegrity::kInvalid);
  EXPECT_NE(lost.flags & kFlagTrackLoss, 0u);  // 60 tracks to 3 at once
  few.tracked_inliers = 15;
  few.tracked_measurements = 15;
  EXPECT_EQ(m.Assess(few).status, NavIntegrity::kDegraded);
  IntegrityEvidence gated = Healthy();
  gated.rejected_measurements = 20;  // of 80 offered
  EXPECT_NE(m.Assess(gated).flags & kFlagMeasurementsRejected, 0u);
  IntegrityEvidence spun = Healthy();
  spun.covariance(5, 5) = 0.04;  // 0.2 rad
  EXPECT_NE(m.Assess(spun).flags & kFlagCovarianceLarge, 0u);
  IntegrityEvidence line = Healthy();
  line.image_spread_px = 2.0;
  EXPECT_NE(m.Assess(line).flags & kFlagDegenerateGeometry, 0u);
  IntegrityEvidence far = Healthy();
  far.median_disparity_px = 0.3;
  EXPECT_EQ(m.Assess(far).status, NavIntegrity::kDegraded);
  IntegrityEvidence fast = Healthy();
  fast.velocity_world = Vec3<double>(0, 0, 1e4);
  const IntegrityReport f = m.Assess(fast);
  EXPECT_EQ(f.status, NavIntegrity::kInvalid);
  EXPECT_TRUE(f.restart);
  IntegrityEvidence nan_cov = Healthy();
  nan_cov.covariance(0, 0) = std::nan("");
  const IntegrityReport c = m.Assess(nan_cov);
  EXPECT_EQ(c.status, NavIntegrity::kInvalid);
  EXPECT_EQ(c.hpl_m, 0.0);
  IntegrityEvidence failed = Healthy();
  failed.update_status = core::Status::kNumericalFailure;
  EXPECT_EQ(m.Assess(failed).status, NavIntegrity::kInvalid);
  // After those anomalies the output stays DEGRADED (recovering) for recovery_frames.
  EXPECT_NE(m.Assess(Healthy()).flags & kFlagRecovering, 0u);
  // No motion input is reported, not degrading by itself.
  IntegrityMonitor fresh;
  ASSERT_EQ(fresh.Configure(IntegrityOptions{}), core::Status::kOk);
  IntegrityEvidence blind = Healthy();
  blind.has_motion_input = false;
  const IntegrityReport b = fresh.Assess(blind);
  EXPECT_EQ(b.status, NavIntegrity::kValid);
  EXPECT_NE(b.flags & kFlagNoMotionInput, 0u);
  EXPECT_GT(m.FlagCount(3), 0);  // kFlagTooFewTracks was counted
}

// Divergence: residuals high two frames running (or high with a large step) -> INVALID and a
// restart; after the restart DEGRADED (recovering) for recovery_frames, then VALID.
TEST(IntegrityMonitor, DetectsDivergenceAndRecovers) {
  IntegrityMonitor m;
  IntegrityOptions o;
  o.recovery_frames = 3;
  ASSERT_EQ(m.Configure(o), core::Status::kOk);
  EXPECT_EQ(m.Assess(Healthy()).status, NavIntegrity::kValid);
  IntegrityEvidence high = Healthy();
  high.inlier_sigma = 8.0;
  const IntegrityReport first = m.Assess(high);
  EXPECT_EQ(first.status, NavIntegrity::kDegraded);
  EXPECT_NE(first.flags & kFlagResidualJump, 0u);
  EXPECT_FALSE(first.restart);
  const IntegrityReport second = m.Assess(high);
  EXPECT_EQ(second.status, NavIntegrity::kInvalid);
  EXPECT_TRUE(second.restart);
  m.NoteRestart();
  for (int k = 0; k < 3; ++k) {
    const IntegrityReport r = m.Assess(Healthy());
    EXPECT_EQ(r.status, NavIntegrity::kDegraded) << k;
    EXPECT_NE(r.flags & kFlagRecovering, 0u);
  }
  EXPECT_EQ(m.Assess(Healthy()).status, NavIntegrity::kValid);
  EXPECT_EQ(m.Restarts(), 1);
  // A large step with high residuals is divergence at once.
  IntegrityEvidence jump = high;
  jump.step_m = 20.0;
  EXPECT_TRUE(m.Assess(jump).restart);
}

}  // namespace
}  // namespace swf::estimator
