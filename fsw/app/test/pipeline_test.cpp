// The pipeline over a simulated descent: the motion-input gating (glitches outside the envelope
// (a 1 km jump, -1e300, a 3 rad turn) are refused before the filter and a subtler one (0.5 m,
// 25 sigma) is overruled by the images; each is counted and flagged MOTION_REJECTED, never
// published VALID, and the estimate stays with the truth), and the stated calibration
// uncertainty's share of the published covariance.
#include "swf/app/pipeline.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "small_rig.hpp"
#include "swf/app/config.hpp"
#include "swf/sil/sil.hpp"

namespace swf::app {
namespace {

using estimator::NavIntegrity;
using estimator::Pose;
using estimator::Vec3;

// Sets `field` of `options` to a negative, a NaN and an infinite value, each of which Configure
// must refuse (the other options valid), and leaves it at `good`, which Configure must take.
void ExpectOnlyFiniteNonNegativeTaken(Pipeline* pipeline, PipelineOptions* options,
                                      double PipelineOptions::*field, double good) {
  for (const double bad : {-good, std::nan(""), HUGE_VAL}) {
    options->*field = bad;
    EXPECT_EQ(pipeline->Configure(*options), core::Status::kInvalidArgument) << bad;
  }
  options->*field = good;
  EXPECT_EQ(pipeline->Configure(*options), core::Status::kOk) << good;
}

struct Descent {
  FswConfig config;
  std::unique_ptr<sil::SimWorld> world = std::make_unique<sil::SimWorld>();
  std::unique_ptr<Pipeline> pipeline = std::make_unique<Pipeline>();

  explicit Descent(double baseline_sigma_m = 0.0, double disparity_sigma_px = 0.0) {
    std::string error;
    EXPECT_TRUE(testing::BuildSimWorld(
        "source: sim\nsim.frames: 60\nsim.width_px: 256\nsim.height_px: 192\n"
        "sim.terrain_size: 1024\nrate_hz: 10\n",
        &config, world.get(), &error))
        << error;
    PipelineOptions po = testing::SmallRigOptions(*world);
    po.process_sigma_m = 0.02;  // the simulated motion input's noise
    po.process_sigma_rad = 0.0005;
    po.integrity.max_speed_mps = 50.0;
    po.initial_world_T_camera = world->Trajectory().WorldTCamera(0);
    po.calibration_baseline_sigma_m = baseline_sigma_m;
    po.calibration_disparity_sigma_px = disparity_sigma_px;
    EXPECT_EQ(pipeline->Configure(po), core::Status::kOk);
  }

  // Runs every frame with its motion input passed through `corrupt(frame, motion)`; records
  // each frame's status, flags and position error.
  template <typename Corrupt>
  void Run(const Corrupt& corrupt) {
    for (std::int32_t k = 0; k < world->NumFrames(); ++k) {
      PipelineFrame frame;
      frame.left =
          frontend::GrayView{world->Left(k), world->Width(), world->Height(), world->Width()};
      frame.right =
          frontend::GrayView{world->Right(k), world->Width(), world->Height(), world->Width()};
      frame.utime = 100000 * static_cast<std::int64_t>(k);
      frame.seq = k;
      drivers::MotionInput m;
      const bool has_motion = world->Motion(static_cast<std::uint64_t>(k), &m);
      Pose<double> motion;
      motion.t = Vec3<double>(m.translation_m[0], m.translation_m[1], m.translation_m[2]);
      motion.R = estimator::ExpSO3<double>(
          Vec3<double>(m.rotation_rad[0], m.rotation_rad[1], m.rotation_rad[2]));
      corrupt(k, &motion);
      ASSERT_EQ(pipeline->Rectify(frame), core::Status::kOk);
      ASSERT_EQ(pipeline->Track(), core::Status::kOk);
      ASSERT_EQ(pipeline->Estimate(has_motion ? &motion : nullptr), core::Status::kOk);
      pipeline->MakeNav(&nav);
      const Vec3<double> truth = world->Trajectory().WorldTCamera(k).t;
      status[k] = nav.status;
      flags[k] = static_cast<std::uint32_t>(nav.integrity_flags);
      error_m[k] =
          (Vec3<double>(nav.position_world_m[0], nav.position_world_m[1], nav.position_world_m[2]) -
           truth)
              .norm();
    }
  }

