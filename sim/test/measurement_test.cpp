#include "swf/sim/measurement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

#include "swf/sim/rng.hpp"
#include "swf/testing/refusals.hpp"

namespace swf::sim {
namespace {

TEST(RngTest, GaussianHasUnitMomentsAndIsRepeatable) {
  Rng a(42);
  Rng b(42);
  double sum = 0.0;
  double sum2 = 0.0;
  constexpr int kN = 200000;
  for (int i = 0; i < kN; ++i) {
    const double x = a.Gaussian();
    ASSERT_EQ(x, b.Gaussian());
    sum += x;
    sum2 += x * x;
  }
  EXPECT_NEAR(sum / kN, 0.0, 0.01);
  EXPECT_NEAR(sum2 / kN, 1.0, 0.02);
}

TEST(RngTest, KnownFirstDrawPinsTheEngine) {
  // std::mt19937_64's 10000th output for the default seed is fixed by the standard.
  std::mt19937_64 engine;
  engine.discard(9999);
  EXPECT_EQ(engine(), 9981545732273789042ull);
}

TEST(TrajectoryTest, PresetsMatchThePaper) {
  Trajectory descent;
  ASSERT_EQ(descent.Configure(DescentTrajectory(15.0)), core::Status::kOk);
  EXPECT_EQ(descent.NumFrames(), 136);
  EXPECT_NEAR(descent.WorldTCamera(0).t.z(), 100.0, 1e-12);
  EXPECT_NEAR(descent.WorldTCamera(descent.NumFrames() - 1).t.z(), 10.0, 1e-9);
  EXPECT_EQ(descent.FrameTimeNs(15), core::kNsPerS);

  Trajectory lab;
  ASSERT_EQ(lab.Configure(LabTrajectory()), core::Status::kOk);
  EXPECT_EQ(lab.NumFrames(), 61);
  EXPECT_NEAR(lab.WorldTCamera(1).t.z(), 9.85, 1e-12);
  EXPECT_NEAR(lab.WorldTCamera(60).t.z(), 1.0, 1e-9);

  // Sideways: consecutive frames share 85 % of the ground footprint width.
  const RigOptions rig = EdlRig();
  Trajectory side;
  ASSERT_EQ(side.Configure(SidewaysTrajectory(rig, 50.0, 0.85, 10)), core::Status::kOk);
  const double footprint = 2.0 * 50.0 * std::tan(12.5 * M_PI / 180.0);
  const double step = (side.WorldTCamera(1).t - side.WorldTCamera(0).t).norm();
  EXPECT_NEAR(1.0 - step / footprint, 0.85, 1e-9);

  Trajectory hover;
  ASSERT_EQ(hover.Configure(HoverTrajectory(30.0, 5)), core::Status::kOk);
  EXPECT_EQ((hover.WorldTCamera(4).t - hover.WorldTCamera(0).t).norm(), 0.0);
}

TEST(TrajectoryTest, NadirCameraLooksDownAndJitterIsBounded) {
  TrajectoryOptions o = DescentTrajectory();
  o.jitter_sigma_rad = 0.0;
  Trajectory t;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  const Eigen::Vector3d optical_axis_world = t.WorldTCamera(0).R.col(2);
  EXPECT_NEAR((optical_axis_world - Eigen::Vector3d(0, 0, -1)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(t.WorldTCamera(0).R.determinant(), 1.0, 1e-12);

  o.jitter_sigma_rad = 0.01;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  double max_angle = 0.0;
  for (int k = 0; k < t.NumFrames(); ++k) {
    const double angle = std::acos(std::clamp(-t.WorldTCamera(k).R.col(2).z(), -1.0, 1.0));
    max_angle = std::max(max_angle, angle);
  }
  EXPECT_GT(max_angle, 0.005);
  EXPECT_LT(max_angle, 0.08);
}

// GIVEN a dispersed descent (70 m -> 25 m at 5 m/s at 10 Hz, drifting sideways, the camera
// offset from nadir and turning) THEN the frames follow from the geometry, the position moves at
// the given velocity, and the attitude without jitter is the offset growing at the body rate: the
// optical axis tilts as the offset says at the start and the rotation between two frames is the
// body rate times their time.
TEST(TrajectoryTest, DescentGeometryOffsetAndBodyRate) {
  TrajectoryOptions o = DescentTrajectory(10.0, 70.0, 25.0, 5.0);
  o.velocity_world_mps.x() = 2.0;
  o.velocity_world_mps.y() = -1.0;
  o.jitter_sigma_rad = 0.0;
  const double deg = M_PI / 180.0;
  o.attitude_offset_rad = Eigen::Vector3d(10.0, 0.0, 0.0) * deg;  // roll: about camera x
  o.body_rate_radps = Eigen::Vector3d(0.0, 2.0, 0.0) * deg;       // pitching
  Trajectory t;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  ASSERT_EQ(t.NumFrames(), 91);  // 45 m at 5 m/s = 9 s
  const Eigen::Vector3d end = t.WorldTCamera(90).t;
  EXPECT_NEAR((end - Eigen::Vector3d(18.0, -9.0, 25.0)).norm(), 0.0, 1e-9);
  // Rolling by 10 deg about camera x (world x for heading 0) tilts the optical axis 10 deg off
  // nadir towards camera -y, which is world +y.
  const Eigen::Vector3d axis0 = t.WorldTCamera(0).R.col(2);
  EXPECT_NEAR(std::acos(-axis0.z()), 10.0 * deg, 1e-12);
  EXPECT_NEAR(axis0.x(), 0.0, 1e-12);
  EXPECT_GT(axis0.y(), 0.0);
  const Eigen::Matrix3d relative = t.WorldTCamera(30).R.transpose() * t.WorldTCamera(80).R;
  EXPECT_LT((estimator::LogSO3<double>(relative) - o.body_rate_radps * 5.0).norm(), 1e-12);
  // Without offset and rate the steered attitude is the nadir rotation itself (bit for bit).
  const TrajectoryOptions nominal = DescentTrajectory(10.0);
  EXPECT_EQ(SteeredAttitude(nominal, 3.7), NadirRotation(0.0));
  EXPECT_EQ(DescentTrajectory(10.0).num_frames, 91);
  EXPECT_EQ(DescentTrajectory(10.0, 100.0, 10.0, 3.0).num_frames, 301);
}

TEST(TrajectoryTest, RejectsBadOptions) {
  testing::ExpectEachRefused<Trajectory, TrajectoryOptions>({
      [](TrajectoryOptions& o) { o.rate_hz = 0.0; },
      [](TrajectoryOptions& o) { o.num_frames = 0; },
      [](TrajectoryOptions& o) { o.jitter_correlation = 1.0; },
      [](TrajectoryOptions& o) { o.body_rate_radps.x() = std::numeric_limits<double>::infinity(); },
      // A descent that never gets to its end altitude has no frame count.
      [](TrajectoryOptions& o) { o = DescentTrajectory(10.0, 10.0, 100.0, 10.0); },
  });
}

MeasurementOptions PaperFig14Options() {
  MeasurementOptions o;
  o.features_per_frame = 20;
  o.track_length_frames = 10;
  o.pixel_sigma_px = 0.5;
  o.relief_amplitude_m = 2.0;
  o.seed = 7;
  return o;
}

TEST(MeasurementTest, NoiseFreeObservationsAreExactProjectionsOfTruth) {
  MeasurementOptions o = PaperFig14Options();
  o.pixel_sigma_px = 0.0;
  MeasurementScenario s;
  ASSERT_EQ(s.Configure(o), core::Status::kOk);
  ASSERT_EQ(s.NumFrames(), 136);
  for (int k = 0; k < s.NumFrames(); ++k) {
    const MeasurementFrame& f = s.Frame(k);
    for (const Observation& obs : f.observations) {
      const Eigen::Vector3d l = s.Landmarks()[obs.landmark_id];
      const Eigen::Vector3d z = s.Camera().Project(f.world_T_camera.ApplyInverse(l));
      EXPECT_NEAR(z.x(), obs.u_left_px, 1e-9);
      EXPECT_NEAR(z.y(), obs.u_right_px, 1e-9);
      EXPECT_NEAR(z.z(), obs.v_px, 1e-9);
      // Landmarks lie on the surface.
      const PlaneWaveSurface surface(0.0, 2.0, 20.0);
      EXPECT_NEAR(l.z(), surface.HeightAt(l.x(), l.y()), 1e-6);
      EXPECT_GT(obs.u_left_px - obs.u_right_px, 0.0);
    }
  }
}

TEST(MeasurementTest, FeatureCountTrackLengthAndNoiseAreAsRequested) {
  MeasurementScenario s;
  ASSERT_EQ(s.Configure(PaperFig14Options()), core::Status::kOk);
  for (int k = 0; k < s.NumFrames(); ++k) EXPECT_EQ(s.Frame(k).observations.size(), 20u);
  // Descending, the view shrinks, so some tracks end early: mean a bit under 10.
  EXPECT_GT(s.Summary().mean_track_length_frames, 6.0);
  EXPECT_LE(s.Summary().mean_track_length_frames, 10.5);
  double sum2 = 0.0;
  std::int64_t n = 0;
  for (int k = 0; k < s.NumFrames(); ++k) {
    for (const Observation& obs : s.Frame(k).observations) {
      sum2 += std::pow(obs.u_left_px - obs.z_true.x(), 2) + std::pow(obs.v_px - obs.z_true.z(), 2);
      n += 2;
      EXPECT_FALSE(obs.is_outlier);
    }
  }
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.5, 0.03);
}

TEST(MeasurementTest, UnlimitedTracksFollowTheSameLandmarksWhileHovering) {
  MeasurementOptions o;
  o.trajectory = HoverTrajectory(50.0, 30);
  o.features_per_frame = 30;
  o.track_length_frames = 0;
  MeasurementScenario s;
  ASSERT_EQ(s.Configure(o), core::Status::kOk);
  EXPECT_EQ(s.Summary().num_landmarks, 30);
  EXPECT_EQ(s.Frame(29).observations.size(), 30u);
}

TEST(MeasurementTest, OutlierFractionIsHonouredAndFlagged) {
  MeasurementOptions o = PaperFig14Options();
  o.outlier_fraction = 0.2;
  MeasurementScenario s;
  ASSERT_EQ(s.Configure(o), core::Status::kOk);
  const double fraction =
      static_cast<double>(s.Summary().num_outliers) / s.Summary().num_observations;
  EXPECT_NEAR(fraction, 0.2, 0.03);
  for (int k = 0; k < s.NumFrames(); ++k) {
    for (const Observation& obs : s.Frame(k).observations) {
      const double err = std::hypot(obs.u_left_px - obs.z_true.x(), obs.v_px - obs.z_true.z());
      if (obs.is_outlier) EXPECT_GT(err, 2.0);
    }
  }
}

TEST(MeasurementTest, SameSeedSameBitsDifferentSeedDifferentData) {
  MeasurementScenario a;
  MeasurementScenario b;
  ASSERT_EQ(a.Configure(PaperFig14Options()), core::Status::kOk);
  ASSERT_EQ(b.Configure(PaperFig14Options()), core::Status::kOk);
  ASSERT_EQ(a.Summary().num_observations, b.Summary().num_observations);
  for (int k = 0; k < a.NumFrames(); ++k) {
    ASSERT_EQ(a.Frame(k).observations.size(), b.Frame(k).observations.size());
    for (size_t i = 0; i < a.Frame(k).observations.size(); ++i) {
      EXPECT_EQ(a.Frame(k).observations[i].u_left_px, b.Frame(k).observations[i].u_left_px);
      EXPECT_EQ(a.Frame(k).observations[i].landmark_id, b.Frame(k).observations[i].landmark_id);
    }
  }
  MeasurementOptions o = PaperFig14Options();
  o.seed = 8;
  MeasurementScenario c;
  ASSERT_EQ(c.Configure(o), core::Status::kOk);
  EXPECT_NE(a.Landmarks()[0].x(), c.Landmarks()[0].x());
}

TEST(MeasurementTest, SidewaysLandmarksEnterAndLeaveTheView) {
  MeasurementOptions o;
  o.trajectory = SidewaysTrajectory(o.rig, 50.0, 0.85, 30);
  o.features_per_frame = 25;
  o.track_length_frames = 0;
  MeasurementScenario s;
  ASSERT_EQ(s.Configure(o), core::Status::kOk);
  // 15 % new ground per frame: a landmark spawned uniformly across the view lasts on average
  // about half of 1/0.15 frames.
  EXPECT_GT(s.Summary().mean_track_length_frames, 2.8);
  EXPECT_LT(s.Summary().mean_track_length_frames, 8.0);
  std::map<int, int> first_seen;
  for (int k = 0; k < s.NumFrames(); ++k) {
    for (const Observation& obs : s.Frame(k).observations) first_seen.emplace(obs.landmark_id, k);
  }
  EXPECT_GT(first_seen.size(), 60u);
}

TEST(MeasurementTest, RejectsBadOptions) {
  testing::ExpectEachRefused<MeasurementScenario, MeasurementOptions>({
      [](MeasurementOptions& o) { o.outlier_fraction = 1.5; },
      [](MeasurementOptions& o) { o.pixel_sigma_px = -1.0; },
      [](MeasurementOptions& o) { o.rig.baseline_m = 0.0; },
      [](MeasurementOptions& o) { o.trajectory.rate_hz = -1.0; },
  });
}

}  // namespace
}  // namespace swf::sim
