#include "swf/frontend/stereo_matcher.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "swf/testing/allocation_counter.hpp"
#include "synthetic.hpp"

namespace swf::frontend {
namespace {

using testing::Median;
using testing::Render;
using testing::TestImage;

struct Pair {
  TestImage left;
  TestImage right;
};

// Right image of a fronto-parallel scene: uR = uL - d, so right(x, y) = T(x + d, y).
Pair MakePair(double disparity, std::uint32_t seed) {
  const testing::Texture texture(seed);
  return Pair{texture.RenderShifted<TestImage>(400, 240, 0.0, 0.0),
              texture.RenderShifted<TestImage>(400, 240, -disparity, 0.0)};
}

CornerList Detect(const TestImage& img) {
  auto detector = std::make_unique<HarrisDetector>();
  EXPECT_EQ(detector->Configure(HarrisOptions{}), core::Status::kOk);
  CornerList corners;
  EXPECT_EQ(detector->Detect(img.View(), nullptr, 0, &corners), core::Status::kOk);
  return corners;
}

class StereoSubpixelTest : public ::testing::TestWithParam<double> {};

// GIVEN an exactly known subpixel disparity WHEN matching THEN median error <= 0.015 px
// (measured 0.006-0.008 px).
TEST_P(StereoSubpixelTest, MedianErrorBelowFifteenThousandthsPixel) {
  const double truth = GetParam();
  const Pair pair = MakePair(truth, 7);
  const CornerList corners = Detect(pair.left);
  ASSERT_GE(corners.size(), 100u);
  StereoMatcher matcher;
  ASSERT_EQ(matcher.Configure(StereoMatcherOptions{}), core::Status::kOk);
  StereoMatchList matches;
  swf::testing::AllocationScope scope;
  ASSERT_EQ(matcher.MatchAll(pair.left.View(), pair.right.View(), corners, &matches),
            core::Status::kOk);
  EXPECT_EQ(scope.Count(), 0u);
  // Corners near the left edge cannot be matched (their partner is outside the right image).
  EXPECT_GE(matches.size(), corners.size() * 8 / 10);
  std::vector<double> errors;
  for (const StereoMatch& m : matches) errors.push_back(std::fabs(m.disparity - truth));
  const double median = Median(errors);
  std::printf("disparity %.2f: %zu matched, median error %.4f px\n", truth, matches.size(), median);
  EXPECT_LE(median, 0.015) << "disparity " << truth;
  std::sort(errors.begin(), errors.end());
  EXPECT_LE(errors[errors.size() * 9 / 10], 0.3);
}

INSTANTIATE_TEST_SUITE_P(Disparities, StereoSubpixelTest,
                         ::testing::Values(0.3, 7.25, 12.5, 23.71, 60.9));

// GIVEN a right image of a different scene WHEN matching THEN the left-right check and the ZNCC
// gate reject nearly everything.
TEST(StereoMatcherTest, RejectsUnrelatedImages) {
  const testing::Texture a(11);
  const testing::Texture b(12);
  const TestImage left = a.RenderShifted<TestImage>(400, 240, 0.0, 0.0);
  const TestImage right = b.RenderShifted<TestImage>(400, 240, 0.0, 0.0);
  const CornerList corners = Detect(left);
  StereoMatcher matcher;
  ASSERT_EQ(matcher.Configure(StereoMatcherOptions{}), core::Status::kOk);
  StereoMatchList matches;
  ASSERT_EQ(matcher.MatchAll(left.View(), right.View(), corners, &matches), core::Status::kOk);
  EXPECT_LE(matches.size(), corners.size() / 4);
}

TEST(StereoMatcherTest, RefineDisparityConvergesFromOffGuess) {
  const Pair pair = MakePair(9.4, 5);
  StereoMatcher matcher;
  ASSERT_EQ(matcher.Configure(StereoMatcherOptions{}), core::Status::kOk);
  float d = 10.2f;  // 0.8 px off
  float q = 0.0f;
  ASSERT_TRUE(matcher.RefineDisparity(pair.left.View(), pair.right.View(), 200.3f, 120.6f, &d, &q));
  EXPECT_NEAR(d, 9.4, 0.1);
  EXPECT_GT(q, 0.95f);
}

TEST(StereoMatcherTest, RejectsBadOptions) {
  StereoMatcher matcher;
  StereoMatcherOptions o;
  o.max_disparity = kMaxDisparity + 1;
  EXPECT_EQ(matcher.Configure(o), core::Status::kInvalidArgument);
  o = StereoMatcherOptions{};
  o.patch_radius = 0;
  EXPECT_EQ(matcher.Configure(o), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::frontend
