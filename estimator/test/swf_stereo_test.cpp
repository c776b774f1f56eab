// The flight configuration of the Sliding Window Filter (stereo measurements, SE(3) poses) on
// synthetic scenes with exact truth: Jacobians, convergence against batch, the modes the paper
// compares, robustness, bad input, allocation-freedom and determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "scene_runner.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::estimator {
namespace {

using testing::InverseDepthSwf;
using testing::ModeOptions;
using testing::RunScene;
using testing::SceneOptions;
using testing::StereoSwf;
using testing::SyntheticScene;

// The default descent (SceneOptions) shortened to `frames` frames with `landmarks` landmarks.
SyntheticScene StereoDescent(int frames, int landmarks) {
  SceneOptions so;
  so.frames = frames;
  so.num_landmarks = landmarks;
  return SyntheticScene(so);
}

// ---- Jacobians against central differences ----------------------------------------------

// Central differences of predict(pose, params, &z) against the analytic pose (3x6) and
// parameter (3x3) Jacobians. one_sided_last: difference the last parameter forward only (rho at
// zero, where the backward side is not defined).
template <typename Predict>
void ExpectJacobiansMatchNumeric(const Predict& predict, const Pose<double>& pose,
                                 const Vec3<double>& params, const Mat36<double>& jp,
                                 const Mat3<double>& jl, double h, bool one_sided_last = false) {
  Vec3<double> z;
  ASSERT_TRUE(predict(pose, params, &z));
  for (int k = 0; k < 9; ++k) {
    const bool pose_column = k < 6;
    Vec6<double> dp = Vec6<double>::Zero();
    Vec3<double> dl = Vec3<double>::Zero();
    if (pose_column) {
      dp[k] = h;
    } else {
      dl[k - 6] = h;
    }
    const Vec3<double> column = pose_column ? Vec3<double>(jp.col(k)) : Vec3<double>(jl.col(k - 6));
    Vec3<double> zp;
    Vec3<double> zm;
    ASSERT_TRUE(predict(pose.Retract(dp), params + dl, &zp)) << k;
    if (one_sided_last && k == 8) {
      EXPECT_LT(((zp - z) / h - column).norm(), 1e-3 * (1 + column.norm())) << k;
      continue;
    }
    ASSERT_TRUE(predict(pose.Retract(-dp), params - dl, &zm)) << k;
    EXPECT_LT(((zp - zm) / (2 * h) - column).norm(), 1e-4 * (1 + column.norm())) << k;
  }
}

TEST(StereoModel, MeasurementJacobiansMatchNumeric) {
  StereoModel<double> model;
  model.camera = testing::EdlRig();
  const Pose<double> pose{ExpSO3<double>(Vec3<double>(3.0, 0.1, -0.05)), Vec3<double>(1, 2, 60)};
  const Vec3<double> l(3.0, -1.0, 0.5);
  Vec3<double> z;
  Mat36<double> jp;
  Mat3<double> jl;
  ASSERT_TRUE(model.Predict(pose, l, &z, &jp, &jl));
  ExpectJacobiansMatchNumeric(
      [&](const Pose<double>& p, const Vec3<double>& m, Vec3<double>* out) {
        return model.Predict(p, m, out, nullptr, nullptr);
      },
      pose, l, jp, jl, 1e-6);
  // Behind the camera: no prediction.
  EXPECT_FALSE(model.Predict(pose, Vec3<double>(1, 2, 80), &z, &jp, &jl));
}

// Anchored inverse depth: Jacobians of the measurement (pose and parameters) and of the world
// position, including a point at infinity (rho = 0), which is still measurable.
TEST(InverseDepthStereoModel, JacobiansMatchNumeric) {
  InverseDepthStereoModel<double> model;
  model.camera = testing::EdlRig();
  const Pose<double> anchor{ExpSO3<double>(Vec3<double>(3.1, 0.05, 0.02)), Vec3<double>(0, 1, 70)};
  const Pose<double> pose{ExpSO3<double>(Vec3<double>(3.0, 0.1, -0.05)), Vec3<double>(1, 2, 60)};
  for (const double rho : {1.0 / 65.0, 0.0}) {
    const Vec3<double> m(0.04, -0.02, rho);
    Vec3<double> z;
    Mat36<double> jp;
    Mat3<double> jl;
    ASSERT_TRUE(model.Predict(pose, anchor, m, &z, &jp, &jl));
    ExpectJacobiansMatchNumeric(
        [&](const Pose<double>& p, const Vec3<double>& params, Vec3<double>* out) {
          return model.Predict(p, anchor, params, out, nullptr, nullptr);
        },
        pose, m, jp, jl, 1e-7, rho == 0.0);
  }
  // The parameterization agrees with the world-point model, and so does its position Jacobian.
  const Vec3<double> m(0.04, -0.02, 1.0 / 65.0);
  Vec3<double> l;
  Mat3<double> jpos;
  ASSERT_TRUE(InverseDepthStereoModel<double>::LandmarkPosition(anchor, m, &l, &jpos));
  StereoModel<double> xyz;
  xyz.camera = model.camera;
  Vec3<double> z_xyz;
  Vec3<double> z_inv;
  ASSERT_TRUE(xyz.Predict(pose, l, &z_xyz, nullptr, nullptr));
  ASSERT_TRUE(model.Predict(pose, anchor, m, &z_inv, nullptr, nullptr));
  EXPECT_LT((z_xyz - z_inv).norm(), 1e-9);
  for (int k = 0; k < 3; ++k) {
    Vec3<double> d = Vec3<double>::Zero();
    d[k] = 1e-8;
    Vec3<double> lp;
    Vec3<double> lm;
    ASSERT_TRUE(InverseDepthStereoModel<double>::LandmarkPosition(anchor, m + d, &lp, nullptr));
    ASSERT_TRUE(InverseDepthStereoModel<double>::LandmarkPosition(anchor, m - d, &lm, nullptr));
    EXPECT_LT(((lp - lm) / 2e-8 - jpos.col(k)).norm(), 1e-5 * jpos.col(k).norm()) << k;
  }
  // Initialization inverts the measurement; beyond infinity there is no position to report.
  InverseDepthStereoModel<double>::LandmarkAnchor a;
  Vec3<double> m0;
  ASSERT_TRUE(model.InitLandmark(pose, z_inv, &a, &m0));
  ASSERT_TRUE(InverseDepthStereoModel<double>::LandmarkPosition(a, m0, &l, nullptr));
  Vec3<double> l_truth;
  ASSERT_TRUE(InverseDepthStereoModel<double>::LandmarkPosition(anchor, m, &l_truth, nullptr));
  EXPECT_LT((l - l_truth).norm(), 1e-9);
  EXPECT_FALSE(InverseDepthStereoModel<double>::LandmarkPosition(anchor, Vec3<double>(0, 0, -1e-3),
                                                                 &l, nullptr));
  EXPECT_FALSE(model.Predict(pose, anchor, Vec3<double>(0, 0, -1e-3), &z_inv, nullptr, nullptr));
}

TEST(StereoModel, ProcessJacobiansMatchNumeric) {
  StereoModel<double> model;
  const Pose<double> a{ExpSO3<double>(Vec3<double>(0.2, -0.3, 0.1)), Vec3<double>(1, 2, 3)};
  const Pose<double> u{ExpSO3<double>(Vec3<double>(0.05, 0.02, -0.04)), Vec3<double>(0.3, -0.1, 1)};
  const Pose<double> b =
      (a * u).Retract((Vec6<double>() << 0.1, -0.2, 0.05, 0.03, -0.02, 0.04).finished());
  Mat6<double> ja;
  Mat6<double> jb;
  model.ProcessResidual(a, b, u, &ja, &jb);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Vec6<double> d = Vec6<double>::Zero();
    d[k] = h;
    Mat6<double> unused1;
    Mat6<double> unused2;
    const Vec6<double> na = (model.ProcessResidual(a.Retract(d), b, u, &unused1, &unused2) -
                             model.ProcessResidual(a.Retract(-d), b, u, &unused1, &unused2)) /
                            (2 * h);
    const Vec6<double> nb = (model.ProcessResidual(a, b.Retract(d), u, &unused1, &unused2) -
                             model.ProcessResidual(a, b.Retract(-d), u, &unused1, &unused2)) /
                            (2 * h);
    EXPECT_LT((na - ja.col(k)).norm(), 1e-7) << k;
    EXPECT_LT((nb - jb.col(k)).norm(), 1e-7) << k;
  }
  Mat6<double> jd;
  const Vec6<double> delta = StereoModel<double>::Difference(a, b, &jd);
  for (int k = 0; k < 6; ++k) {
    Vec6<double> d = Vec6<double>::Zero();
    d[k] = h;
    Mat6<double> unused;
    const Vec6<double> n = (StereoModel<double>::Difference(a, b.Retract(d), &unused) -
                            StereoModel<double>::Difference(a, b.Retract(-d), &unused)) /
                           (2 * h);
    EXPECT_LT((n - jd.col(k)).norm(), 1e-7) << k;
  }
  EXPECT_LT((a.Retract(delta).Matrix() - b.Matrix()).norm(), 1e-12);
}

