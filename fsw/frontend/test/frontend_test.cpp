#include "swf/frontend/frontend.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <memory>

#include "swf/testing/allocation_counter.hpp"
#include "synthetic.hpp"

namespace swf::frontend {
namespace {

using testing::Median;
using testing::Render;
using testing::TestImage;

constexpr int kW = 480;
constexpr int kH = 360;
constexpr double kDisparity = 14.3;
constexpr double kShiftX = 1.7;  // per frame
constexpr double kShiftY = -0.9;

struct Frame {
  TestImage left;
  TestImage right;
};

std::vector<Frame> MakeSequence(int frames) {
  const testing::Texture texture(77);
  std::vector<Frame> seq;
  for (int k = 0; k < frames; ++k) {
    const double ox = k * kShiftX;
    const double oy = k * kShiftY;
    seq.push_back(Frame{texture.RenderShifted<TestImage>(kW, kH, ox, oy),
                        texture.RenderShifted<TestImage>(kW, kH, ox - kDisparity, oy)});
  }
  return seq;
}

FrontendOptions Options() {
  FrontendOptions o;
  o.camera.fx = o.camera.fy = 400.0;
  o.camera.cx = kW / 2.0;
  o.camera.cy = kH / 2.0;
  o.camera.baseline_m = 0.2;
  o.max_tracks = 250;
  return o;
}

// GIVEN a sequence with exactly known subpixel motion and disparity WHEN the front end runs
// without a pose prediction THEN it keeps ~all tracks, measures them with median error <= 0.1 px
// and allocates nothing per frame.
TEST(FrontendTest, TracksSyntheticSequenceSubpixelWithoutAllocation) {
  const std::vector<Frame> seq = MakeSequence(6);
  auto frontend = std::make_unique<Frontend>();
  ASSERT_EQ(frontend->Configure(Options()), core::Status::kOk);
  auto out = std::make_unique<FrameOutput>();
  std::map<std::uint32_t, std::pair<double, double>> origin;  // id -> (x, y) at frame of birth
  std::map<std::uint32_t, int> birth;
  std::vector<double> position_errors;
  std::vector<double> disparity_errors;
  std::uint64_t allocations = 0;
  for (int k = 0; k < static_cast<int>(seq.size()); ++k) {
    const StereoFrame frame{seq[k].left.View(), seq[k].right.View()};
    {
      swf::testing::AllocationScope scope;
      ASSERT_EQ(frontend->ProcessFrame(frame, FramePrediction{}, out.get()), core::Status::kOk);
      allocations += scope.Count();
    }
    if (k > 0) {
      EXPECT_GE(out->measurements.size(), 200u) << "frame " << k;
      EXPECT_LE(out->stats.lost_tracking + out->stats.lost_stereo + out->stats.rejected_consistency,
                out->stats.tracks_in / 20);
    }
    for (const StereoMeasurement& m : out->measurements) {
      const auto [x0, y0] = origin.at(m.landmark_id);
      const int age = k - birth.at(m.landmark_id);
      position_errors.push_back(
          std::hypot(m.u_left - (x0 + age * kShiftX), m.v - (y0 + age * kShiftY)));
      disparity_errors.push_back(std::fabs(m.u_left - m.u_right - kDisparity));
    }
    for (const NewLandmark& n : out->new_landmarks) {
      origin[n.landmark_id] = {n.u_left, n.v};
      birth[n.landmark_id] = k;
      EXPECT_NEAR(n.p_camera.z(), 400.0 * 0.2 / kDisparity, 0.05);
    }
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_LE(Median(position_errors), 0.1);
  EXPECT_LE(Median(disparity_errors), 0.1);
  EXPECT_GE(frontend->NumTracks(), 240u);
}

// GIVEN the same input twice WHEN two front ends process it THEN the outputs are bit-identical.
TEST(FrontendTest, OutputIsBitIdenticalOnRepeat) {
  const std::vector<Frame> seq = MakeSequence(3);
  auto a = std::make_unique<Frontend>();
  auto b = std::make_unique<Frontend>();
  ASSERT_EQ(a->Configure(Options()), core::Status::kOk);
  ASSERT_EQ(b->Configure(Options()), core::Status::kOk);
  auto out_a = std::make_unique<FrameOutput>();
  auto out_b = std::make_unique<FrameOutput>();
  for (const Frame& f : seq) {
    const StereoFrame frame{f.left.View(), f.right.View()};
    ASSERT_EQ(a->ProcessFrame(frame, FramePrediction{}, out_a.get()), core::Status::kOk);
    ASSERT_EQ(b->ProcessFrame(frame, FramePrediction{}, out_b.get()), core::Status::kOk);
    ASSERT_EQ(out_a->measurements.size(), out_b->measurements.size());
    ASSERT_EQ(out_a->new_landmarks.size(), out_b->new_landmarks.size());
    for (std::size_t i = 0; i < out_a->measurements.size(); ++i) {
      const StereoMeasurement& ma = out_a->measurements[i];
      const StereoMeasurement& mb = out_b->measurements[i];
      EXPECT_EQ(ma.landmark_id, mb.landmark_id);
      EXPECT_EQ(std::memcmp(&ma.u_left, &mb.u_left, sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&ma.u_right, &mb.u_right, sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&ma.v, &mb.v, sizeof(double)), 0);
    }
    for (std::size_t i = 0; i < out_a->new_landmarks.size(); ++i) {
      EXPECT_EQ(std::memcmp(out_a->new_landmarks[i].p_camera.data(),
                            out_b->new_landmarks[i].p_camera.data(), 3 * sizeof(double)),
                0);
    }
  }
}

TEST(FrontendTest, RejectsBadInput) {
  auto frontend = std::make_unique<Frontend>();
  auto out = std::make_unique<FrameOutput>();
  const TestImage img(64, 64);
  const StereoFrame frame{img.View(), img.View()};
  EXPECT_EQ(frontend->ProcessFrame(frame, FramePrediction{}, out.get()),
            core::Status::kNotConfigured);
  FrontendOptions bad = Options();
  bad.camera.baseline_m = 0.0;
  EXPECT_EQ(frontend->Configure(bad), core::Status::kInvalidArgument);
  ASSERT_EQ(frontend->Configure(Options()), core::Status::kOk);
  const TestImage other(32, 64);
  EXPECT_EQ(
      frontend->ProcessFrame(StereoFrame{img.View(), other.View()}, FramePrediction{}, out.get()),
      core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::frontend
