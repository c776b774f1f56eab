#include "swf/sim/terrain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>

#include "swf/sim/appearance.hpp"
#include "swf/sim/hazard.hpp"
#include "swf/sim/rng.hpp"
#include "swf/testing/refusals.hpp"

namespace swf::sim {
namespace {

TerrainOptions Small(TerrainPreset preset, std::uint64_t seed = 3) {
  TerrainOptions o = TerrainPresetOptions(preset, seed);
  o.size = 512;  // 51.2 m: keeps the tests fast
  return o;
}

TEST(TerrainTest, SameSeedGivesIdenticalHeightsAndOtherSeedDiffers) {
  Terrain a;
  Terrain b;
  Terrain c;
  ASSERT_EQ(a.Configure(Small(TerrainPreset::kCraterField, 3)), core::Status::kOk);
  ASSERT_EQ(b.Configure(Small(TerrainPreset::kCraterField, 3)), core::Status::kOk);
  ASSERT_EQ(c.Configure(Small(TerrainPreset::kCraterField, 4)), core::Status::kOk);
  EXPECT_EQ(a.Heights(), b.Heights());
  EXPECT_NE(a.Heights(), c.Heights());
}

TEST(TerrainTest, CraterAndRockCountsFollowTheirModels) {
  Terrain t;
  const TerrainOptions o = Small(TerrainPreset::kRockField);
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  const double area = std::pow((o.size - 1) * o.cell_m, 2);
  const double b = o.craters.sfd_exponent;
  const double expected_craters =
      area * o.craters.density_at_1m *
      (std::pow(o.craters.min_diameter_m, -b) - std::pow(o.craters.max_diameter_m, -b));
  EXPECT_NEAR(static_cast<double>(t.Craters().size()), expected_craters, 0.51);
  // Golombek-Rapp: the fractional area covered by drawn rocks ~ F(Dmin) - F(Dmax).
  const double q = 1.79 + 0.152 / o.rocks.k;
  const double expected_fraction =
      o.rocks.k * (std::exp(-q * o.rocks.min_diameter_m) - std::exp(-q * o.rocks.max_diameter_m));
  double covered = 0.0;
  for (const Rock& r : t.Rocks()) covered += std::numbers::pi * 0.25 * r.diameter_m * r.diameter_m;
  EXPECT_NEAR(covered / area, expected_fraction, 0.2 * expected_fraction);
  for (const Rock& r : t.Rocks()) {
    EXPECT_GE(r.diameter_m, o.rocks.min_diameter_m);
    EXPECT_LE(r.diameter_m, o.rocks.max_diameter_m);
    EXPECT_DOUBLE_EQ(r.height_m, 0.5 * r.diameter_m);
  }
}

TEST(TerrainTest, RayHitsATiltedPlaneExactly) {
  TerrainOptions o;
  o.size = 256;
  o.relief_rms_m = 0.0;
  o.tilt_x = 0.1;
  o.tilt_y = -0.05;
  Terrain t;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  const Eigen::Vector3d origin(1.0, 2.0, 30.0);
  const Eigen::Vector3d dir(0.1, -0.07, -1.0);
  double s = 0.0;
  ASSERT_TRUE(t.Intersect(origin, dir, &s));
  // Plane z = 0.1 x - 0.05 y along the ray: 30 - s = 0.1 (1 + 0.1 s) - 0.05 (2 - 0.07 s).
  const double expected = (30.0 - 0.1 * 1.0 + 0.05 * 2.0) / (1.0 + 0.1 * 0.1 + 0.05 * 0.07);
  EXPECT_NEAR(s, expected, 1e-6);
}

TEST(TerrainTest, IntersectFindsTheFirstHitOfRandomRaysOnRoughTerrain) {
  // GIVEN rough terrain with rocks and craters and rays of random slant from 2-40 m up.
  Terrain t;
  ASSERT_EQ(t.Configure(Small(TerrainPreset::kRockField, 11)), core::Status::kOk);
  Rng rng(5);
  int hits = 0;
  for (int n = 0; n < 400; ++n) {
    const Eigen::Vector3d origin(rng.Uniform(-20.0, 20.0), rng.Uniform(-20.0, 20.0),
                                 t.MaxHeightM() + rng.Uniform(0.5, 40.0));
    const Eigen::Vector3d dir(rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5), -1.0);
    double s = 0.0;
    // WHEN the ray is cast with and without a (valid) local start height.
    const bool hit = t.Intersect(origin, dir, &s);
    double s_below = 0.0;
    ASSERT_EQ(t.IntersectBetween(origin, dir, t.MaxHeightM() + 1.0, t.MinHeightM() - 1.0, &s_below),
              hit);
    if (!hit) continue;
    ++hits;
    EXPECT_EQ(s, s_below);
    // THEN the hit is on the surface and a dense march (1/50 cell) finds no earlier crossing.
    const Eigen::Vector3d p = origin + s * dir;
    EXPECT_NEAR(p.z(), t.HeightAt(p.x(), p.y()), 1e-9);
    const double step = 0.02 * t.CellM() / dir.head<2>().norm();
    const double s0 = (origin.z() - t.MaxHeightM()) / -dir.z();
    for (double q = s0; q < s - 1e-6; q += step) {
      const Eigen::Vector3d a = origin + q * dir;
      ASSERT_GT(a.z(), t.HeightAt(a.x(), a.y()) - 1e-9) << "ray " << n << " passes below at " << q;
    }
  }
  EXPECT_GT(hits, 150);  // the others leave the 51 m square first
}

TEST(TerrainTest, FourRaysAtOnceAgreeWithOneRayAtATime) {
  // GIVEN rough terrain and flat ground (a zero quadratic term: the linear root), rays in fours
  // from one origin and spans from a tenth of a cell to several cells (one cell, two neighbours
  // and the pyramid walk, mixed across the lanes).
  for (const bool flat : {false, true}) {
    TerrainOptions o = Small(TerrainPreset::kRockField, 13);
    if (flat) {
      o = TerrainOptions{};
      o.size = 256;
      o.relief_rms_m = 0.0;  // no craters or rocks by default
    }
    Terrain t;
    ASSERT_EQ(t.Configure(o), core::Status::kOk);
    Rng rng(17);
    const double half = t.HalfExtentM() - 2.0 * t.CellM();
    int hits = 0;
    int misses = 0;
    int disagree = 0;
    int walks = 0;
    int seconds = 0;
    int split_differs = 0;
    double worst = 0.0;
    for (int n = 0; n < 4000; ++n) {
      const Eigen::Vector3d origin(rng.Uniform(-0.5, 0.5) * half, rng.Uniform(-0.5, 0.5) * half,
                                   t.MaxHeightM() + rng.Uniform(0.5, 20.0));
      Terrain::GridRays4 rays{};
      const double gx0 = (origin.x() - t.NodeX(0)) / t.CellM();
      const double gy0 = (origin.y() - t.NodeY(0)) / t.CellM();
      rays.base_i = static_cast<std::int32_t>(std::floor(gx0));
      rays.base_j = static_cast<std::int32_t>(std::floor(gy0));
      rays.gx0 = static_cast<float>(gx0 - rays.base_i);
      rays.gy0 = static_cast<float>(gy0 - rays.base_j);
      rays.oz = static_cast<float>(origin.z());
      bool inside = true;
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d d(rng.Uniform(-0.4, 0.4), rng.Uniform(-0.4, 0.4), -1.0);
        rays.dgx[k] = static_cast<float>(d.x() / t.CellM());
        rays.dgy[k] = static_cast<float>(d.y() / t.CellM());
        rays.dz[k] = static_cast<float>(d.z());
        // Start near the ground (where a local height range puts it), cover 0.1-6 cells.
        const double cells = std::exp(rng.Uniform(std::log(0.1), std::log(6.0)));
        const double speed = std::max(std::hypot(d.x(), d.y()) / t.CellM(), 1e-3);
        rays.ta[k] = static_cast<float>(origin.z() - t.MaxHeightM() + rng.Uniform(-0.3, 0.3));
        rays.tb[k] = static_cast<float>(rays.ta[k] + cells / speed);
        for (const double s : {static_cast<double>(rays.ta[k]), static_cast<double>(rays.tb[k])}) {
          const Eigen::Vector3d p = origin + s * d;
          inside = inside && std::abs(p.x()) < half && std::abs(p.y()) < half;
        }
      }
      if (!inside) continue;
      // WHEN the four are cast at once (single precision) and one at a time (double, the same
      // single-precision ray).
      Terrain::V4f four{};
      Terrain::V4i walk{};
      t.IntersectSpan4(rays, &four, &walk);
      // AND in two steps with the second cells solved in other lanes (reversed, as a renderer
      // packs them from several groups): the same bits.
      Terrain::V4f first{};
      Terrain::V4i walk_two{};
      Terrain::SecondCells4 second{};
      t.IntersectSpan4(rays, &first, &walk_two, &second);
      Terrain::GridRays4 packed = rays;
      Terrain::SecondCells4 cells = second;
      for (int k = 0; k < 4; ++k) {
        packed.dgx[3 - k] = rays.dgx[k];
        packed.dgy[3 - k] = rays.dgy[k];
        packed.dz[3 - k] = rays.dz[k];
        packed.tb[3 - k] = rays.tb[k];
        cells.i[3 - k] = second.i[k];
        cells.j[3 - k] = second.j[k];
        cells.t0[3 - k] = second.t0[k];
      }
      const Terrain::V4f later = t.IntersectSecondCells4(packed, cells);
      for (int k = 0; k < 4; ++k) {
        if (walk[k] != 0) continue;
        const float two_step = second.pending[k] != 0 ? later[3 - k] : first[k];
        seconds += second.pending[k] != 0 ? 1 : 0;
        const float one_step = four[k];
        if (std::memcmp(&two_step, &one_step, sizeof(float)) != 0) ++split_differs;
      }
      for (int k = 0; k < 4; ++k) {
        const Terrain::GridRay ray{gx0, gy0, rays.dgx[k], rays.dgy[k], rays.oz, rays.dz[k]};
        double single = 0.0;
        const bool hit = t.IntersectSpan(ray, rays.ta[k], rays.tb[k], &single);
        (hit ? hits : misses) += 1;
        if (walk[k] != 0) {
          ++walks;
          continue;
        }
        if (hit != !std::isnan(four[k])) {
          ++disagree;
          continue;
        }
        if (hit) worst = std::max(worst, std::abs(four[k] - single));
      }
    }
    // THEN they find the same hits (single precision may decide a graze differently: at most
    // 1 in 2000) at the same parameter to 2e-5 (a float's resolution at ~20 m is 2e-6); the
    // segments over more than two cells are marked for the walk; solving the second cells apart
    // changes no bit.
    EXPECT_GT(hits, 2000) << "flat " << flat;
    EXPECT_GT(misses, 2000) << "flat " << flat;
    EXPECT_LE(disagree, (hits + misses) / 2000) << "flat " << flat;
    EXPECT_LT(worst, 2e-5) << "flat " << flat;
    EXPECT_GT(walks, 500) << "flat " << flat;
    EXPECT_LT(walks, (hits + misses) / 2) << "flat " << flat;
    EXPECT_GT(seconds, 100) << "flat " << flat;
    EXPECT_EQ(split_differs, 0) << "flat " << flat;
    std::printf("flat %d: %d hits, %d misses, %d walks, %d disagree, worst %.3g\n", flat, hits,
                misses, walks, disagree, worst);
  }
}