TEST(SwfStereo, HuberWeightingResistsGrossOutliers) {
  const SyntheticScene clean = StereoDescent(20, 60);
  SwfOptions robust = ModeOptions(SwfMode::kSlidingWindow);
  SwfOptions plain = robust;
  plain.robust = false;
  auto run = [](const SyntheticScene& scene, const SwfOptions& o) {
    return RunScene(std::make_unique<StereoSwf<5>>().get(), scene, o).rms_m;
  };
  // Corrupt a random 10% of the measurements by (+30, +30, +30) px: gross mismatches whose
  // pulls all point the same way (the hard case for a bounded-influence kernel). The error
  // varies a lot with which measurements are hit, so three outlier draws are summed.
  double e_robust = 0;
  double e_plain = 0;
  for (std::uint64_t seed : {42u, 43u, 44u}) {
    auto corrupted = clean;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (auto& f : corrupted.mutable_frames())
      for (auto& o : f.obs)
        if (unit(rng) < 0.1) o.z += Vec3<double>(30, 30, 30);
    const double r = run(corrupted, robust);
    const double p = run(corrupted, plain);
    std::printf("outliers, draw %d: robust %.4f plain %.4f\n", static_cast<int>(seed), r, p);
    e_robust += r;
    e_plain += p;
  }
  std::printf("outliers: clean %.4f, robust %.4f, plain %.4f (means)\n", run(clean, robust),
              e_robust / 3, e_plain / 3);
  // Measured (first-estimate Jacobians on): robust 3.16 m, plain 4.79 m, clean 0.49 m.
  EXPECT_LT(e_robust, 0.8 * e_plain);
}

