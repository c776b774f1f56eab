// SGM on synthetic rectified pairs with exactly known disparity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "sgm_reference.hpp"
#include "swf/hazard/dense_stereo.hpp"
#include "swf/testing/allocation_counter.hpp"
#include "synthetic_pair.hpp"

namespace swf::hazard {
namespace {

using testing::Box;
using testing::Pair;
using testing::Scene;

estimator::StereoCamera<double> Camera(int w, int h, double f, double b) {
  estimator::StereoCamera<double> c;
  c.fx = c.fy = f;
  c.cx = 0.5 * (w - 1);
  c.cy = 0.5 * (h - 1);
  c.baseline_m = b;
  return c;
}

frontend::GrayView View(const std::vector<std::uint8_t>& p, int w, int h) {
  return frontend::GrayView{p.data(), w, h, w};
}

TEST(SgmMatcherTest, RejectsBadOptionsAndInput) {
  SgmMatcher m;
  SgmOptions o;
  o.paths = 6;
  EXPECT_EQ(m.Configure(o), core::Status::kInvalidArgument);
  std::vector<std::uint8_t> img(64 * 48, 0);
  EXPECT_EQ(m.Compute(View(img, 64, 48), View(img, 64, 48), 0, 16), core::Status::kNotConfigured);
  o = SgmOptions{};
  o.max_width = 64;
  o.max_height = 48;
  o.max_disparities = 32;
  ASSERT_EQ(m.Configure(o), core::Status::kOk);
  EXPECT_EQ(m.Compute(View(img, 64, 48), View(img, 64, 48), 0, 64), core::Status::kInvalidArgument);
  std::vector<std::uint8_t> big(128 * 48, 0);
  EXPECT_EQ(m.Compute(View(big, 128, 48), View(big, 128, 48), 0, 16),
            core::Status::kInvalidArgument);
}

// GIVEN a tilted textured plane seen by a nadir rig (disparity varies smoothly across the image)
// WHEN matching THEN most pixels are valid and subpixel disparities are within 0.25 px median.
TEST(SgmMatcherTest, SubpixelOnTiltedPlane) {
  const int w = 320;
  const int h = 240;
  const auto cam = Camera(w, h, 400.0, 0.5);
  Scene scene;
  scene.tilt_x = 0.15;
  estimator::Pose<double> pose;
  pose.R = testing::Nadir();
  pose.t = {0.0, 0.0, 10.0};
  Pair pair;
  testing::Render(scene, cam, w, h, pose, &pair);
  auto m = std::make_unique<SgmMatcher>();
  SgmOptions o;
  o.max_width = w;
  o.max_height = h;
  o.max_disparities = 64;
  ASSERT_EQ(m->Configure(o), core::Status::kOk);
  {
    swf::testing::AllocationScope scope;
    ASSERT_EQ(m->Compute(View(pair.left, w, h), View(pair.right, w, h), 0, 48), core::Status::kOk);
    EXPECT_EQ(scope.Count(), 0u);
  }
  std::vector<double> err;
  for (int v = 4; v < h - 4; ++v) {
    for (int u = 40; u < w - 4; ++u) {
      const float d = m->DisparityAt(u, v);
      if (d == SgmMatcher::kInvalid) continue;
      const Eigen::Vector3d dir =
          pose.R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const Eigen::Vector3d p = scene.Cast(pose.t, dir);
      const double z = pose.ApplyInverse(p).z();
      err.push_back(std::fabs(d - cam.fx * cam.baseline_m / z));
    }
  }
  const double total = static_cast<double>(h - 8) * (w - 44);
  ASSERT_GT(err.size(), 0.9 * total);
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  const double median = err[err.size() / 2];
  std::printf("tilted plane: %.1f%% valid, median |error| %.3f px\n", 100.0 * err.size() / total,
              median);
  EXPECT_LT(median, 0.25);
  size_t within1 = 0;
  for (double e : err) within1 += e < 1.0;
  EXPECT_GT(within1, 0.97 * err.size());
}

// GIVEN a raised box THEN its top has the larger disparity and the occluded strip beside it
// (visible in the left image only) is removed by the left-right check.
TEST(SgmMatcherTest, BoxAndOcclusion) {
  const int w = 320;
  const int h = 240;
  const auto cam = Camera(w, h, 400.0, 0.5);
  Scene scene;
  scene.boxes.push_back(Box{0.0, 0.0, 0.8, 2.0});
  estimator::Pose<double> pose;
  pose.R = testing::Nadir();
  pose.t = {0.0, 0.0, 10.0};
  Pair pair;
  testing::Render(scene, cam, w, h, pose, &pair);
  SgmOptions o;
  o.max_width = w;
  o.max_height = h;
  o.max_disparities = 64;
  auto m = std::make_unique<SgmMatcher>();
  ASSERT_EQ(m->Configure(o), core::Status::kOk);
  ASSERT_EQ(m->Compute(View(pair.left, w, h), View(pair.right, w, h), 4, 40), core::Status::kOk);
  // Box top (depth 8 m): disparity 25; ground: 20.
  const int cx = w / 2;
  const int cy = h / 2;
  EXPECT_NEAR(m->DisparityAt(cx, cy), 25.0, 0.3);
  EXPECT_NEAR(m->DisparityAt(30 + 40, cy), 20.0, 0.3);
  // The ground just left of the box top (ground x in [-1.125, -1.0] m, u in [cx-45, cx-40]) is
  // seen by the left camera but hidden from the right one by the box.
  const int box_left_edge = static_cast<int>(std::ceil(cam.cx - cam.fx * 0.8 / 8.0));
  int invalid = 0;
  int checked = 0;
  for (int v = cy - 20; v <= cy + 20; ++v) {
    for (int u = box_left_edge - 4; u <= box_left_edge - 2; ++u) {
      ++checked;
      const float d = m->DisparityAt(u, v);
      invalid += d == SgmMatcher::kInvalid || std::fabs(d - 20.0f) < 1.0f ? 1 : 0;
    }
  }
  // Occluded pixels are either rejected or given the background (correct ground) disparity.
  EXPECT_GT(invalid, checked * 8 / 10);
}

// Every kernel this CPU runs (x86-64: portable 128-bit and AVX2; AArch64: portable and NEON).
std::vector<SgmKernel> Kernels() {
  std::vector<SgmKernel> k;
  for (SgmKernel c : {SgmKernel::kPortable, SgmKernel::kAvx2, SgmKernel::kNeon}) {
    if (SgmKernelSupported(c)) k.push_back(c);
  }
  return k;
}

// A pair with the right image shifted by a disparity that varies across the image, noise added to
// both and a band of constant grey (no texture: ambiguous costs, ties).
void NoisyPair(int w, int h, std::uint32_t seed, std::vector<std::uint8_t>* l,
               std::vector<std::uint8_t>* r) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> grey(0, 255);
  std::uniform_int_distribution<int> noise(-6, 6);
  std::vector<int> texture(static_cast<std::size_t>(w + 64) * h);
  for (int& t : texture) t = grey(rng);
  l->assign(static_cast<std::size_t>(w) * h, 0);
  r->assign(l->size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int d = 6 + (x * 13) / w + (y * 7) / h;
      const bool flat = y > h / 3 && y < h / 3 + 6;
      const int lv = flat ? 128 : texture[static_cast<std::size_t>(y) * (w + 64) + x + 32];
      const int rv = flat ? 128 : texture[static_cast<std::size_t>(y) * (w + 64) + x + 32 + d];
      (*l)[static_cast<std::size_t>(y) * w + x] =
          static_cast<std::uint8_t>(std::clamp(lv + noise(rng), 0, 255));
      (*r)[static_cast<std::size_t>(y) * w + x] =
          static_cast<std::uint8_t>(std::clamp(rv + noise(rng), 0, 255));
    }
  }
}

