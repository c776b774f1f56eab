#include "swf/frontend/tracker.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <vector>

#include "swf/frontend/harris.hpp"
#include "swf/testing/allocation_counter.hpp"
#include "synthetic.hpp"

namespace swf::frontend {
namespace {

using testing::Median;
using testing::Render;
using testing::TestImage;

struct FlowCase {
  double dx;
  double dy;
};

class FlowSubpixelTest : public ::testing::TestWithParam<FlowCase> {};

// Median endpoint error of pyramidal LK over the corners of a texture moved by `shift`.
double FlowMedian(const FlowCase& shift, bool brightness_offset) {
  const testing::Texture texture(21);
  const TestImage a = texture.RenderShifted<TestImage>(400, 300, 0.0, 0.0);
  const TestImage b = texture.RenderShifted<TestImage>(400, 300, shift.dx, shift.dy);
  auto prev = std::make_unique<Pyramid>();
  auto cur = std::make_unique<Pyramid>();
  EXPECT_EQ(prev->Build(a.View(), 3), core::Status::kOk);
  EXPECT_EQ(cur->Build(b.View(), 3), core::Status::kOk);
  PatchTracker tracker;
  TrackerOptions options;
  options.brightness_offset = brightness_offset;
  EXPECT_EQ(tracker.Configure(options), core::Status::kOk);
  const CornerList corners = testing::DetectCorners(a);
  EXPECT_GE(corners.size(), 100u);
  std::vector<double> errors;
  errors.reserve(corners.size());
  std::size_t tracked = 0;
  std::size_t trackable = 0;  // destination at least one patch inside the image
  {
    swf::testing::AllocationScope scope;
    for (const Corner& c : corners) {
      const double tx = c.x + shift.dx;
      const double ty = c.y + shift.dy;
      if (tx < 8 || ty < 8 || tx > 392 || ty > 292) continue;
      ++trackable;
      float x = c.x;
      float y = c.y;
      float q = 0.0f;
      if (!tracker.TrackFlow(*prev, *cur, c.x, c.y, &x, &y, &q)) continue;
      ++tracked;
      errors.push_back(std::hypot(x - c.x - shift.dx, y - c.y - shift.dy));
    }
    EXPECT_EQ(scope.Count(), 0u);
  }
  EXPECT_GE(tracked, trackable * 95 / 100);
  return Median(errors);
}

// GIVEN a texture moved by an exactly known subpixel shift WHEN tracking with pyramidal LK
// THEN the median endpoint error is a few hundredths of a pixel with the per-patch brightness
// offset, and lower with constant brightness (the model that holds here).
TEST_P(FlowSubpixelTest, MedianEndpointErrorBelowTwoHundredthsPixel) {
  const FlowCase shift = GetParam();
  const double with_offset = FlowMedian(shift, true);
  const double constant = FlowMedian(shift, false);
  std::printf("shift (%.2f, %.2f): median endpoint error %.4f px with offset, %.4f px without\n",
              shift.dx, shift.dy, with_offset, constant);
  EXPECT_LE(with_offset, 0.02);
  EXPECT_LE(constant, 0.02);
  EXPECT_LE(constant, with_offset);
}

INSTANTIATE_TEST_SUITE_P(Shifts, FlowSubpixelTest,
                         ::testing::Values(FlowCase{0.37, -0.21}, FlowCase{2.6, 1.3},
                                           FlowCase{-6.45, 4.2}, FlowCase{11.3, -8.8}));

TEST(PlaneHomographyTest, MapsPlanePointsLikeTheCameras) {
  estimator::StereoCamera<double> cam;
  cam.fx = 450.0;
  cam.fy = 452.0;
  cam.cx = 320.0;
  cam.cy = 241.0;
  cam.baseline_m = 0.1;
  estimator::Pose<double> cur_T_ref;
  cur_T_ref.R = estimator::ExpSO3<double>(estimator::Vec3<double>(0.05, -0.1, 0.2));
  cur_T_ref.t = estimator::Vec3<double>(0.3, -0.2, -1.0);
  const double depth = 7.5;
  const Eigen::Matrix3d h = PlaneHomography(cam, cur_T_ref, depth);
  for (double x : {-2.0, 0.0, 1.5}) {
    for (double y : {-1.0, 0.5, 2.0}) {
      const estimator::Vec3<double> p_ref(x, y, depth);
      const estimator::Vec3<double> z_ref = cam.Project(p_ref);
      const estimator::Vec3<double> z_cur = cam.Project(cur_T_ref.Apply(p_ref));
      const Eigen::Vector3d m = h * Eigen::Vector3d(z_ref.x(), z_ref.z(), 1.0);
      EXPECT_NEAR(m.x() / m.z(), z_cur.x(), 1e-9);
      EXPECT_NEAR(m.y() / m.z(), z_cur.z(), 1e-9);
    }
  }
}

// Reference -> current view: rotation by 15 deg and scale 1.2 about (200, 150), a slight
// shift and perspective (paper 4.1.2: descent imagery).
Eigen::Matrix3d RotatedAndScaled() {
  Eigen::Matrix3d h;
  const double c = 1.2 * std::cos(0.26);
  const double s = 1.2 * std::sin(0.26);
  h << c, -s, 200.0 - c * 200.0 + s * 150.0 + 3.3, s, c, 150.0 - s * 200.0 - c * 150.0 - 2.1, 1e-5,
      -2e-5, 1.0;
  return h;
}

// The 400 x 300 view of `texture` that the reference -> current homography `h` makes.
TestImage RenderWarped(const testing::Texture& texture, const Eigen::Matrix3d& h) {
  const Eigen::Matrix3d h_inv = h.inverse();
  return Render(400, 300, [&](double x, double y) {
    const Eigen::Vector3d p = h_inv * Eigen::Vector3d(x, y, 1.0);
    return texture(p.x() / p.z(), p.y() / p.z());
  });
}

// A corner of the reference view and its true position in the warped view.
struct WarpedCorner {
  Corner corner;
  double x = 0.0;
  double y = 0.0;
};

// The corners of `a` that the homography h takes at least `margin` px inside the 400 x 300 view.
std::vector<WarpedCorner> CornersInside(const TestImage& a, const Eigen::Matrix3d& h,
                                        double margin) {
  std::vector<WarpedCorner> inside;
  for (const Corner& corner : testing::DetectCorners(a)) {
    const Eigen::Vector3d t = h * Eigen::Vector3d(corner.x, corner.y, 1.0);
    const double x = t.x() / t.z();
    const double y = t.y() / t.z();
    if (x < margin || y < margin || x > 400 - margin || y > 300 - margin) continue;
    inside.push_back({corner, x, y});
  }
  return inside;
}

// A textured view and the same texture rotated by 15 deg and scaled by 1.2 (paper 4.1.2: descent
// imagery), h taking the first to the second.
class WarpedViewTest : public ::testing::Test {
 protected:
  const testing::Texture texture_{33};
  const TestImage a_ = texture_.RenderShifted<TestImage>(400, 300, 0.0, 0.0);
  const Eigen::Matrix3d h_ = RotatedAndScaled();
  const TestImage b_ = RenderWarped(texture_, h_);
};

// GIVEN the rotated and scaled view WHEN tracking the reference patches warped by the true
// homography THEN the error is subpixel-accurate, and better than square-patch tracking of the
// same features.
TEST_F(WarpedViewTest, WarpedTrackingBeatsSquarePatches) {
  PatchTracker tracker;
  ASSERT_EQ(tracker.Configure(TrackerOptions{}), core::Status::kOk);
  const std::vector<WarpedCorner> candidates = CornersInside(a_, h_, 20);
  std::vector<double> warped_errors;
  std::vector<double> square_errors;
  for (const auto& [corner, tx, ty] : candidates) {
    PatchTemplate tmpl;
    ASSERT_TRUE(tracker.ExtractTemplate(a_.View(), corner.x, corner.y, &tmpl));
    // Prediction off by (0.8, -0.6) px, as from a noisy pose.
    float x = static_cast<float>(tx + 0.8);
    float y = static_cast<float>(ty - 0.6);
    float q = 0.0f;
    if (tracker.TrackWarped(b_.View(), tmpl, h_, &x, &y, &q)) {
      warped_errors.push_back(std::hypot(x - tx, y - ty));
    }
    // Square patch: the same template with a pure translation as the warp.
    Eigen::Matrix3d translation = Eigen::Matrix3d::Identity();
    translation(0, 2) = tx - corner.x;
    translation(1, 2) = ty - corner.y;
    x = static_cast<float>(tx + 0.8);
    y = static_cast<float>(ty - 0.6);
    if (tracker.TrackWarped(b_.View(), tmpl, translation, &x, &y, &q)) {
      square_errors.push_back(std::hypot(x - tx, y - ty));
    }
  }
  ASSERT_GE(candidates.size(), 50u);
  EXPECT_GE(warped_errors.size(), candidates.size() * 9 / 10);
  EXPECT_LE(Median(warped_errors), 0.1);
  std::printf("warped: %zu tracked, median %.3f px; square: %zu tracked, median %.3f px\n",
              warped_errors.size(), Median(warped_errors), square_errors.size(),
              Median(square_errors));
  EXPECT_GT(Median(square_errors), 3.0 * Median(warped_errors));
}

// GIVEN the rotated and scaled view and a prediction 9 px off (beyond warped LK's reach for some
// features; a 10 px search radius) WHEN LK is started there THEN the search around the
// prediction (SearchWarped) finds those too, with subpixel error, without allocating.
TEST_F(WarpedViewTest, SearchRecoversWhatWarpedLkLoses) {
  PatchTracker tracker;
  TrackerOptions options;
  options.search_radius_px = 10;
  ASSERT_EQ(tracker.Configure(options), core::Status::kOk);
  const std::vector<WarpedCorner> candidates = CornersInside(a_, h_, 30);
  std::size_t lk_right = 0;  // LK alone ends within 0.5 px of the truth
  std::vector<double> search_errors;
  std::uint64_t allocations = 0;
  for (const auto& [corner, tx, ty] : candidates) {
    PatchTemplate tmpl;
    ASSERT_TRUE(tracker.ExtractTemplate(a_.View(), corner.x, corner.y, &tmpl));
    const float px = static_cast<float>(tx + 7.2);
    const float py = static_cast<float>(ty - 5.4);
    float x = px;
    float y = py;
    float q = 0.0f;
    if (tracker.TrackWarped(b_.View(), tmpl, h_, &x, &y, &q) && std::hypot(x - tx, y - ty) < 0.5) {
      ++lk_right;
    }
    x = px;
    y = py;
    swf::testing::AllocationScope scope;
    const bool found = tracker.SearchWarped(b_.View(), tmpl, h_, &x, &y, &q);
    allocations += scope.Count();
    if (found) search_errors.push_back(std::hypot(x - tx, y - ty));
  }
  std::printf(
      "prediction 9 px off: LK alone right for %zu of %zu, the search found %zu, "
      "median %.3f px\n",
      lk_right, candidates.size(), search_errors.size(), Median(search_errors));
  ASSERT_GE(candidates.size(), 50u);
  EXPECT_EQ(allocations, 0u);
  EXPECT_GE(search_errors.size(), candidates.size() * 9 / 10);
  EXPECT_GE(search_errors.size(), lk_right + 5);  // measured: 186 against 177
  EXPECT_LE(Median(search_errors), 0.1);
}

// Reference -> current view: a zoom by m about (200, 150), the descent's focus of expansion.
Eigen::Matrix3d ZoomAboutCentre(double m) {
  Eigen::Matrix3d h = Eigen::Matrix3d::Identity();
  h(0, 0) = m;
  h(1, 1) = m;
  h(0, 2) = 200.0 - m * 200.0;
  h(1, 2) = 150.0 - m * 150.0;
  return h;
}

// GIVEN a view zoomed by m = 1.1 ... 2 about the focus of expansion and a warp predicted 3 % short
// of the true growth (the estimate a little too high), started from that prediction WHEN
// tracking THEN the tracked points do not lag the expansion: their median error along the ray
// from the focus, over the distance from it, stays below 2e-5 (the descent's tracks lag 1e-4 to
// 3e-4 there, docs/imu.md: so not this alignment on clean texture).
TEST(WarpedZoomTest, TracksDoNotLagTheExpansion) {
  const testing::Texture texture{33};
  const TestImage a = texture.RenderShifted<TestImage>(400, 300, 0.0, 0.0);
  PatchTracker tracker;
  ASSERT_EQ(tracker.Configure(TrackerOptions{}), core::Status::kOk);
  for (double m : {1.1, 1.3, 1.6, 2.0}) {
    const Eigen::Matrix3d h = ZoomAboutCentre(m);
    const Eigen::Matrix3d predicted = ZoomAboutCentre(1.0 + 0.97 * (m - 1.0));
    const TestImage b = RenderWarped(texture, h);
    std::vector<double> radial;
    for (const auto& [corner, tx, ty] : CornersInside(a, h, 20)) {
      PatchTemplate tmpl;
      ASSERT_TRUE(tracker.ExtractTemplate(a.View(), corner.x, corner.y, &tmpl));
      const Eigen::Vector3d p = predicted * Eigen::Vector3d(corner.x, corner.y, 1.0);
      float x = static_cast<float>(p.x());
      float y = static_cast<float>(p.y());
      float q = 0.0f;
      const double rx = tx - 200.0;
      const double ry = ty - 150.0;
      const double r2 = rx * rx + ry * ry;
      if (r2 < 100.0 || !tracker.TrackWarped(b.View(), tmpl, predicted, &x, &y, &q)) continue;
      radial.push_back(((x - tx) * rx + (y - ty) * ry) / r2);
    }
    ASSERT_GE(radial.size(), 50u) << "m " << m;
    EXPECT_LT(std::abs(Median(radial)), 2e-5) << "m " << m;
  }
}

}  // namespace
}  // namespace swf::frontend