// The summary says why the last solve stopped; only the converged reasons set `converged`, and
// a solve that runs out of iterations raises kFaultNotConverged.
TEST(SwfStereo, SummaryGivesTheTerminationReason) {
  const SyntheticScene scene = StereoDescent(8, 40);
  auto swf = std::make_unique<StereoSwf<5>>();
  EXPECT_EQ(swf->Summary().termination, SwfTermination::kNoSolve);
  (void)RunScene(swf.get(), scene, ModeOptions(SwfMode::kSlidingWindow));
  const SwfTermination normal = swf->Summary().termination;
  EXPECT_TRUE(normal == SwfTermination::kCostTolerance ||
              normal == SwfTermination::kStepTolerance || normal == SwfTermination::kNoDescent)
      << TerminationName(normal);
  EXPECT_TRUE(swf->Summary().Converged());

  // One iteration and no tolerance: the loop can only run out or find no descent.
  SwfOptions one = ModeOptions(SwfMode::kSlidingWindow);
  one.max_iterations = 1;
  one.relative_cost_tolerance = 0.0;
  one.step_tolerance = 0.0;
  (void)RunScene(swf.get(), scene, one);
  const SwfSummary& summary = swf->Summary();
  ASSERT_TRUE(summary.termination == SwfTermination::kMaxIterations ||
              summary.termination == SwfTermination::kNoDescent)
      << TerminationName(summary.termination);
  const bool ran_out = summary.termination == SwfTermination::kMaxIterations;
  EXPECT_EQ(summary.Converged(), !ran_out);
  EXPECT_EQ(summary.status == core::Status::kNotConverged, ran_out);
  if (ran_out) {
    EXPECT_NE(swf->FaultBits() & kFaultNotConverged, 0u);
  }
  EXPECT_STREQ(TerminationName(SwfTermination::kMaxIterations), "max iterations");
}