// GIVEN pairs of several sizes, disparity ranges (multiples of 16 and not), offsets and path counts
// WHEN every kernel matches them THEN disparities and confidences equal those of the plain scalar
// SGM (sgm_reference.hpp) bit for bit, so results do not depend on the CPU or the instruction set;
// no kernel allocates.
TEST(SgmMatcherTest, EveryKernelMatchesTheScalarReferenceBitForBit) {
  struct Case {
    int w, h, min_d, num_d, paths, p1, p2;
  };
  const Case cases[] = {{97, 41, 0, 32, 8, 8, 96},    {64, 37, 3, 21, 8, 8, 96},
                        {53, 30, 0, 4, 4, 8, 96},     {120, 33, 5, 48, 4, 12, 300},
                        {70, 29, 1, 37, 8, 30, 1000}, {83, 26, 2, 16, 8, 8, 96}};
  const std::vector<SgmKernel> kernels = Kernels();
  ASSERT_GE(kernels.size(), 2u);  // the portable kernel and the ISA's own
  std::uint32_t seed = 1;
  for (const Case& c : cases) {
    std::vector<std::uint8_t> l;
    std::vector<std::uint8_t> r;
    NoisyPair(c.w, c.h, seed++, &l, &r);
    SgmOptions o;
    o.max_width = 128;
    o.max_height = 48;
    o.max_disparities = 64;
    o.paths = c.paths;
    o.p1 = c.p1;
    o.p2 = c.p2;
    const testing::ReferenceSgm reference(o, View(l, c.w, c.h), View(r, c.w, c.h), c.min_d,
                                          c.num_d);
    const testing::ReferenceResult& ref = reference.Result();
    ASSERT_GT(ref.num_valid, c.w * c.h / 4);
    for (SgmKernel k : kernels) {
      o.kernel = k;
      auto m = std::make_unique<SgmMatcher>();
      ASSERT_EQ(m->Configure(o), core::Status::kOk);
      ASSERT_EQ(m->Kernel(), k);
      {
        swf::testing::AllocationScope scope;
        ASSERT_EQ(m->Compute(View(l, c.w, c.h), View(r, c.w, c.h), c.min_d, c.num_d),
                  core::Status::kOk);
        EXPECT_EQ(scope.Count(), 0u) << "kernel " << static_cast<int>(k);
      }
      const std::size_t n = static_cast<std::size_t>(c.w) * c.h;
      EXPECT_EQ(m->NumValid(), ref.num_valid) << "kernel " << static_cast<int>(k);
      EXPECT_EQ(std::memcmp(m->Disparity(), ref.disparity.data(), n * sizeof(float)), 0)
          << "kernel " << static_cast<int>(k) << " w " << c.w << " d " << c.num_d;
      EXPECT_EQ(std::memcmp(m->Confidence(), ref.confidence.data(), n * sizeof(float)), 0)
          << "kernel " << static_cast<int>(k);
    }
  }
}

TEST(SgmMatcherTest, AutoPicksASupportedKernelAndRejectsAnUnsupportedOne) {
  SgmOptions o;
  o.max_width = 64;
  o.max_height = 32;
  o.max_disparities = 16;
  SgmMatcher m;
  ASSERT_EQ(m.Configure(o), core::Status::kOk);
  EXPECT_NE(m.Kernel(), SgmKernel::kAuto);
  EXPECT_TRUE(SgmKernelSupported(m.Kernel()));
#if defined(__x86_64__)
  o.kernel = SgmKernel::kNeon;
#else
  o.kernel = SgmKernel::kAvx2;
#endif
  EXPECT_EQ(m.Configure(o), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::hazard
