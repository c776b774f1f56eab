#include "swf/frontend/rectify.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "swf/testing/allocation_counter.hpp"
#include "synthetic.hpp"

namespace swf::frontend {
namespace {

using estimator::Pose;
using estimator::Vec3;

// The EuRoC V1_01 rig (sensor.yaml of cam0 / cam1), typed in so this test needs no files.
CameraCalibration EurocCam(int index) {
  CameraCalibration c;
  c.width = 752;
  c.height = 480;
  Eigen::Matrix4d m;
  if (index == 0) {
    c.fx = 458.654, c.fy = 457.296, c.cx = 367.215, c.cy = 248.375;
    c.k1 = -0.28340811, c.k2 = 0.07395907, c.p1 = 0.00019359, c.p2 = 1.76187114e-05;
    m << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, 0.999557249008,
        0.0149672133247, 0.025715529948, -0.064676986768, -0.0257744366974, 0.00375618835797,
        0.999660727178, 0.00981073058949, 0, 0, 0, 1;
  } else {
    c.fx = 457.587, c.fy = 456.134, c.cx = 379.999, c.cy = 255.238;
    c.k1 = -0.28368365, c.k2 = 0.07451284, c.p1 = -0.00010473, c.p2 = -3.55590700e-05;
    m << 0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556, 0.999598781151,
        0.0130119051815, 0.0251588363115, 0.0453689425024, -0.0253898008918, 0.0179005838253,
        0.999517347078, 0.00786212447038, 0, 0, 0, 1;
  }
  c.body_T_camera = Pose<double>::FromMatrix(m);
  return c;
}

// Independent forward model: body point -> distorted raw pixel.
Eigen::Vector2d ProjectRaw(const CameraCalibration& c, const Vec3<double>& p_body) {
  const Vec3<double> p = c.body_T_camera.ApplyInverse(p_body);
  const double x = p.x() / p.z();
  const double y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + c.k1 * r2 + c.k2 * r2 * r2 + c.k3 * r2 * r2 * r2;
  const double xd = x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y;
  return Eigen::Vector2d(c.fx * xd + c.cx, c.fy * yd + c.cy);
}

// GIVEN the real EuRoC calibration WHEN a scene point is projected by the rectified stereo
// camera THEN the remap's source pixels are exactly where the raw cameras see that point: the
// rectified rows are epipolar lines and the baseline is +x.
TEST(StereoRectifierTest, RectifiedProjectionMatchesRawCameras) {
  auto rectifier = std::make_unique<StereoRectifier>();
  const CameraCalibration left = EurocCam(0);
  const CameraCalibration right = EurocCam(1);
  ASSERT_EQ(rectifier->Configure(left, right, RectifyOptions{}), core::Status::kOk);
  const auto& cam = rectifier->Camera();
  EXPECT_NEAR(cam.baseline_m, 0.110, 0.001);  // EuRoC's stereo baseline is about 11 cm
  for (double x : {-1.0, 0.0, 0.7}) {
    for (double y : {-0.5, 0.0, 0.4}) {
      for (double z : {2.0, 6.0}) {
        const Vec3<double> p_rect(x, y, z);
        const Vec3<double> p_body = rectifier->RectifiedInBody().Apply(p_rect);
        const Vec3<double> meas = cam.Project(p_rect);
        double u = 0.0;
        double v = 0.0;
        ASSERT_TRUE(rectifier->RawPixel(0, meas.x(), meas.z(), &u, &v));
        const Eigen::Vector2d raw_left = ProjectRaw(left, p_body);
        EXPECT_NEAR(u, raw_left.x(), 1e-6);
        EXPECT_NEAR(v, raw_left.y(), 1e-6);
        ASSERT_TRUE(rectifier->RawPixel(1, meas.y(), meas.z(), &u, &v));
        const Eigen::Vector2d raw_right = ProjectRaw(right, p_body);
        EXPECT_NEAR(u, raw_right.x(), 1e-6);
        EXPECT_NEAR(v, raw_right.y(), 1e-6);
      }
    }
  }
}

// Exact float reference: bilinear interpolation of the raw image at the exact source pixel.
double ExactSample(const testing::TestImage& raw, double u, double v) {
  const int x0 = std::min(static_cast<int>(u), raw.width - 2);
  const int y0 = std::min(static_cast<int>(v), raw.height - 2);
  const double ax = u - x0;
  const double ay = v - y0;
  auto at = [&](int x, int y) {
    return static_cast<double>(raw.pixels[static_cast<std::size_t>(y) * raw.width + x]);
  };
  const double top = at(x0, y0) * (1.0 - ax) + at(x0 + 1, y0) * ax;
  const double bottom = at(x0, y0 + 1) * (1.0 - ax) + at(x0 + 1, y0 + 1) * ax;
  return top * (1.0 - ay) + bottom * ay;
}

// GIVEN the EuRoC rig WHEN the compact table (a quadratic per 16-pixel row segment) is compared
// with the exact map at every output pixel THEN it is within 0.01 px wherever the exact source is
// inside the raw image, and the rectifier's own bound says the same.
TEST(StereoRectifierTest, CompactTableIsWithinBoundOfExactMap) {
  auto rectifier = std::make_unique<StereoRectifier>();
  ASSERT_EQ(rectifier->Configure(EurocCam(0), EurocCam(1), RectifyOptions{}), core::Status::kOk);
  EXPECT_FALSE(rectifier->IsIdentity());
  EXPECT_LE(rectifier->MaxTableErrorPx(), 0.01);
  double max_error = 0.0;
  int checked = 0;
  for (int c = 0; c < 2; ++c) {
    const CameraCalibration cal = EurocCam(c);
    for (int v = 0; v < rectifier->Height(); ++v) {
      for (int u = 0; u < rectifier->Width(); ++u) {
        double eu = 0.0;
        double ev = 0.0;
        if (!rectifier->RawPixel(c, u, v, &eu, &ev)) continue;
        if (!(eu >= 0.0 && ev >= 0.0 && eu <= cal.width - 1 && ev <= cal.height - 1)) continue;
        float tu = 0.0f;
        float tv = 0.0f;
        if (!rectifier->TablePixel(c, u, v, &tu, &tv)) {
          // Only pixels whose exact source is within the table error of the border may differ.
          EXPECT_TRUE(eu < 0.01 || ev < 0.01 || eu > cal.width - 1.01 || ev > cal.height - 1.01)
              << u << " " << v;
          continue;
        }
        max_error = std::max(max_error, std::hypot(tu - eu, tv - ev));
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 2 * 752 * 480 * 8 / 10);
  EXPECT_LE(max_error, 0.01);
  EXPECT_LE(max_error, rectifier->MaxTableErrorPx() + 1e-9);
  std::printf("compact table: max error %.5f px over %d pixels\n", max_error, checked);
}

// GIVEN the EuRoC rig (as is, and zoomed out so that part of the output has no source) and a
// textured raw pair WHEN rectified THEN every output pixel is within 0.75 grey levels of the
// exact float remap (bilinear at the exact source pixel; the output's rounding alone is 0.5), the
// mean error is that of the rounding, pixels without a source are 0, the call allocates nothing
// and a second call gives bit-identical images.
class RectifyOutputTest : public ::testing::TestWithParam<double> {};

TEST_P(RectifyOutputTest, OutputMatchesExactFloatRemap) {
  auto rectifier = std::make_unique<StereoRectifier>();
  RectifyOptions options;
  options.focal_scale = GetParam();
  ASSERT_EQ(rectifier->Configure(EurocCam(0), EurocCam(1), options), core::Status::kOk);
  EXPECT_LE(rectifier->MaxTableErrorPx(), 0.01);
  const testing::Texture texture(7);
  const testing::TestImage raw_left = texture.RenderShifted<testing::TestImage>(752, 480, 0.0, 0.0);
  const testing::TestImage raw_right =
      texture.RenderShifted<testing::TestImage>(752, 480, 3.3, -1.7);
  testing::TestImage out_left(752, 480);
  testing::TestImage out_right(752, 480);
  {
    swf::testing::AllocationScope scope;
    ASSERT_EQ(rectifier->Rectify(raw_left.View(), raw_right.View(), out_left.MutableView(),
                                 out_right.MutableView()),
              core::Status::kOk);
    EXPECT_EQ(scope.Count(), 0u);
  }
  for (int c = 0; c < 2; ++c) {
    const testing::TestImage& raw = c == 0 ? raw_left : raw_right;
    const testing::TestImage& out = c == 0 ? out_left : out_right;
    double sum = 0.0;
    double worst = 0.0;
    int count = 0;
    int outside = 0;
    for (int v = 0; v < 480; ++v) {
      for (int u = 0; u < 752; ++u) {
        const int got = out.pixels[static_cast<std::size_t>(v) * 752 + u];
        double eu = 0.0;
        double ev = 0.0;
        const bool source = rectifier->RawPixel(c, u, v, &eu, &ev) && eu >= 0.0 && ev >= 0.0 &&
                            eu <= 751.0 && ev <= 479.0;
        if (!source) {
          // Within the table error of the border a pixel may still be sampled.
          if (eu < -0.01 || ev < -0.01 || eu > 751.01 || ev > 479.01) {
            EXPECT_EQ(got, 0);
            ++outside;
          }
          continue;
        }
        float tu = 0.0f;
        float tv = 0.0f;
        if (!rectifier->TablePixel(c, u, v, &tu, &tv)) continue;  // on the border (above)
        const double error = std::fabs(got - ExactSample(raw, eu, ev));
        worst = std::max(worst, error);
        sum += error;
        ++count;
      }
    }
    if (GetParam() < 1.0) {
      EXPECT_GT(outside, 752 * 480 / 10);  // the border paths are exercised
    }
    EXPECT_LE(worst, 0.75);
    // Output rounding alone gives 0.25 on average; 1/128-px weights add little.
    EXPECT_LE(sum / count, 0.26);
    std::printf(
        "focal x%.1f camera %d: |rectified - exact float remap| max %.3f, mean %.4f over %d px, %d "
        "without source\n",
        GetParam(), c, worst, sum / count, count, outside);
  }
  testing::TestImage again_left(752, 480);
  testing::TestImage again_right(752, 480);
  ASSERT_EQ(rectifier->Rectify(raw_left.View(), raw_right.View(), again_left.MutableView(),
                               again_right.MutableView()),
            core::Status::kOk);
  EXPECT_EQ(again_left.pixels, out_left.pixels);
  EXPECT_EQ(again_right.pixels, out_right.pixels);
}

INSTANTIATE_TEST_SUITE_P(FocalScales, RectifyOutputTest, ::testing::Values(1.0, 0.6));

// Every kernel this CPU supports against the portable one on a padded raw pair (the test below).
void CompareKernels(int width, int height, int stride, int zooms, int* compared) {
  const testing::Texture texture(11);
  const testing::TestImage left_src =
      texture.RenderShifted<testing::TestImage>(width, height, 0.0, 0.0);
  const testing::TestImage right_src =
      texture.RenderShifted<testing::TestImage>(width, height, 2.7, -0.6);
  std::vector<std::uint8_t> padded_left(static_cast<std::size_t>(stride) * height, 0xA5);
  std::vector<std::uint8_t> padded_right(static_cast<std::size_t>(stride) * height, 0x5A);
  for (int v = 0; v < height; ++v) {
    std::copy_n(left_src.pixels.begin() + static_cast<std::ptrdiff_t>(v) * width, width,
                padded_left.begin() + static_cast<std::ptrdiff_t>(v) * stride);
    std::copy_n(right_src.pixels.begin() + static_cast<std::ptrdiff_t>(v) * width, width,
                padded_right.begin() + static_cast<std::ptrdiff_t>(v) * stride);
  }
  const GrayView raw_left{padded_left.data(), width, height, stride};
  const GrayView raw_right{padded_right.data(), width, height, stride};
  auto reference = std::make_unique<StereoRectifier>();
  auto rectifier = std::make_unique<StereoRectifier>();
  for (const double zoom : {1.0, 0.6, 1.7}) {
    if (zooms-- == 0) break;
    RectifyOptions options;
    options.focal_scale = zoom;
    options.kernel = RemapKernel::kPortable;
    ASSERT_EQ(reference->Configure(EurocCam(0), EurocCam(1), options), core::Status::kOk);
    EXPECT_EQ(reference->Kernel(), RemapKernel::kPortable);
    testing::TestImage want_left(width, height);
    testing::TestImage want_right(width, height);
    ASSERT_EQ(
        reference->Rectify(raw_left, raw_right, want_left.MutableView(), want_right.MutableView()),
        core::Status::kOk);
    for (const RemapKernel kernel : {RemapKernel::kSsse3, RemapKernel::kAvx2, RemapKernel::kNeon}) {
      options.kernel = kernel;
      if (rectifier->Configure(EurocCam(0), EurocCam(1), options) != core::Status::kOk) continue;
      std::printf("kernel %d zoom %.1f: %.3f of the segments by windows\n",
                  static_cast<int>(kernel), zoom, rectifier->WindowFraction());
      EXPECT_EQ(rectifier->Kernel(), kernel);
      EXPECT_GT(rectifier->WindowFraction(), zoom < 1.0 ? 0.4 : 0.95);
      testing::TestImage got_left(width, height);
      testing::TestImage got_right(width, height);
      {
        swf::testing::AllocationScope scope;
        ASSERT_EQ(rectifier->Rectify(raw_left, raw_right, got_left.MutableView(),
                                     got_right.MutableView()),
                  core::Status::kOk);
        EXPECT_EQ(scope.Count(), 0u);
      }
      EXPECT_EQ(got_left.pixels, want_left.pixels) << static_cast<int>(kernel) << " zoom " << zoom;
      EXPECT_EQ(got_right.pixels, want_right.pixels)
          << static_cast<int>(kernel) << " zoom " << zoom;
      ++*compared;
    }
  }
}

// GIVEN the EuRoC rig at several zooms and raw images with row padding (800 bytes, and 2^15, where
// the AVX2 kernel computes window addresses in scalar code) WHEN every remap kernel this CPU
// supports is forced THEN each output is bit-identical to the portable kernel's, without
// allocating; a kernel the CPU lacks is rejected.
TEST(StereoRectifierTest, EveryKernelMatchesPortableBitForBit) {
  constexpr int kW = 752;
  constexpr int kH = 480;
  int compared = 0;
  for (const int stride : {800, 1 << 15}) {
    CompareKernels(kW, kH, stride, stride == 800 ? 3 : 1, &compared);
  }
#if defined(__x86_64__) || defined(__aarch64__)
  EXPECT_GE(compared, 4);  // at least one SIMD kernel per zoom and stride (SSSE3 / NEON)
#endif
  auto rectifier = std::make_unique<StereoRectifier>();
  RectifyOptions automatic;
  ASSERT_EQ(rectifier->Configure(EurocCam(0), EurocCam(1), automatic), core::Status::kOk);
  EXPECT_NE(rectifier->Kernel(), RemapKernel::kAuto);
}

// GIVEN an ideal rig (no distortion, parallel cameras) THEN rectification is the identity.
TEST(StereoRectifierTest, IdealRigIsIdentityAndAllocationFree) {
  CameraCalibration left;
  left.width = 160;
  left.height = 120;
  left.fx = left.fy = 200.0;
  left.cx = 80.0;
  left.cy = 60.0;
  CameraCalibration right = left;
  right.body_T_camera.t = Vec3<double>(0.2, 0.0, 0.0);
  auto rectifier = std::make_unique<StereoRectifier>();
  ASSERT_EQ(rectifier->Configure(left, right, RectifyOptions{}), core::Status::kOk);
  EXPECT_TRUE(rectifier->IsIdentity());
  const testing::Texture texture(4);
  const testing::TestImage raw = texture.RenderShifted<testing::TestImage>(160, 120, 0.0, 0.0);
  testing::TestImage out_left(160, 120);
  testing::TestImage out_right(160, 120);
  {
    swf::testing::AllocationScope scope;
    ASSERT_EQ(
        rectifier->Rectify(raw.View(), raw.View(), out_left.MutableView(), out_right.MutableView()),
        core::Status::kOk);
    EXPECT_EQ(scope.Count(), 0u);
  }
  EXPECT_EQ(out_left.pixels, raw.pixels);
  EXPECT_EQ(out_right.pixels, raw.pixels);
  testing::TestImage wrong(100, 100);
  EXPECT_EQ(
      rectifier->Rectify(raw.View(), raw.View(), wrong.MutableView(), out_right.MutableView()),
      core::Status::kInvalidArgument);
  right.body_T_camera.t.setZero();
  EXPECT_EQ(rectifier->Configure(left, right, RectifyOptions{}), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::frontend