// A landmark initialized from a corrupted first stereo measurement. As a world point started
// far beyond the terrain, its later measurements barely constrain its depth (dh/dZ ~ 1/Z^2),
// Huber down-weights them and the landmark stays there. Two defences, measured here: inverse
// depth (the measurement is nearly linear in rho, so the inliers pull the landmark back) and
// refusing initial depths beyond what the scene can hold (max_init_depth_m; the scene is at most
// ~101 m away). The corruption is constructed, not drawn: which landmark a random draw turns
// into a far start depends on the last bits of the scene's noise, which differ between x86-64
// and AArch64 libm (a draw that sent one landmark 1e5 m away on one went unnoticed on the other).
//   far:  every 10th landmark's first sighting gets 0.05 px of disparity (~46 km away),
//   near: every 10th (offset 5) gets half its disparity (twice as far, still inside the gate).
TEST(SwfStereo, CorruptedFirstMeasurementsAreContained) {
  const SyntheticScene clean = StereoDescent(20, 60);
  const SwfOptions robust = ModeOptions(SwfMode::kSlidingWindow);
  const double e_clean = RunScene(std::make_unique<StereoSwf<5>>().get(), clean, robust).rms_m;
  auto corrupted = clean;
  std::vector<bool> seen(clean.landmarks().size(), false);
  int far = 0;
  int near = 0;
  for (auto& f : corrupted.mutable_frames())
    for (auto& o : f.obs) {
      if (seen[o.id]) continue;
      seen[o.id] = true;
      const double disparity = o.z[0] - o.z[1];
      if (o.id % 10 == 0) {
        o.z[1] = o.z[0] - 0.05;
        ++far;
      } else if (o.id % 10 == 5) {
        o.z[1] = o.z[0] - 0.5 * disparity;
        ++near;
      }
    }
  ASSERT_GT(far, 3);
  ASSERT_GT(near, 3);
  auto rms = [&](auto filter, double gate_m) {
    return RunScene(filter.get(), corrupted, robust, gate_m).rms_m;
  };
  const double e_xyz = rms(std::make_unique<StereoSwf<5>>(), 0.0);
  const double e_inv = rms(std::make_unique<InverseDepthSwf<5>>(), 0.0);
  const double e_xyz_gate = rms(std::make_unique<StereoSwf<5>>(), 300.0);
  const double e_inv_gate = rms(std::make_unique<InverseDepthSwf<5>>(), 300.0);
  std::printf(
      "corrupted first sightings (%d far, %d near): clean %.4f m, world point %.4g m, inverse "
      "depth %.4g m, with the 300 m gate %.4g / %.4g m\n",
      far, near, e_clean, e_xyz, e_inv, e_xyz_gate, e_inv_gate);
  // Measured (x86-64): clean 0.486 m; world point 2.5e6 m (the far starts drift further out),
  // inverse depth 0.75 m; gated 0.61 / 0.62 m. The near corruption is recovered by both.
  EXPECT_GT(e_xyz, 100.0);
  EXPECT_LT(e_inv, 2.0 * e_clean);
  EXPECT_LT(e_xyz_gate, 2.0 * e_clean);
  EXPECT_LT(e_inv_gate, 2.0 * e_clean);
}

