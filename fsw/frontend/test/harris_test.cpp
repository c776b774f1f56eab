#include "swf/frontend/harris.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "swf/testing/allocation_counter.hpp"
#include "synthetic.hpp"

namespace swf::frontend {
namespace {

using testing::Render;
using testing::TestImage;

// GIVEN bright squares on a dark background WHEN detecting THEN corners sit on square corners.
TEST(HarrisTest, FindsCornersOfSquares) {
  const TestImage img = Render(320, 240, [](double x, double y) {
    const int cx = static_cast<int>(x) / 40;
    const int cy = static_cast<int>(y) / 40;
    const bool in_square = static_cast<int>(x) % 40 >= 10 && static_cast<int>(x) % 40 < 30 &&
                           static_cast<int>(y) % 40 >= 10 && static_cast<int>(y) % 40 < 30;
    return in_square ? 60.0 + 20.0 * ((cx + cy) % 3) + 100.0 : 40.0;
  });
  auto detector = std::make_unique<HarrisDetector>();
  HarrisOptions options;
  options.bucket_cols = 8;
  options.bucket_rows = 6;
  options.max_per_bucket = 4;
  ASSERT_EQ(detector->Configure(options), core::Status::kOk);
  CornerList corners;
  ASSERT_EQ(detector->Detect(img.View(), nullptr, 0, &corners), core::Status::kOk);
  ASSERT_GE(corners.size(), 100u);
  for (const Corner& c : corners) {
    // Square corners are at x mod 40 in {10, 30} (the edge between pixel 9|10 and 29|30).
    const double mx = std::fmod(c.x, 40.0);
    const double my = std::fmod(c.y, 40.0);
    const double ex = std::min(std::fabs(mx - 9.5), std::fabs(mx - 29.5));
    const double ey = std::min(std::fabs(my - 9.5), std::fabs(my - 29.5));
    EXPECT_LE(ex, 1.5) << c.x << "," << c.y;
    EXPECT_LE(ey, 1.5) << c.x << "," << c.y;
  }
}

TEST(HarrisTest, BucketingCoversTheImageAndRespectsQuota) {
  const testing::Texture texture(3);
  const TestImage img = texture.RenderShifted<TestImage>(640, 480, 0.0, 0.0);
  auto detector = std::make_unique<HarrisDetector>();
  HarrisOptions options;  // 16 x 12 buckets, 2 each
  ASSERT_EQ(detector->Configure(options), core::Status::kOk);
  CornerList corners;
  ASSERT_EQ(detector->Detect(img.View(), nullptr, 0, &corners), core::Status::kOk);
  int per_bucket[16 * 12] = {};
  for (const Corner& c : corners) {
    ++per_bucket[static_cast<int>(c.y) * 12 / 480 * 16 + static_cast<int>(c.x) * 16 / 640];
  }
  int filled = 0;
  for (int b : per_bucket) {
    EXPECT_LE(b, 2);
    filled += b > 0;
  }
  EXPECT_GE(filled, 16 * 12 * 9 / 10);  // texture everywhere -> corners everywhere

  // Occupied points use up their bucket's quota and repel new corners.
  Point2f occupied[2] = {{corners[0].x, corners[0].y}, {corners[0].x + 3.0f, corners[0].y}};
  CornerList again;
  ASSERT_EQ(detector->Detect(img.View(), occupied, 2, &again), core::Status::kOk);
  for (const Corner& c : again) {
    EXPECT_FALSE(c.x == corners[0].x && c.y == corners[0].y);
  }
  EXPECT_LE(again.size(), corners.size() - 1);
}

// GIVEN buckets already full of tracks WHEN detecting THEN only the other buckets are searched,
// and their corners are exactly those a search of the whole image finds there.
TEST(HarrisTest, SearchingOnlyOpenBucketsFindsTheSameCorners) {
  const testing::Texture texture(5);
  const TestImage img = texture.RenderShifted<TestImage>(640, 480, 0.0, 0.0);
  auto detector = std::make_unique<HarrisDetector>();
  HarrisOptions options;  // 16 x 12 buckets, 2 each
  options.quality_level = 0.0f;
  options.min_distance_px = 0.0f;
  ASSERT_EQ(detector->Configure(options), core::Status::kOk);
  CornerList all;
  ASSERT_EQ(detector->Detect(img.View(), nullptr, 0, &all), core::Status::kOk);
  // Fill every bucket except a scattered set (2 tracks at each full bucket's centre).
  auto open = [](int bx, int by) { return (bx * 7 + by * 3) % 5 == 0 || (bx == 15 && by == 11); };
  std::vector<Point2f> occupied;
  for (int by = 0; by < 12; ++by) {
    for (int bx = 0; bx < 16; ++bx) {
      if (open(bx, by)) continue;
      const Point2f p{40.0f * bx + 20.0f, 40.0f * by + 20.0f};
      occupied.push_back(p);
      occupied.push_back(p);
    }
  }
  CornerList some;
  swf::testing::AllocationScope scope;
  ASSERT_EQ(detector->Detect(img.View(), occupied.data(), occupied.size(), &some),
            core::Status::kOk);
  EXPECT_EQ(scope.Count(), 0u);
  std::vector<Corner> expected;
  for (const Corner& c : all) {
    if (open(static_cast<int>(c.x) / 40, static_cast<int>(c.y) / 40)) expected.push_back(c);
  }
  ASSERT_GE(expected.size(), 40u);
  ASSERT_EQ(some.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(some[i].x, expected[i].x);
    EXPECT_EQ(some[i].y, expected[i].y);
    EXPECT_EQ(some[i].response, expected[i].response);
  }
}

TEST(HarrisTest, BlankImageHasNoCornersAndNoAllocation) {
  const TestImage img(200, 150);
  auto detector = std::make_unique<HarrisDetector>();
  ASSERT_EQ(detector->Configure(HarrisOptions{}), core::Status::kOk);
  CornerList corners;
  swf::testing::AllocationScope scope;
  ASSERT_EQ(detector->Detect(img.View(), nullptr, 0, &corners), core::Status::kOk);
  EXPECT_EQ(corners.size(), 0u);
  EXPECT_EQ(scope.Count(), 0u);
}

TEST(HarrisTest, RejectsBadOptionsAndImages) {
  auto detector = std::make_unique<HarrisDetector>();
  HarrisOptions bad;
  bad.max_per_bucket = kMaxCandidatesPerBucket + 1;
  EXPECT_EQ(detector->Configure(bad), core::Status::kInvalidArgument);
  CornerList corners;
  const TestImage img(100, 100);
  EXPECT_EQ(detector->Detect(img.View(), nullptr, 0, &corners), core::Status::kNotConfigured);
  ASSERT_EQ(detector->Configure(HarrisOptions{}), core::Status::kOk);
  const TestImage tiny(10, 10);
  EXPECT_EQ(detector->Detect(tiny.View(), nullptr, 0, &corners), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::frontend
