#include "swf/frontend/stereo_matcher.hpp"

#include <gtest/gtest.h>

#include <cmath>
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

class StereoSubpixelTest : public ::testing::TestWithParam<double> {};

// GIVEN an exactly known subpixel disparity WHEN matching THEN median error <= 0.015 px
// (measured 0.006-0.008 px).
TEST_P(StereoSubpixelTest, MedianErrorBelowFifteenThousandthsPixel) {
  const double truth = GetParam();
  const Pair pair = MakePair(truth, 7);
  const CornerList corners = testing::DetectCorners(pair.left);
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
  const CornerList corners = testing::DetectCorners(left);
  StereoMatcher matcher;
  ASSERT_EQ(matcher.Configure(StereoMatcherOptions{}), core::Status::kOk);
  StereoMatchList matches;
  ASSERT_EQ(matcher.MatchAll(left.View(), right.View(), corners, &matches), core::Status::kOk);
  EXPECT_LE(matches.size(), corners.size() / 4);
}

// GIVEN a right image that holds, besides the true match at disparity 10.5 (between integers),
// an exact copy of a strip of the left image at disparity 58 (a look-alike, as rocks of one
// size and light on a row are), both with sensor noise, WHEN matching the left features in that
// strip THEN without the ambiguity check the copy's lower integer SAD wins and passes the
// left-right check and the ZNCC gate, and with it the features are rejected as ambiguous, none at a
// wrong disparity.
TEST(StereoMatcherTest, RejectsALookAlikeThatBeatsTheTrueMatch) {
  const testing::Texture texture(7);
  TestImage left = texture.RenderShifted<TestImage>(400, 240, 0.0, 0.0);
  TestImage right = texture.RenderShifted<TestImage>(400, 240, -10.5, 0.0);
  constexpr int kCopyFrom = 100;  // right columns [100, 140) = left columns [158, 198)
  constexpr int kCopyTo = 140;
  constexpr int kLookAlike = 58;
  for (int y = 0; y < right.height; ++y) {
    for (int x = kCopyFrom; x < kCopyTo; ++x) {
      right.pixels[static_cast<std::size_t>(y) * right.width + x] =
          left.pixels[static_cast<std::size_t>(y) * left.width + x + kLookAlike];
    }
  }
  // Independent sensor noise in each image (uniform +-3 DN, a fixed hash): no real camera sees a
  // pixel-exact copy.
  std::uint32_t h = 12345u;
  for (TestImage* img : {&left, &right}) {
    for (std::uint8_t& p : img->pixels) {
      h = h * 1664525u + 1013904223u;
      const int v = p + static_cast<int>((h >> 24) % 7u) - 3;
      p = static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
  }
  // Left features whose look-alike patch lies inside the copy and whose true match outside it.
  CornerList strip;
  for (const Corner& c : testing::DetectCorners(left)) {
    const int x = static_cast<int>(c.x);
    if (x >= kCopyFrom + kLookAlike + 5 && x + 5 < kCopyTo + kLookAlike && x - 11 - 5 >= kCopyTo) {
      (void)strip.push_back(c);
    }
  }
  ASSERT_GE(strip.size(), 5u);
  auto match = [&](float sad_ratio, std::size_t* wrong) {
    StereoMatcherOptions o;
    o.ambiguity_sad_ratio = sad_ratio;
    StereoMatcher matcher;
    EXPECT_EQ(matcher.Configure(o), core::Status::kOk);
    StereoMatchList matches;
    EXPECT_EQ(matcher.MatchAll(left.View(), right.View(), strip, &matches), core::Status::kOk);
    *wrong = 0;
    for (const StereoMatch& m : matches) *wrong += std::fabs(m.disparity - 10.5f) > 1.0f;
    return matches.size();
  };
  std::size_t wrong_off = 0;
  std::size_t wrong_on = 0;
  const std::size_t off = match(-1.0f, &wrong_off);
  const std::size_t on = match(StereoMatcherOptions{}.ambiguity_sad_ratio, &wrong_on);
  std::printf("look-alike strip, %zu features: check off %zu matched (%zu wrong), on %zu (%zu)\n",
              strip.size(), off, wrong_off, on, wrong_on);
  EXPECT_GE(wrong_off, strip.size() / 2);  // the failure the check exists for
  EXPECT_EQ(wrong_on, 0u);
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
  o = StereoMatcherOptions{};
  o.ambiguity_zncc_margin = -0.1f;
  EXPECT_EQ(matcher.Configure(o), core::Status::kInvalidArgument);
  o = StereoMatcherOptions{};
  o.ambiguity_sad_ratio = std::nanf("");
  EXPECT_EQ(matcher.Configure(o), core::Status::kInvalidArgument);
  o.ambiguity_sad_ratio = -1.0f;  // off
  EXPECT_EQ(matcher.Configure(o), core::Status::kOk);
}

}  // namespace
}  // namespace swf::frontend