TEST(SwfStereo, BadInputIsRefusedAndCounted) {
  auto swf = std::make_unique<SlidingWindowFilter<StereoModel<double>, 3, 4, 2, 4>>();
  StereoModel<double> model;
  model.camera = testing::EdlRig();
  SwfOptions bad;
  bad.max_iterations = 0;
  EXPECT_EQ(swf->Configure(model, bad), core::Status::kInvalidArgument);
  ASSERT_EQ(swf->Configure(model, ModeOptions(SwfMode::kSlidingWindow)), core::Status::kOk);
  const Mat3<double> r = Mat3<double>::Identity();
  EXPECT_EQ(swf->AddObservation(1, Vec3<double>(500, 480, 300), r), core::Status::kNotConfigured);
  EXPECT_EQ(swf->AddPoseConstantVelocity(Mat6<double>::Identity()), core::Status::kInvalidArgument);
  Pose<double> start;
  start.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  start.t = Vec3<double>(0, 0, 50);
  ASSERT_EQ(swf->AddPose(start), core::Status::kOk);
  EXPECT_EQ(swf->AddObservation(1, Vec3<double>(std::nan(""), 1, 1), r),
            core::Status::kInvalidArgument);
  EXPECT_EQ(swf->AddObservation(1, Vec3<double>(500, 510, 300), r), core::Status::kInvalidArgument);
  EXPECT_EQ(swf->AddObservation(1, Vec3<double>(500, 480, 300), r), core::Status::kOk);
  EXPECT_EQ(swf->AddObservation(1, Vec3<double>(500, 480, 300), r), core::Status::kInvalidArgument);
  EXPECT_EQ(swf->AddObservation(2, Vec3<double>(400, 380, 300), r), core::Status::kOk);
  EXPECT_EQ(swf->AddObservation(3, Vec3<double>(300, 280, 300), r), core::Status::kFull);
  EXPECT_NE(swf->FaultBits() & kFaultMeasurementCapacity, 0u);
  EXPECT_EQ(swf->Update(), core::Status::kOk);
}

// GIVEN a landmark seen from two poses WHEN the newest pose's measurement of it is replaced after
// the update (the front end's refinement in the loop) THEN the filter's cost (what the next
// solve minimizes) is evaluated with the new value; a landmark's first sighting, an unknown id, a
// non-finite value and an empty window are refused, and nothing else changes.
TEST(SwfStereo, ReplaceNewestObservationFeedsTheCost) {
  auto swf = std::make_unique<SlidingWindowFilter<StereoModel<double>, 3, 4, 4, 4>>();
  StereoModel<double> model;
  model.camera = testing::EdlRig();
  ASSERT_EQ(swf->Configure(model, ModeOptions(SwfMode::kSlidingWindow)), core::Status::kOk);
  const Mat3<double> r = Mat3<double>::Identity();
  EXPECT_EQ(swf->ReplaceNewestObservation(1, Vec3<double>(500, 480, 300)), core::Status::kEmpty);
  Pose<double> pose;
  pose.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  pose.t = Vec3<double>(0, 0, 50);
  ASSERT_EQ(swf->AddPose(pose), core::Status::kOk);
  ASSERT_EQ(swf->AddObservation(1, Vec3<double>(500, 480, 300), r), core::Status::kOk);
  ASSERT_EQ(swf->AddObservation(2, Vec3<double>(400, 370, 320), r), core::Status::kOk);
  ASSERT_EQ(swf->Update(), core::Status::kOk);
  EXPECT_EQ(swf->ReplaceNewestObservation(1, Vec3<double>(501, 481, 300)),
            core::Status::kInvalidArgument);  // the first sighting placed the landmark
  ASSERT_EQ(swf->AddPose(pose), core::Status::kOk);
  ASSERT_EQ(swf->AddObservation(1, Vec3<double>(500, 480, 300), r), core::Status::kOk);
  ASSERT_EQ(swf->AddObservation(2, Vec3<double>(400, 370, 320), r), core::Status::kOk);
  ASSERT_EQ(swf->Update(), core::Status::kOk);
  const double cost = swf->MeasurementCost();
  EXPECT_EQ(swf->ReplaceNewestObservation(1, Vec3<double>(500, 480, 300)), core::Status::kOk);
  EXPECT_EQ(swf->MeasurementCost(), cost);  // the same value: the same cost, bit for bit
  EXPECT_EQ(swf->ReplaceNewestObservation(7, Vec3<double>(500, 480, 300)), core::Status::kEmpty);
  EXPECT_EQ(swf->ReplaceNewestObservation(1, Vec3<double>(std::nan(""), 480, 300)),
            core::Status::kInvalidArgument);
  // Two pixels on u_left and u_right of the newest measurement: whitened residual 2 on each.
  EXPECT_EQ(swf->ReplaceNewestObservation(1, Vec3<double>(502, 482, 300)), core::Status::kOk);
  EXPECT_GT(swf->MeasurementCost(), cost + 1.0);
  EXPECT_EQ(swf->NumLandmarks(), 2);
}