  NavOutput nav;  // the last frame's
  std::int8_t status[60] = {};
  std::uint32_t flags[60] = {};
  double error_m[60] = {};
};

bool Valid(std::int8_t status) { return status == static_cast<std::int8_t>(NavIntegrity::kValid); }

// GIVEN a base sigma and a growth per unit of magnification (an angle) WHEN measurements come
// with their template's magnification THEN the stated sigma is the base for an unwarped template
// (a first sighting), grows linearly with the scale change, alike for a view twice as near or
// twice as far, twice as fast in pixels for twice the focal length (a growth in pixels adds the
// same at any focal length), and is the base when no scale is known; a negative or non-finite
// growth is refused.
TEST(PipelineTest, MeasurementSigmaGrowsWithTheWarpsMagnification) {
  PipelineOptions po;
  po.camera.fx = 1000.0;
  po.measurement_sigma_px = 0.04;
  po.measurement_sigma_per_magnification_rad = 2e-4;  // 0.2 px per unit of m - 1 at this fx
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 1.0), 0.04);
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 1.5), 0.04 + 0.2 * 0.5);
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 2.0), 0.24);
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 0.5), 0.24);
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 0.0), 0.04);
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, -1.0), 0.04);
  po.camera.fx = 2000.0;
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 2.0), 0.44);
  po.measurement_sigma_per_magnification_px = 0.1;  // a part that does not scale with fx
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 2.0), 0.04 + 0.1 + 0.4);
  po.camera.fx = 1000.0;
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 2.0), 0.04 + 0.1 + 0.2);
  po.measurement_sigma_per_magnification_rad = 0.0;
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 1.5), 0.04 + 0.1 * 0.5);
  po.measurement_sigma_per_magnification_px = 0.0;
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 3.0), 0.04);  // the constant sigma of before

  const Descent descent;  // a valid configuration, one field at a time made invalid
  PipelineOptions bad = testing::SmallRigOptions(*descent.world);
  auto pipeline = std::make_unique<Pipeline>();
  ExpectOnlyFiniteNonNegativeTaken(pipeline.get(), &bad,
                                   &PipelineOptions::measurement_sigma_per_magnification_rad, 2e-4);
  ExpectOnlyFiniteNonNegativeTaken(pipeline.get(), &bad,
                                   &PipelineOptions::measurement_sigma_per_magnification_px, 0.1);
}

// GIVEN the warp-grown part of the left error shared by a track's sightings
// (track_error_shared) WHEN its n-th sighting is stated THEN its variance is the single
// sighting's plus (n - 1) times the shared part's, so n sightings stated so carry no more
// information about their common error than the exact model with that error common to all of
// them (sigma_w^2 I + sigma_b^2 1 1^T) does, and at least the share of it the base model's sum
// of sigmas leaves; a first sighting, a template seen unwarped and the independent model keep the
// sigma of before.
TEST(PipelineTest, AWarpErrorSharedByATrackIsNotCountedOncePerSighting) {
  PipelineOptions po;
  po.camera.fx = 1000.0;
  po.measurement_sigma_px = 0.03;
  po.measurement_sigma_per_magnification_rad = 2e-4;  // 0.2 px per unit of m - 1 at this fx
  po.track_error_shared = true;
  const double w = 0.03;
  const double b = 0.2 * 0.5;  // m = 1.5
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 1.5, 1), w + b);
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 1.5, 10), std::sqrt((w + b) * (w + b) + 9 * b * b));
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 1.0, 10), w);  // nothing warped, nothing shared
  EXPECT_DOUBLE_EQ(MeasurementNoiseOf(po, 1.5, 40.0, 10).sigma_px, MeasurementSigmaPx(po, 1.5, 10));
  for (const int n : {2, 5, 20, 60}) {
    const Eigen::MatrixXd common =
        w * w * Eigen::MatrixXd::Identity(n, n) + b * b * Eigen::MatrixXd::Ones(n, n);
    const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
    const double exact = ones.dot(common.ldlt().solve(ones));
    const double sigma = MeasurementSigmaPx(po, 1.5, n);
    const double stated = n / (sigma * sigma);
    EXPECT_LE(stated, exact) << n;
    EXPECT_GE(stated, 0.5 * exact) << n;
  }
  po.track_error_shared = false;  // the independent model of before
  EXPECT_DOUBLE_EQ(MeasurementSigmaPx(po, 1.5, 10), w + b);
}

