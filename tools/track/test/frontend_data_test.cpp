// The front end on real images with ground truth (../shared/data): Middlebury optical flow
// (RubberWhale, Dimetrodon), Middlebury stereo (aloe) and the EuRoC V1_01 stereo sequence.
// Prints the numbers reported in docs/benchmarks.md ("## Front end") and asserts thresholds
// a little below them, so a regression fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "swf/evaluation/statistics.hpp"
#include "swf/frontend/frontend.hpp"
#include "swf/frontend/rectify.hpp"
#include "swf/image_io/image_io.hpp"
#include "swf/testing/shared_dir.hpp"

namespace swf::frontend {
namespace {

using image_io::GrayImage;

std::string DataDir() { return swf::testing::SharedDir() + "/data"; }

GrayImage MustLoad(const std::string& path) {
  GrayImage image;
  std::string error;
  EXPECT_TRUE(image_io::LoadGray(path, &image, &error)) << error;
  return image;
}

using evaluation::Median;

double FractionBelow(const std::vector<double>& v, double limit) {
  if (v.empty()) return 0.0;
  return static_cast<double>(
             std::count_if(v.begin(), v.end(), [&](double e) { return e <= limit; })) /
         static_cast<double>(v.size());
}

HarrisOptions DetectorFor(int width, int height) {
  HarrisOptions o;
  o.bucket_cols = std::min(64, width / 40);
  o.bucket_rows = std::min(64, height / 40);
  return o;
}

struct FlowResult {
  std::size_t detected = 0;
  std::vector<double> errors;
};

FlowResult RunFlow(const std::string& name) {
  const std::string dir = DataDir() + "/middlebury/flow-" + name + "/";
  const GrayImage a = MustLoad(dir + "frame10.png");
  const GrayImage b = MustLoad(dir + "frame11.png");
  image_io::FlowField truth;
  std::string error;
  EXPECT_TRUE(image_io::LoadFlo(dir + "flow10.flo", &truth, &error)) << error;
  FlowResult result;
  if (a.width != truth.width || a.height != truth.height) {
    ADD_FAILURE() << "flow size mismatch";
    return result;
  }
  auto detector = std::make_unique<HarrisDetector>();
  EXPECT_EQ(detector->Configure(DetectorFor(a.width, a.height)), core::Status::kOk);
  CornerList corners;
  EXPECT_EQ(detector->Detect(a.View(), nullptr, 0, &corners), core::Status::kOk);
  auto prev = std::make_unique<Pyramid>();
  auto cur = std::make_unique<Pyramid>();
  PatchTracker tracker;
  EXPECT_EQ(tracker.Configure(TrackerOptions{}), core::Status::kOk);
  EXPECT_EQ(prev->Build(a.View(), 3), core::Status::kOk);
  EXPECT_EQ(cur->Build(b.View(), 3), core::Status::kOk);
  for (const Corner& c : corners) {
    const int xi = static_cast<int>(c.x);
    const int yi = static_cast<int>(c.y);
    if (!truth.Known(xi, yi)) continue;
    ++result.detected;
    float x = c.x;
    float y = c.y;
    float q = 0.0f;
    if (!tracker.TrackFlow(*prev, *cur, c.x, c.y, &x, &y, &q)) continue;
    result.errors.push_back(std::hypot(x - c.x - truth.U(xi, yi), y - c.y - truth.V(xi, yi)));
  }
  std::printf(
      "flow %s: %zu features with ground truth, %zu tracked (%.1f%%), median endpoint "
      "error %.3f px, within 1 px %.1f%%, within 0.5 px %.1f%%\n",
      name.c_str(), result.detected, result.errors.size(),
      100.0 * result.errors.size() / std::max<std::size_t>(1, result.detected),
      Median(result.errors), 100.0 * FractionBelow(result.errors, 1.0),
      100.0 * FractionBelow(result.errors, 0.5));
  return result;
}

TEST(FrontendDataTest, MiddleburyFlowRubberWhale) {
  const FlowResult r = RunFlow("RubberWhale");
  EXPECT_GE(r.errors.size(), r.detected * 95 / 100);
  EXPECT_LE(Median(r.errors), 0.075);  // measured 0.054 px (OpenCV's LK on the same corners 0.059)
  EXPECT_GE(FractionBelow(r.errors, 1.0), 0.90);
}

TEST(FrontendDataTest, MiddleburyFlowDimetrodon) {
  const FlowResult r = RunFlow("Dimetrodon");
  EXPECT_GE(r.errors.size(), r.detected * 93 / 100);
  EXPECT_LE(Median(r.errors), 0.075);  // measured 0.057 px (OpenCV's LK on the same corners 0.059)
  EXPECT_GE(FractionBelow(r.errors, 1.0), 0.97);
}

TEST(FrontendDataTest, MiddleburyStereoAloe) {
  const std::string dir = DataDir() + "/middlebury/";
  const GrayImage left = MustLoad(dir + "aloeL.jpg");
  const GrayImage right = MustLoad(dir + "aloeR.jpg");
  GrayImage truth;
  std::string error;
  ASSERT_TRUE(image_io::LoadChannel0(dir + "aloeGT.png", &truth, &error)) << error;
  ASSERT_EQ(truth.width, left.width);
  ASSERT_EQ(truth.height, left.height);
  auto detector = std::make_unique<HarrisDetector>();
  ASSERT_EQ(detector->Configure(DetectorFor(left.width, left.height)), core::Status::kOk);
  CornerList corners;
  ASSERT_EQ(detector->Detect(left.View(), nullptr, 0, &corners), core::Status::kOk);
  StereoMatcher matcher;
  StereoMatcherOptions options;
  options.max_disparity = 160;
  ASSERT_EQ(matcher.Configure(options), core::Status::kOk);
  auto matches = std::make_unique<StereoMatchList>();
  ASSERT_EQ(matcher.MatchAll(left.View(), right.View(), corners, matches.get()), core::Status::kOk);
  std::size_t with_truth = 0;
  for (const Corner& c : corners) {
    with_truth += truth.pixels[static_cast<std::size_t>(c.y) * truth.width + c.x] > 0;
  }
  std::vector<double> errors;
  for (const StereoMatch& m : *matches) {
    const int gt = truth.pixels[static_cast<std::size_t>(m.y) * truth.width + m.x];
    if (gt == 0) continue;
    errors.push_back(std::fabs(m.disparity - gt));
  }
  std::printf(
      "stereo aloe: %zu corners (%zu with ground truth), %zu matched with truth "
      "(%.1f%%), median |disparity error| %.3f px, within 1 px %.1f%%\n",
      corners.size(), with_truth, errors.size(),
      100.0 * errors.size() / std::max<std::size_t>(1, with_truth), Median(errors),
      100.0 * FractionBelow(errors, 1.0));
  EXPECT_GE(errors.size(), with_truth * 65 / 100);
  EXPECT_LE(Median(errors), 0.45);  // the ground truth is quantised to whole pixels
  EXPECT_GE(FractionBelow(errors, 1.0), 0.90);
}

// GIVEN the real EuRoC V1_01 rig and its 40 stereo pairs WHEN rectifying with sensor.yaml and
// running the front end without a pose prediction THEN landmarks are tracked through the sequence.
TEST(FrontendDataTest, EurocRectifyAndTrackAllFrames) {
  const std::string dir = DataDir() + "/euroc-v101/mav0/";
  CameraCalibration cal[2];
  std::string error;
  ASSERT_TRUE(image_io::LoadCalibration(dir + "cam0/sensor.yaml", &cal[0], &error)) << error;
  ASSERT_TRUE(image_io::LoadCalibration(dir + "cam1/sensor.yaml", &cal[1], &error)) << error;
  auto rectifier = std::make_unique<StereoRectifier>();
  ASSERT_EQ(rectifier->Configure(cal[0], cal[1], RectifyOptions{}), core::Status::kOk);
  std::vector<std::string> names;
  {
    std::ifstream csv(dir + "cam0/data.csv");
    std::string line;
    while (std::getline(csv, line)) {
      if (line.empty() || line[0] == '#') continue;
      names.push_back(line.substr(line.find(',') + 1));
      while (!names.back().empty() && (names.back().back() == '\r' || names.back().back() == ' ')) {
        names.back().pop_back();
      }
    }
  }
  ASSERT_EQ(names.size(), 40u);
  FrontendOptions options;
  options.camera = rectifier->Camera();
  options.harris = DetectorFor(rectifier->Width(), rectifier->Height());
  options.max_tracks = 300;
  auto frontend = std::make_unique<Frontend>();
  ASSERT_EQ(frontend->Configure(options), core::Status::kOk);
  auto out = std::make_unique<FrameOutput>();
  GrayImage rl;
  GrayImage rr;
  rl.Resize(rectifier->Width(), rectifier->Height());
  rr.Resize(rectifier->Width(), rectifier->Height());
  std::map<std::uint32_t, int> length;
  std::vector<double> per_frame;
  std::string counts;
  std::size_t rejected = 0;
  for (const std::string& name : names) {
    const GrayImage l = MustLoad(dir + "cam0/data/" + name);
    const GrayImage r = MustLoad(dir + "cam1/data/" + name);
    ASSERT_EQ(rectifier->Rectify(l.View(), r.View(), rl.MutableView(), rr.MutableView()),
              core::Status::kOk);
    ASSERT_EQ(
        frontend->ProcessFrame(StereoFrame{rl.View(), rr.View()}, FramePrediction{}, out.get()),
        core::Status::kOk);
    for (const StereoMeasurement& m : out->measurements) ++length[m.landmark_id];
    for (const NewLandmark& n : out->new_landmarks) length[n.landmark_id] = 1;
    rejected += out->stats.rejected_consistency;
    per_frame.push_back(static_cast<double>(out->measurements.size()));
    counts += std::to_string(out->measurements.size()) + " ";
  }
  std::vector<double> lengths;
  std::size_t long_tracks = 0;
  std::size_t full = 0;
  for (const auto& [id, n] : length) {
    lengths.push_back(n);
    long_tracks += n >= 30;
    full += n == 40;
  }
  per_frame.erase(per_frame.begin());  // frame 0 only initialises
  std::printf(
      "euroc: rectified f=%.2f px baseline=%.4f m; tracked per frame (frames 1-39): "
      "median %.0f, min %.0f; landmarks %zu, median track length %.0f frames, >= 30 "
      "frames: %zu, all 40: %zu, removed by consistency: %zu\n  per frame: %s\n",
      rectifier->Camera().fx, rectifier->Camera().baseline_m, Median(per_frame),
      *std::min_element(per_frame.begin(), per_frame.end()), lengths.size(), Median(lengths),
      long_tracks, full, rejected, counts.c_str());
  EXPECT_GE(Median(per_frame), 250.0);
  EXPECT_GE(*std::min_element(per_frame.begin(), per_frame.end()), 200.0);
  EXPECT_GE(long_tracks, 200u);
}

}  // namespace
}  // namespace swf::frontend