// After Update() the covariances come from its last Gauss-Newton iteration's factor, at that
// iteration's linearization point (no factorization of their own): asked twice they have the same
// bits, and they are close to the covariance factorized at the final estimate, which the next
// call computes once the window's measurements changed (here: the newest measurement of a tracked
// landmark replaced by its own value, the same problem). Where the last iteration found no
// descent the state went back to its linearization point and the two are the same bits; where it
// took a converged step they differ (the reuse is real) by second-order terms: at most 0.21 % of
// the covariance's norm on this scene.
TEST(SwfStereo, CovariancesAfterUpdateAreTheLastIterationsNearTheFinalEstimates) {
  SceneOptions so;
  so.frames = 12;
  so.num_landmarks = 40;
  const SyntheticScene scene(so);
  auto swf = std::make_unique<StereoSwf<5>>();
  int unmoved = 0;
  int stepped = 0;
  int differed = 0;
  double worst = 0.0;
  const auto compare = [&](StereoSwf<5>* filter, std::size_t j) {
    if (j == 0) return;  // no tracked landmark yet
    ASSERT_EQ(filter->ComputeNewestCovariance(), core::Status::kOk);
    const Mat6<double> reused = filter->NewestPoseCovariance();
    ASSERT_EQ(filter->ComputeCovariances(), core::Status::kOk);
    EXPECT_TRUE(filter->NewestPoseCovariance() == reused) << "frame " << j;
    bool replaced = false;
    for (const scene::SceneObservation& o : scene.frames()[j].obs) {
      if (filter->ReplaceNewestObservation(o.id, o.z) == core::Status::kOk) {
        replaced = true;
        break;
      }
    }
    ASSERT_TRUE(replaced) << "frame " << j;
    ASSERT_EQ(filter->ComputeNewestCovariance(), core::Status::kOk);
    const Mat6<double> at_final = filter->NewestPoseCovariance();
    if (filter->Summary().termination == SwfTermination::kNoDescent) {
      ++unmoved;
      EXPECT_TRUE(reused == at_final) << "frame " << j;
      return;
    }
    ++stepped;
    differed += reused == at_final ? 0 : 1;
    worst = std::max(worst, (reused - at_final).norm() / at_final.norm());
  };
  (void)scene::RunScene(swf.get(), scene, ModeOptions(SwfMode::kSlidingWindow),
                        scene::MotionInput(scene::MotionInput::kSigmaM,
                                           scene::MotionInput::kSigmaRad, so.seed + 1000),
                        compare);
  EXPECT_EQ(unmoved + stepped, so.frames - 1);
  EXPECT_GT(unmoved, 0);
  EXPECT_GT(differed, 0);
  EXPECT_LT(worst, 0.01);
}

// Paper Fig. 14 load on a long sideways pass: ~20 measurements per frame, tracks ~10 frames.
SceneOptions LongPass(int frames) {
  SceneOptions so = swf::scene::Fig14Sideways();
  so.frames = frames;
  so.seed = 9;
  return so;
}