// GIVEN the stereo match's own sigma (a base plus a growth with the parallax d / fx) WHEN a
// measurement is stated THEN uR follows uL: a shift common to both coordinates (the tracker's
// error, which the match carries over) whitens into the bearing alone and a change of uR alone
// into the disparity alone, W^T W is the inverse of R = [s^2 s^2 0; s^2 s^2 + sd^2 0; 0 0 s^2],
// and without a disparity
// sigma the model of before holds (uR independent at uL's sigma); a negative or non-finite
// disparity sigma is refused.
TEST(PipelineTest, RightCoordinateFollowsTheLeftWithTheMatchsOwnSigma) {
  PipelineOptions po;
  po.camera.fx = 1000.0;
  po.measurement_sigma_px = 0.05;
  po.measurement_sigma_per_magnification_rad = 2e-4;
  po.measurement_disparity_sigma_px = 0.02;
  po.measurement_disparity_sigma_per_parallax_px = 0.6;
  const MeasurementNoise n = MeasurementNoiseOf(po, 1.5, 50.0);
  EXPECT_DOUBLE_EQ(n.sigma_px, 0.05 + 0.2 * 0.5);             // the left's, as MeasurementSigmaPx
  EXPECT_DOUBLE_EQ(n.disparity_sigma_px, 0.02 + 0.6 * 0.05);  // d / fx = 0.05
  EXPECT_TRUE(n.right_follows_left);
  EXPECT_DOUBLE_EQ(MeasurementNoiseOf(po, 3.0, 50.0).disparity_sigma_px, 0.05);  // not with m
  EXPECT_DOUBLE_EQ(MeasurementNoiseOf(po, 1.0, -3.0).disparity_sigma_px, 0.02);

  const estimator::Mat3<double> w = MeasurementSqrtInformation(n);
  estimator::Mat3<double> r;
  const double s2 = n.sigma_px * n.sigma_px;
  const double d2 = n.disparity_sigma_px * n.disparity_sigma_px;
  r << s2, s2, 0.0, s2, s2 + d2, 0.0, 0.0, 0.0, s2;
  EXPECT_LT(((w.transpose() * w) * r - estimator::Mat3<double>::Identity()).norm(), 1e-9);
  const estimator::Vec3<double> bearing = w * estimator::Vec3<double>(0.3, 0.3, 0.0);
  EXPECT_NEAR(bearing.x(), 0.3 / n.sigma_px, 1e-9);
  EXPECT_NEAR(bearing.y(), 0.0, 1e-9);  // a shared shift says nothing about the depth
  const estimator::Vec3<double> depth = w * estimator::Vec3<double>(0.0, -0.01, 0.0);
  EXPECT_NEAR(depth.x(), 0.0, 1e-9);
  EXPECT_NEAR(depth.y(), -0.01 / n.disparity_sigma_px, 1e-9);

  po.measurement_disparity_sigma_px = 0.0;  // the model of before
  const MeasurementNoise before = MeasurementNoiseOf(po, 1.0, 50.0);
  EXPECT_FALSE(before.right_follows_left);
  EXPECT_DOUBLE_EQ(before.disparity_sigma_px, std::sqrt(2.0) * 0.05);
  EXPECT_EQ(MeasurementSqrtInformation(before), estimator::Mat3<double>::Identity() / 0.05);

  const Descent descent;  // a valid configuration, one field at a time made invalid
  PipelineOptions bad = testing::SmallRigOptions(*descent.world);
  auto pipeline = std::make_unique<Pipeline>();
  ExpectOnlyFiniteNonNegativeTaken(pipeline.get(), &bad,
                                   &PipelineOptions::measurement_disparity_sigma_px, 0.02);
  ExpectOnlyFiniteNonNegativeTaken(
      pipeline.get(), &bad, &PipelineOptions::measurement_disparity_sigma_per_parallax_px, 0.6);
}

