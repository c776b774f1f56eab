// The front end with an estimator in the loop on a rendered descent: a textured tilted plane
// seen by a stereo camera that moves 3 m towards it (image scale x1.6) while rotating 14 deg.
// Landmarks are tracked with the patch warped by the landmark's plane homography from the
// predicted pose (paper 4.1.2), and re-refined after a simulated estimator update.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <vector>

#include "swf/frontend/frontend.hpp"
#include "swf/testing/allocation_counter.hpp"
#include "synthetic.hpp"

namespace swf::frontend {
namespace {

using estimator::Pose;
using estimator::Vec3;
using testing::Median;

constexpr int kW = 320;
constexpr int kH = 240;
constexpr int kFrames = 6;

struct Scene {
  estimator::StereoCamera<double> camera;
  Vec3<double> normal = Vec3<double>(0.0, -0.3, 1.0).normalized();  // plane n.p = offset
  double offset = 8.0 / Vec3<double>(0.0, -0.3, 1.0).norm();
  testing::Texture texture{91};

  std::vector<testing::TestImage> left;
  std::vector<testing::TestImage> right;

  Scene() {
    camera.fx = camera.fy = 300.0;
    camera.cx = 160.0;
    camera.cy = 120.0;
    camera.baseline_m = 0.2;
    for (int k = 0; k < kFrames; ++k) {  // rendered once, used by both runs
      left.push_back(Render(TruePose(k), 0.0));
      right.push_back(Render(TruePose(k), camera.baseline_m));
    }
  }
  static Pose<double> TruePose(int k) {
    Pose<double> p;
    p.R = estimator::ExpSO3<double>(Vec3<double>(0.0, 0.0, 0.04 * k));
    p.t = Vec3<double>(0.05 * k, -0.03 * k, 0.6 * k);
    return p;
  }
  // World point seen at pixel (u, v) of the camera at x-offset `dx` (0 left, baseline right).
  Vec3<double> Intersect(const Pose<double>& world_T_cam, double dx, double u, double v) const {
    const Vec3<double> o = world_T_cam.Apply(Vec3<double>(dx, 0.0, 0.0));
    const Vec3<double> r =
        world_T_cam.R * Vec3<double>((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
    const double lambda = (offset - normal.dot(o)) / normal.dot(r);
    return o + lambda * r;
  }
  testing::TestImage Render(const Pose<double>& world_T_cam, double dx) const {
    return testing::Render(kW, kH, [&](double u, double v) {
      const Vec3<double> p = Intersect(world_T_cam, dx, u, v);
      return texture(40.0 * p.x(), 40.0 * p.y());
    });
  }
};

// A deterministic pose error of about 2 cm and 0.3 deg (times `scale`), as from a process-model
// prediction.
Pose<double> Perturb(const Pose<double>& p, int k, double scale) {
  Pose<double> q = p;
  const double s = (k % 2 == 0) ? scale : -scale;
  q.t += Vec3<double>(0.015 * s, -0.01 * scale, 0.02 * s);
  q.R = q.R * estimator::ExpSO3<double>(Vec3<double>(0.004 * s, 0.003 * scale, -0.002 * s));
  return q;
}

struct RunResult {
  std::vector<double> errors_px;          // |(uL, v) - truth| of every measurement, frames 1..
  std::vector<double> refined_errors_px;  // the same after Refine with the true state
  std::size_t final_tracks_from_first_frame = 0;
  std::size_t final_visible_from_first_frame = 0;  // truly in view in the last frame
  std::size_t warped = 0;
  std::size_t recovered = 0;
  std::size_t lost_tracking = 0;
  std::uint64_t allocations = 0;
  // Per measurement of frames 1..: StereoMeasurement::magnification and the true one (the
  // landmark's true depth in its first frame over its true depth now).
  std::vector<double> magnification;
  std::vector<double> true_magnification;
};

// error_scale: the prediction's pose error in units of Perturb's; recover: the search for tracks
// warped LK loses (FrontendOptions::recover_lost_tracks).
RunResult RunDescent(const Scene& scene, bool with_prediction, double error_scale = 1.0,
                     bool recover = true) {
  FrontendOptions options;
  options.recover_lost_tracks = recover;
  options.camera = scene.camera;
  options.harris.bucket_cols = 8;
  options.harris.bucket_rows = 6;
  options.max_tracks = 80;
  options.stereo.max_disparity = 40;
  auto frontend = std::make_unique<Frontend>();
  EXPECT_EQ(frontend->Configure(options), core::Status::kOk);
  auto out = std::make_unique<FrameOutput>();
  std::map<std::uint32_t, Vec3<double>> truth;     // landmark id -> true world point
  std::map<std::uint32_t, Vec3<double>> estimate;  // the "estimator's" map
  std::vector<LandmarkEstimate> estimates;
  std::vector<LandmarkEstimate> true_landmarks;
  estimates.reserve(kMaxTracks);
  true_landmarks.reserve(kMaxTracks);
  RunResult result;
  std::vector<std::uint32_t> first_ids;
  std::map<std::uint32_t, int> first_frame;  // landmark id -> the frame it was first seen in
  for (int k = 0; k < kFrames; ++k) {
    const Pose<double> pose = Scene::TruePose(k);
    const testing::TestImage& left = scene.left[k];
    const testing::TestImage& right = scene.right[k];
    const Pose<double> predicted = Perturb(pose, k, error_scale);
    estimates.clear();
    true_landmarks.clear();
    for (const auto& [id, p] : estimate) estimates.push_back(LandmarkEstimate{id, p});
    for (const auto& [id, p] : truth) true_landmarks.push_back(LandmarkEstimate{id, p});
    FramePrediction prediction;
    if (with_prediction) {
      prediction.has_pose = true;
      prediction.world_T_camera = predicted;
      prediction.landmarks = estimates.data();
      prediction.num_landmarks = estimates.size();
    }
    {
      swf::testing::AllocationScope scope;
      EXPECT_EQ(
          frontend->ProcessFrame(StereoFrame{left.View(), right.View()}, prediction, out.get()),
          core::Status::kOk);
      result.allocations += scope.Count();
    }
    result.warped += out->stats.warped;
    result.recovered += out->stats.recovered;
    result.lost_tracking += out->stats.lost_tracking;
    auto error_of = [&](const StereoMeasurement& m) {
      const Vec3<double> z = scene.camera.Project(pose.ApplyInverse(truth.at(m.landmark_id)));
      return std::hypot(m.u_left - z.x(), m.v - z.z());
    };
    for (const StereoMeasurement& m : out->measurements) {
      result.errors_px.push_back(error_of(m));
      const Vec3<double>& p = truth.at(m.landmark_id);
      result.magnification.push_back(m.magnification);
      result.true_magnification.push_back(
          Scene::TruePose(first_frame.at(m.landmark_id)).ApplyInverse(p).z() /
          pose.ApplyInverse(p).z());
    }
    if (with_prediction && k > 0) {
      // The estimator's update: here the true pose and landmarks (a converged filter).
      FramePrediction updated;
      updated.has_pose = true;
      updated.world_T_camera = pose;
      updated.landmarks = true_landmarks.data();
      updated.num_landmarks = true_landmarks.size();
      std::size_t refined = 0;
      {
        swf::testing::AllocationScope scope;
        EXPECT_EQ(frontend->Refine(updated, out.get(), &refined), core::Status::kOk);
        result.allocations += scope.Count();
      }
      for (const StereoMeasurement& m : out->measurements) {
        result.refined_errors_px.push_back(error_of(m));
      }
    }
    for (const NewLandmark& n : out->new_landmarks) {
      truth[n.landmark_id] = scene.Intersect(pose, 0.0, n.u_left, n.v);
      estimate[n.landmark_id] = predicted.Apply(n.p_camera);
      first_frame[n.landmark_id] = k;
      if (k == 0) first_ids.push_back(n.landmark_id);
    }
  }
  const Pose<double> last = Scene::TruePose(kFrames - 1);
  for (const std::uint32_t id : first_ids) {
    const Vec3<double> z = scene.camera.Project(last.ApplyInverse(truth.at(id)));
    result.final_visible_from_first_frame +=
        z.y() >= 12 && z.x() < kW - 12 && z.z() >= 12 && z.z() < kH - 12;
  }
  for (const StereoMeasurement& m : out->measurements) {
    result.final_tracks_from_first_frame +=
        std::find(first_ids.begin(), first_ids.end(), m.landmark_id) != first_ids.end();
  }
  return result;
}

// GIVEN a descent with a 1.6x scale change and 14 deg of roll WHEN tracking with the predicted
// pose and landmark estimates THEN the warped patches keep most first-frame landmarks with
// subpixel accuracy, where square patches from the previous frame lose more of them.
TEST(FrontendSceneTest, WarpedTrackingThroughDescent) {
  const Scene scene;
  const RunResult warped = RunDescent(scene, true);
  const RunResult square = RunDescent(scene, false);
  const double refined_median = Median(warped.refined_errors_px);
  const double warped_median = Median(warped.errors_px);
  std::printf(
      "descent: %zu first-frame landmarks still in view; warped %zu tracks left, median error %.4f "
      "px (%zu warped "
      "alignments), after Refine %.4f px (%.1f%% lower); square patches %zu left, "
      "median %.4f px\n",
      warped.final_visible_from_first_frame, warped.final_tracks_from_first_frame, warped_median,
      warped.warped, refined_median, 100.0 * (warped_median - refined_median) / warped_median,
      square.final_tracks_from_first_frame, Median(square.errors_px));
  EXPECT_EQ(warped.allocations, 0u);
  EXPECT_GT(warped.warped, 0u);
  EXPECT_GE(warped.final_visible_from_first_frame, 25u);
  EXPECT_GE(warped.final_tracks_from_first_frame * 10, warped.final_visible_from_first_frame * 9);
  EXPECT_LE(warped_median, 0.1);
  EXPECT_LE(refined_median, 0.1);
  EXPECT_GE(warped.final_tracks_from_first_frame, square.final_tracks_from_first_frame);
  EXPECT_LT(3.0 * warped_median, Median(square.errors_px));  // square patches drift
}

// GIVEN the same descent with a prediction six times as wrong (about 10 px at the patches) WHEN
// warped LK, started there, loses tracks THEN the search around the prediction finds some of them
// again on their own template (paper 4.1.1: patch matching, then LK), inside the frame's
// allocation-free path, and loses no more tracks and no accuracy against the truth than the
// front end without the search, whose frame-to-frame LK takes such tracks over (measured: 14
// recovered, 52 against 54 lost, median 0.140 px both).
TEST(FrontendSceneTest, SearchRecoversTracksWarpedLkLoses) {
  const Scene scene;
  const RunResult with = RunDescent(scene, true, 6.0, true);
  const RunResult without = RunDescent(scene, true, 6.0, false);
  std::printf(
      "prediction x6: with the search %zu recovered, %zu lost, %zu first-frame tracks left, "
      "median %.4f px; without %zu lost, %zu left, median %.4f px\n",
      with.recovered, with.lost_tracking, with.final_tracks_from_first_frame,
      Median(with.errors_px), without.lost_tracking, without.final_tracks_from_first_frame,
      Median(without.errors_px));
  EXPECT_EQ(with.allocations, 0u);
  EXPECT_GE(with.recovered, 5u);
  EXPECT_EQ(without.recovered, 0u);
  EXPECT_LE(with.lost_tracking, without.lost_tracking);
  EXPECT_LE(Median(with.errors_px), Median(without.errors_px) + 0.01);
}

// GIVEN the descent with the x4 prediction error WHEN each frame's measurements are refined at
// the updated (here: true) pose and landmarks THEN the error against the truth drops (paper
// 4.1.2: 10-15 %): the update changes the warp the template is aligned under.
TEST(FrontendSceneTest, RefinementAtTheUpdatedEstimateLowersTheError) {
  const Scene scene;
  const RunResult r = RunDescent(scene, true, 4.0, true);
  std::vector<double> before;  // the same measurements (frames 1..) before Refine
  for (std::size_t i = r.errors_px.size() - r.refined_errors_px.size(); i < r.errors_px.size();
       ++i) {
    before.push_back(r.errors_px[i]);
  }
  const double b = Median(before);
  const double a = Median(r.refined_errors_px);
  std::printf("prediction x4: median %.4f px before Refine, %.4f px after (%.1f%% lower)\n", b, a,
              100.0 * (b - a) / b);
  EXPECT_EQ(r.allocations, 0u);
  EXPECT_LT(a, 0.95 * b);
}

// GIVEN the descent towards the plane (up to 1.6x) WHEN tracking with the predicted pose and
// landmark estimates THEN each measurement reports the magnification of its template's warp
// within 3 % of the true one (its landmark's depth in the template's frame over its depth now),
// which is what the pipeline's measurement sigma grows with (app::MeasurementSigmaPx); without an
// estimate (square patches from the previous frame) it reports 1.
TEST(FrontendSceneTest, MeasurementsReportTheirTemplatesMagnification) {
  const Scene scene;
  const RunResult warped = RunDescent(scene, true);
  const RunResult square = RunDescent(scene, false);
  ASSERT_FALSE(warped.magnification.empty());
  std::vector<double> relative;
  double largest = 0.0;
  for (std::size_t i = 0; i < warped.magnification.size(); ++i) {
    relative.push_back(std::abs(warped.magnification[i] / warped.true_magnification[i] - 1.0));
    largest = std::max(largest, warped.true_magnification[i]);
  }
  std::sort(relative.begin(), relative.end());
  const double p90 = relative[relative.size() * 9 / 10];
  std::printf(
      "magnification: %zu measurements, true up to %.3f; relative error median %.4f, "
      "p90 %.4f\n",
      relative.size(), largest, Median(relative), p90);
  EXPECT_GT(largest, 1.4);
  EXPECT_LT(p90, 0.03);
  for (const double m : square.magnification) EXPECT_EQ(m, 1.0);
}

}  // namespace
}  // namespace swf::frontend
