// Hazard mapping against truth: SGM vs the simulator's per-pixel disparity and the Middlebury aloe
// ground truth; a reduced seeded descent over each terrain preset vs the terrain's exact layers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "swf/evaluation/statistics.hpp"
#include "swf/hazard_eval/hazard_eval.hpp"
#include "swf/image_io/image_io.hpp"
#include "swf/sim/trajectory.hpp"
#include "swf/testing/shared_dir.hpp"

namespace swf::hazard_eval {
namespace {

using swf::testing::SharedDir;

using evaluation::Quantile;

EvalOptions SmallOptions() {
  EvalOptions o;
  o.image_width = 320;
  o.image_height = 240;
  o.terrain_size = 512;
  o.footprint_radius_m = 1.0;
  o.shared_dir = SharedDir();
  return o;
}

// GIVEN a rendered crater-field pair at 30 m (320 x 240) WHEN matched by SGM THEN it agrees with
// the renderer's exact disparity: median error < 0.25 px, > 95 % of valid pixels within 1 px,
// > 80 % of the matchable pixels valid.
TEST(HazardSimTest, SgmAgainstSimulatorDisparity) {
  World world;
  ASSERT_EQ(world.Configure(sim::TerrainPreset::kCraterField, 3, SmallOptions()),
            core::Status::kOk);
  sim::StereoImages images;
  estimator::Pose<double> pose;
  pose.R = sim::NadirRotation(0.3);
  pose.t = {2.0, -3.0, world.Terrain().HeightAt(2.0, -3.0) + 30.0};
  ASSERT_EQ(world.Renderer().Render(world.Terrain(), world.Appearance(), pose, 0, &images),
            core::Status::kOk);
  auto sgm = std::make_unique<hazard::SgmMatcher>();
  hazard::SgmOptions so;
  so.max_width = 320;
  so.max_height = 240;
  so.max_disparities = 64;
  ASSERT_EQ(sgm->Configure(so), core::Status::kOk);
  float dmin = 1e9f;
  float dmax = 0.0f;
  for (float d : images.disparity_px) {
    if (std::isfinite(d)) {
      dmin = std::min(dmin, d);
      dmax = std::max(dmax, d);
    }
  }
  const int lo = static_cast<int>(dmin) - 3;
  const int num = static_cast<int>(dmax) + 4 - lo;
  const frontend::GrayView l{images.left.data(), 320, 240, 320};
  const frontend::GrayView r{images.right.data(), 320, 240, 320};
  ASSERT_EQ(sgm->Compute(l, r, lo, num), core::Status::kOk);
  std::vector<double> err;
  int matchable = 0;
  for (int v = 3; v < 237; ++v) {
    for (int u = lo + num + 3; u < 317; ++u) {
      const float t = images.disparity_px[static_cast<std::size_t>(v) * 320 + u];
      if (!std::isfinite(t)) continue;
      ++matchable;
      const float d = sgm->DisparityAt(u, v);
      if (d != hazard::SgmMatcher::kInvalid) err.push_back(std::fabs(d - t));
    }
  }
  ASSERT_GT(matchable, 20000);
  const double within =
      static_cast<double>(std::count_if(err.begin(), err.end(), [](double e) { return e < 1.0; })) /
      err.size();
  std::printf("sim 30 m: valid %.1f%%, median |err| %.3f px, within 1 px %.1f%%\n",
              100.0 * err.size() / matchable, Quantile(err, 0.5), 100.0 * within);
  EXPECT_GT(err.size(), 0.8 * matchable);
  EXPECT_LT(Quantile(err, 0.5), 0.25);
  EXPECT_GT(within, 0.95);
}

// GIVEN the Middlebury aloe pair at half resolution (641 x 555) WHEN matched THEN against
// aloeGT (full-resolution integer disparities, halved) the bad-pixel rate (> 1 px at half
// resolution, i.e. > 2 px full) of valid pixels is < 10 % and at least 70 % of GT pixels are valid.
TEST(HazardSimTest, SgmAgainstMiddleburyAloe) {
  const std::string dir = SharedDir() + "/data/middlebury/";
  image_io::GrayImage left;
  image_io::GrayImage right;
  image_io::GrayImage truth;
  std::string error;
  ASSERT_TRUE(image_io::LoadGray(dir + "aloeL.jpg", &left, &error)) << error;
  ASSERT_TRUE(image_io::LoadGray(dir + "aloeR.jpg", &right, &error)) << error;
  ASSERT_TRUE(image_io::LoadChannel0(dir + "aloeGT.png", &truth, &error)) << error;
  const int hw = (left.width + 1) / 2;
  const int hh = (left.height + 1) / 2;
  std::vector<std::uint8_t> hl(static_cast<std::size_t>(hw) * hh);
  std::vector<std::uint8_t> hr(hl.size());
  hazard::HalveImage(left.View(), hl.data());
  hazard::HalveImage(right.View(), hr.data());
  const frontend::GrayView lv{hl.data(), hw, hh, hw};
  const frontend::GrayView rv{hr.data(), hw, hh, hw};
  auto sgm = std::make_unique<hazard::SgmMatcher>();
  hazard::SgmOptions so;
  so.max_width = hw;
  so.max_height = hh;
  so.max_disparities = 96;
  ASSERT_EQ(sgm->Configure(so), core::Status::kOk);
  ASSERT_EQ(sgm->Compute(lv, rv, 0, 96), core::Status::kOk);
  int with_truth = 0;
  int valid = 0;
  int bad = 0;
  std::vector<double> err;
  for (int y = 0; y < hh; ++y) {
    for (int x = 96; x < hw; ++x) {
      const int gt = truth.pixels[static_cast<std::size_t>(2 * y) * truth.width + 2 * x];
      if (gt == 0) continue;
      ++with_truth;
      const float d = sgm->DisparityAt(x, y);
      if (d == hazard::SgmMatcher::kInvalid) continue;
      ++valid;
      const double e = std::fabs(d - 0.5 * gt);
      err.push_back(e);
      bad += e > 1.0;
    }
  }
  std::printf("aloe (half res): valid %.1f%% of GT pixels, bad (>1 px) %.1f%%, median %.3f px\n",
              100.0 * valid / with_truth, 100.0 * bad / valid, Quantile(err, 0.5));
  EXPECT_GT(valid, with_truth * 7 / 10);
  EXPECT_LT(bad, valid / 10);
}

// GIVEN a reduced seeded descent (320 x 240, 40 -> 25 -> 15 -> 10 m) over each preset THEN the
// fused elevation error is consistent with its sigma (40-95 % within 1 sigma), the chosen site is
// not within the footprint of a true hazard, the false-alarm rate is below 2 %, and every rock the
// rock criterion calls resolvable is detected (at this resolution none is on these descents: the
// next test flies over rocks).
TEST(HazardSimTest, ReducedDescentAgainstTruth) {
  for (int p = 0; p < 3; ++p) {
    World world;
    ASSERT_EQ(world.Configure(static_cast<sim::TerrainPreset>(p), 11, SmallOptions()),
              core::Status::kOk);
    auto mapper = std::make_unique<hazard::HazardMapper>();
    ASSERT_EQ(mapper->Configure(world.MapperOptions()), core::Status::kOk);
    HazardMapMetrics m;
    int f = 0;
    for (double alt : {40.0, 25.0, 15.0, 10.0}) {
      estimator::Pose<double> pose;
      pose.R = sim::NadirRotation(0.2);
      pose.t = {1.0, 2.0, world.Terrain().HeightAt(1.0, 2.0) + alt};
      ASSERT_EQ(world.Step(pose, f, 77 + f, mapper.get(), nullptr), core::Status::kOk);
      ++f;
      ASSERT_EQ(world.Evaluate(*mapper, &m), core::Status::kOk);
      const hazard::HazardStats& st = mapper->Stats();
      std::printf(
          "  %.0f m: cell %.2f known %d safe %d uncertain %d rock %d (false %d) slope %d, "
          "valid px %d\n",
          alt, mapper->CellM(), st.known_cells, st.safe_cells, st.uncertain_cells, st.rock_cells,
          m.false_rock_cells, st.slope_cells, st.valid_pixels);
    }
    int within = 0;
    for (std::size_t i = 0; i < m.elevation_errors_m.size(); ++i) {
      within += m.elevation_errors_m[i] <= m.elevation_sigmas_m[i];
    }
    const double frac =
        static_cast<double>(within) / std::max<std::size_t>(1, m.elevation_errors_m.size());
    std::printf(
        "preset %d: %d known cells (%.2f m), within 1 sigma %.1f%%, rocks %d (%d flagged)"
        "/%d, false %d/%d, site %d clearance %.2f m\n",
        p, m.known_cells, m.cell_m, 100.0 * frac, m.rocks_detected, m.rocks_flagged,
        m.rocks_resolved, m.false_rock_cells, m.rock_free_cells, m.site_valid, m.site_clearance_m);
    EXPECT_GT(m.known_cells, 2000);
    EXPECT_GT(frac, 0.4);
    EXPECT_LT(frac, 0.95);
    EXPECT_FALSE(m.site_valid && m.site_on_hazard);
    EXPECT_LT(m.false_rock_cells, std::max(5, m.rock_free_cells / 50));
    EXPECT_EQ(m.rocks_detected, m.rocks_resolved);
  }
}

// GIVEN the rock field's tallest rocks >= 0.3 m near the centre WHEN the reduced camera descends
// straight over each (25 -> 15 -> 10 -> 7 m) THEN the rock criterion resolves it in the final map,
// every resolved rock is detected (kRock), and rock-free cells are declared rocks at most at the
// criterion's false-alarm rate, 1e-3.
TEST(HazardSimTest, RocksInViewResolvedAndDetected) {
  World world;
  ASSERT_EQ(world.Configure(sim::TerrainPreset::kRockField, 11, SmallOptions()), core::Status::kOk);
  std::vector<sim::Rock> rocks;
  for (const sim::Rock& r : world.Terrain().Rocks()) {
    if (r.height_m >= 0.3 && r.center_m.norm() < 15.0) rocks.push_back(r);
  }
  std::sort(rocks.begin(), rocks.end(),
            [](const sim::Rock& a, const sim::Rock& b) { return a.height_m > b.height_m; });
  ASSERT_GE(rocks.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    auto mapper = std::make_unique<hazard::HazardMapper>();
    ASSERT_EQ(mapper->Configure(world.MapperOptions()), core::Status::kOk);
    const Eigen::Vector2d at = rocks[k].center_m + Eigen::Vector2d(0.7, -0.4);
    HazardMapMetrics m;
    int f = 0;
    for (double alt : {25.0, 15.0, 10.0, 7.0}) {
      estimator::Pose<double> pose;
      pose.R = sim::NadirRotation(0.4);
      pose.t = {at.x(), at.y(), world.Terrain().HeightAt(at.x(), at.y()) + alt};
      ASSERT_EQ(world.Step(pose, f, 91 + f, mapper.get(), nullptr), core::Status::kOk);
      ++f;
    }
    ASSERT_EQ(world.Evaluate(*mapper, &m), core::Status::kOk);
    std::printf("rock %.2f x %.2f m: resolved %d detected %d flagged %d, false %d/%d\n",
                rocks[k].height_m, rocks[k].diameter_m, m.rocks_resolved, m.rocks_detected,
                m.rocks_flagged, m.false_rock_cells, m.rock_free_cells);
    EXPECT_GE(m.rocks_resolved, 1);
    EXPECT_EQ(m.rocks_detected, m.rocks_resolved);
    EXPECT_LE(m.false_rock_cells, m.rock_free_cells / 1000);
  }
}

}  // namespace
}  // namespace swf::hazard_eval