TEST(HazardTest, TruthAgreesWithTheHeightField) {
  // GIVEN a tilted plane with rocks on it.
  TerrainOptions o;
  o.size = 512;
  o.relief_rms_m = 0.0;
  o.tilt_x = std::tan(5.0 * std::numbers::pi / 180.0);
  o.rocks.k = 0.1;
  Terrain t;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  ASSERT_GT(t.Rocks().size(), 100u);
  HazardMap map;
  ASSERT_EQ(ComputeHazardTruth(t, HazardOptions{}, &map), core::Status::kOk);
  // THEN the slope is the plane's everywhere and below the 10 deg threshold.
  for (size_t k = 0; k < map.slope_deg.size(); k += 97) EXPECT_NEAR(map.slope_deg[k], 5.0, 1e-3);
  // AND each rock's top is in the height field at its centre and flagged when tall.
  int flagged = 0;
  for (const Rock& r : t.Rocks()) {
    const auto i = static_cast<std::int32_t>(std::lround((r.center_m.x() - t.NodeX(0)) / o.cell_m));
    const auto j = static_cast<std::int32_t>(std::lround((r.center_m.y() - t.NodeY(0)) / o.cell_m));
    const double dx = t.NodeX(i) - r.center_m.x();
    const double dy = t.NodeY(j) - r.center_m.y();
    const double radius = 0.5 * r.diameter_m;
    const double s2 = (dx * dx + dy * dy) / (radius * radius);
    const double rock_here = r.height_m * std::sqrt(std::max(0.0, 1.0 - s2));
    const size_t k = static_cast<size_t>(j) * t.Size() + i;
    EXPECT_GE(t.Heights()[k] + 1e-4, r.base_z_m + rock_here);
    EXPECT_NEAR(map.rock_height_m[k], t.Heights()[k] - t.BaseHeights()[k], 1e-6);
    if (map.rock_height_m[k] > 0.25f) {
      EXPECT_TRUE(map.hazard[k] & kHazardRock);
      ++flagged;
    }
  }
  EXPECT_GT(flagged, 10);
  // AND ground away from rocks is safe.
  int safe = 0;
  for (size_t k = 0; k < map.hazard.size(); ++k) {
    if (map.rock_height_m[k] == 0.0f) {
      EXPECT_EQ(map.hazard[k], 0);
      ++safe;
    }
  }
  EXPECT_GT(safe, 1000);
}