template <typename Filter>
std::uint64_t CountAllocations(const SyntheticScene& scene, SwfMode mode) {
  const auto swf = std::make_unique<Filter>();
  typename Filter::ModelType model;
  model.camera = scene.camera();
  EXPECT_EQ(swf->Configure(model, ModeOptions(mode)), core::Status::kOk);
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  q_sqrt.diagonal() << Vec3<double>::Constant(2.0), Vec3<double>::Constant(50.0);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options().sigma_px;
  // Relative motions as an IMU would give them, computed before counting starts.
  std::vector<Pose<double>> motion(scene.frames().size());
  for (std::size_t j = 1; j < motion.size(); ++j)
    motion[j] = scene.frames()[j - 1].truth.Inverse() * scene.frames()[j].truth;
  int bad = 0;
  swf::testing::AllocationScope scope;
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    const auto& f = scene.frames()[j];
    (void)(j == 0 ? swf->AddPose(f.truth) : swf->AddPoseWithMotion(motion[j], q_sqrt));
    for (const auto& o : f.obs) (void)swf->AddObservation(o.id, o.z, r_sqrt);
    const core::Status s = swf->Update();
    bad += (s == core::Status::kOk || s == core::Status::kNotConverged) ? 0 : 1;
    if (j % 50 == 0) (void)swf->ComputeCovariances();
  }
  const std::uint64_t count = scope.Count();
  EXPECT_EQ(bad, 0);
  return count;
}

TEST(SwfStereo, ZeroAllocationsOverAThousandFramesInEveryMode) {
  const SyntheticScene scene(LongPass(1000));
  double obs = 0;
  for (const auto& f : scene.frames()) obs += static_cast<double>(f.obs.size());
  std::printf("long pass: %.1f measurements per frame\n", obs / 1000.0);
  EXPECT_GT(obs / 1000.0, 15.0);
  using Stereo10 = SlidingWindowFilter<StereoModel<double>, 10, 400, 64, 96>;
  for (const SwfMode mode : {SwfMode::kSlidingWindow, SwfMode::kVisualOdometry, SwfMode::kVsdf}) {
    EXPECT_EQ(CountAllocations<Stereo10>(scene, mode), 0u) << static_cast<int>(mode);
  }
  EXPECT_EQ((CountAllocations<SlidingWindowFilter<StereoModel<double>, 1, 400, 64, 96>>(
                scene, SwfMode::kSlidingWindow)),
            0u);
  EXPECT_EQ(
      (CountAllocations<SlidingWindowFilter<InverseDepthStereoModel<double>, 10, 400, 64, 96>>(
          scene, SwfMode::kSlidingWindow)),
      0u);
  // Batch holds the whole sequence in its window, so it is bounded by K frames.
  const SyntheticScene short_pass(LongPass(60));
  EXPECT_EQ((CountAllocations<SlidingWindowFilter<StereoModel<double>, 60, 1000, 64, 1>>(
                short_pass, SwfMode::kBatch)),
            0u);
}

// Fig. 17's VSDF with only the diagonal elements of the Schur term (eq. 12 read literally) on a
// descent whose landmarks spread over the field of view, as the rendered descent's do: its first
// marginalization leaves the prior indefinite along the landmarks' lines of sight
// (Schur.VsdfScalarDiagonalLeavesAnOffAxisStereoLandmarkIndefiniteAlongItsRay) and the filter
// reports kFaultNotPositiveDefinite at that update, the fourth frame with a window of 3; the
// block-diagonal VSDF on the same scene, and the same reading on a 2 m disc (the measurement
// level's Fig. 17 landmarks, within 1.2 deg of the axis at 100 m), pass that marginalization.
TEST(SwfStereo, VsdfScalarDiagonalReportsTheIndefinitePriorAtItsFirstMarginalization) {
  const auto first_fault = [](double radius_m, bool scalar) {
    SceneOptions so;
    so.frames = 6;
    so.num_landmarks = 90;
    so.landmark_radius_m = radius_m;
    const SyntheticScene scene(so);
    auto swf = std::make_unique<StereoSwf<3>>();
    SwfOptions o = ModeOptions(SwfMode::kVsdf);
    o.vsdf_scalar_diagonal = scalar;
    int first = -1;
    (void)scene::RunScene(
        swf.get(), scene, o,
        scene::MotionInput(scene::MotionInput::kSigmaM, scene::MotionInput::kSigmaRad, 7),
        [&first](StereoSwf<3>* f, std::size_t j) {
          if (first < 0 && (f->FaultBits() & kFaultNotPositiveDefinite) != 0)
            first = static_cast<int>(j);
        });
    return first;
  };
  EXPECT_EQ(first_fault(15.0, true), 3);
  EXPECT_EQ(first_fault(15.0, false), -1);
  const int narrow = first_fault(2.0, true);
  EXPECT_TRUE(narrow == -1 || narrow > 3) << narrow;
}