TEST(PipelineTest, MotionGlitchesAreRefusedOrOverruledAndNeverPublishedValid) {
  Descent clean;
  clean.Run([](int, Pose<double>*) {});
  Descent glitched;
  glitched.Run([](int k, Pose<double>* u) {
    if (k == 20) u->t += Vec3<double>(1000.0, 0.0, 0.0);
    if (k == 26) u->t = Vec3<double>::Constant(-1e300);
    if (k == 32) u->R = u->R * estimator::ExpSO3<double>(Vec3<double>(3.0, 0.0, 0.0));
    if (k == 40) u->t += Vec3<double>(0.0, 0.5, 0.0);
  });
  const IntegrityCounters& c = glitched.pipeline->Integrity();
  EXPECT_EQ(c.motion_refused, 3);
  EXPECT_EQ(c.motion_overruled, 1);
  EXPECT_EQ(clean.pipeline->Integrity().motion_refused, 0);
  EXPECT_EQ(clean.pipeline->Integrity().motion_overruled, 0);
  double worst_clean_m = 0.0;
  double worst_glitched_m = 0.0;
  for (int k = 0; k < 60; ++k) {
    const bool glitch = k == 20 || k == 26 || k == 32 || k == 40;
    EXPECT_EQ((clean.flags[k] & estimator::kFlagMotionRejected) != 0, false) << k;
    EXPECT_EQ((glitched.flags[k] & estimator::kFlagMotionRejected) != 0, glitch) << k;
    if (glitch) EXPECT_FALSE(Valid(glitched.status[k])) << k;
    worst_clean_m = std::max(worst_clean_m, clean.error_m[k]);
    worst_glitched_m = std::max(worst_glitched_m, glitched.error_m[k]);
  }
  EXPECT_TRUE(Valid(glitched.status[59]));
  // Without the gates the 1 km jump stays in the solution for good; with them the run stays
  // within a few decimetres of the clean one.
  EXPECT_LT(worst_glitched_m, worst_clean_m + 0.3);
  std::printf("worst position error: clean %.3f m, with four glitches %.3f m\n", worst_clean_m,
              worst_glitched_m);
}

Eigen::Matrix3d PositionCovariance(const NavOutput& nav) {
  Eigen::Matrix3d c;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(i, j) = nav.covariance[6 * i + j];
  return c;
}

// GIVEN the same descent flown with a perfect calibration stated and with a baseline 1-sigma of
// 1 cm (then a disparity bias of 0.1 px) WHEN the last output is compared THEN the estimates are
// identical (a consider parameter changes no estimate), and the baseline's share of the position
// covariance is exactly sigma^2 d d^T / b^2 with d the estimated displacement (its sensitivity
// telescopes), while the disparity bias's is rank one, along d within 3 deg, its size between
// what the nearest and the farthest range of the descent (41-100 m) give.
TEST(PipelineTest, StatedCalibrationUncertaintyWidensTheCovarianceAlongThePath) {
  const auto fly = [](double baseline_sigma_m, double disparity_sigma_px) {
    Descent d(baseline_sigma_m, disparity_sigma_px);
    d.Run([](std::int32_t, Pose<double>*) {});
    return d.nav;
  };
  const NavOutput perfect = fly(0.0, 0.0);
  const NavOutput baseline = fly(0.01, 0.0);
  const NavOutput disparity = fly(0.0, 0.1);
  const Descent reference;
  const Vec3<double> start = reference.world->Trajectory().WorldTCamera(0).t;
  const double fx_b = reference.world->Camera().fx * reference.world->Camera().baseline_m;
  const Vec3<double> d = Vec3<double>(perfect.position_world_m[0], perfect.position_world_m[1],
                                      perfect.position_world_m[2]) -
                         start;
  ASSERT_GT(d.norm(), 50.0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(baseline.position_world_m[i], perfect.position_world_m[i]);
    EXPECT_EQ(disparity.position_world_m[i], perfect.position_world_m[i]);
  }
  const Eigen::Matrix3d from_baseline = PositionCovariance(baseline) - PositionCovariance(perfect);
  EXPECT_LT((from_baseline - 1e-4 * d * d.transpose()).norm(), 1e-9 * d.squaredNorm());
  EXPECT_GT(baseline.vertical_protection_m, perfect.vertical_protection_m + 0.01 * d.norm());

  // sigma^2 s s^T: one non-zero eigenvalue, its axis along the path (every step weighs by its
  // range, so not exactly along d).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> bias(PositionCovariance(disparity) -
                                                            PositionCovariance(perfect));
  const double along = std::sqrt(bias.eigenvalues()(2));
  EXPECT_LT(std::abs(bias.eigenvalues()(1)), 1e-6 * along * along);
  EXPECT_GT(std::abs(bias.eigenvectors().col(2).dot(d.normalized())), std::cos(0.05));
  EXPECT_GT(along, 0.1 * 30.0 * d.norm() / fx_b);
  EXPECT_LT(along, 0.1 * 110.0 * d.norm() / fx_b);
}

}  // namespace
}  // namespace swf::app