TEST(AppearanceTest, CraterRimCastsAShadowIntoTheBowl) {
  TerrainOptions o;
  o.size = 128;
  o.relief_rms_m = 0.0;
  Terrain t;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  // A flat terrain has no shadows.
  AppearanceOptions a;
  a.sun_azimuth_deg = 0.0;  // sun towards +x
  a.sun_elevation_deg = 20.0;
  Appearance flat;
  ASSERT_EQ(flat.Configure(t, a), core::Status::kOk);
  for (std::uint8_t lit : flat.Lit()) ASSERT_EQ(lit, 1);
  // A crater bowl: its sunward inner wall (+x side, seen from inside) is in shadow near the rim.
  o.craters.density_at_1m = 0.117;  // about one crater of 4-4.5 m on 650 m^2
  o.craters.min_diameter_m = 4.0;
  o.craters.max_diameter_m = 4.5;
  o.craters.min_freshness = 1.0;
  o.size = 256;
  // Deterministically pick the first seed that gives one crater well inside the grid.
  bool found = false;
  for (std::uint64_t seed = 1; seed < 50 && !found; ++seed) {
    o.seed = seed;
    ASSERT_EQ(t.Configure(o), core::Status::kOk);
    found = t.Craters().size() == 1 &&
            std::abs(t.Craters()[0].center_m.x()) + 6.0 < t.HalfExtentM() &&
            std::abs(t.Craters()[0].center_m.y()) + 6.0 < t.HalfExtentM();
  }
  ASSERT_TRUE(found);
  Appearance shaded;
  ASSERT_EQ(shaded.Configure(t, a), core::Status::kOk);
  const Crater& c = t.Craters()[0];
  auto node_lit = [&](double x, double y) {
    const auto i = static_cast<std::int32_t>(std::lround((x - t.NodeX(0)) / o.cell_m));
    const auto j = static_cast<std::int32_t>(std::lround((y - t.NodeY(0)) / o.cell_m));
    return shaded.Lit()[static_cast<size_t>(j) * t.Size() + i];
  };
  const double r = 0.5 * c.diameter_m;
  // Just inside the rim on the sun side the bowl is hidden by that rim.
  EXPECT_EQ(node_lit(c.center_m.x() + 0.8 * r, c.center_m.y()), 0);
  // The inner wall facing the sun (the -x side) is lit.
  EXPECT_EQ(node_lit(c.center_m.x() - 0.8 * r, c.center_m.y()), 1);
}

TEST(TerrainTest, RejectsBadOptions) {
  testing::ExpectEachRefused<Terrain, TerrainOptions>({
      [](TerrainOptions& o) { o.size = 4; },
      [](TerrainOptions& o) { o.rocks.k = 1.5; },
      [](TerrainOptions& o) { o.craters.min_diameter_m = 50.0; },
  });
}

}  // namespace
}  // namespace swf::sim