// Numerical trouble is a counted, reported recovery: a poisoned state resets the filter.
TEST(SwfStereo, NonFiniteStateResetsAndReports) {
  auto swf = std::make_unique<StereoSwf<3>>();
  StereoModel<double> model;
  model.camera = testing::EdlRig();
  ASSERT_EQ(swf->Configure(model, ModeOptions(SwfMode::kSlidingWindow)), core::Status::kOk);
  Pose<double> start;
  start.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  start.t = Vec3<double>(0, 0, 50);
  ASSERT_EQ(swf->AddPose(start), core::Status::kOk);
  ASSERT_EQ(swf->AddObservation(1, Vec3<double>(500, 480, 300), Mat3<double>::Identity()),
            core::Status::kOk);
  // A motion input with a NaN poisons the predicted pose.
  Pose<double> poisoned;
  poisoned.t = Vec3<double>(std::nan(""), 0, 0);
  ASSERT_EQ(swf->Update(), core::Status::kOk);
  ASSERT_EQ(swf->AddPoseWithMotion(poisoned, Mat6<double>::Identity()), core::Status::kOk);
  EXPECT_EQ(swf->Update(), core::Status::kNumericalFailure);
  EXPECT_NE(swf->FaultBits() & kFaultReset, 0u);
  EXPECT_EQ(swf->NumPoses(), 0);
  // And it works again from the next frame.
  ASSERT_EQ(swf->AddPose(start), core::Status::kOk);
  ASSERT_EQ(swf->AddObservation(1, Vec3<double>(500, 480, 300), Mat3<double>::Identity()),
            core::Status::kOk);
  EXPECT_EQ(swf->Update(), core::Status::kOk);
}

TEST(SwfStereo, RepeatRunsAreBitIdentical) {
  const SyntheticScene scene(LongPass(120));
  using Filter = SlidingWindowFilter<StereoModel<double>, 10, 400, 64, 96>;
  auto a = std::make_unique<Filter>();
  auto b = std::make_unique<Filter>();
  RunScene(a.get(), scene, ModeOptions(SwfMode::kSlidingWindow));
  RunScene(b.get(), scene, ModeOptions(SwfMode::kSlidingWindow));
  ASSERT_EQ(a->NumPoses(), b->NumPoses());
  for (int j = 0; j < a->NumPoses(); ++j) {
    EXPECT_EQ(std::memcmp(a->PoseAt(j).R.data(), b->PoseAt(j).R.data(), sizeof(double) * 9), 0);
    EXPECT_EQ(std::memcmp(a->PoseAt(j).t.data(), b->PoseAt(j).t.data(), sizeof(double) * 3), 0);
  }
  std::vector<std::pair<std::int64_t, Vec3<double>>> la;
  std::vector<std::pair<std::int64_t, Vec3<double>>> lb;
  a->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) { la.push_back({id, p}); });
  b->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) { lb.push_back({id, p}); });
  ASSERT_EQ(la.size(), lb.size());
  ASSERT_GT(la.size(), 10u);
  for (std::size_t i = 0; i < la.size(); ++i) {
    EXPECT_EQ(la[i].first, lb[i].first);
    EXPECT_EQ(std::memcmp(la[i].second.data(), lb[i].second.data(), sizeof(double) * 3), 0);
  }
}

}  // namespace
}  // namespace swf::estimator
