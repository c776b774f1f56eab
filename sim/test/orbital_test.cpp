#include "swf/sim/orbital.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace swf::sim {
namespace {

TerrainOptions Flat() {
  TerrainOptions o;
  o.size = 512;  // 51.1 m square
  o.relief_rms_m = 0.0;
  return o;
}

OrbitalSelectionOptions Search(double radius_m) {
  OrbitalSelectionOptions o;
  o.search_radius_m = radius_m;
  return o;
}

TEST(OrbitalTest, FlatGroundKeepsTheNominalTarget) {
  Terrain t;
  ASSERT_EQ(t.Configure(Flat()), core::Status::kOk);
  OrbitalTarget target;
  ASSERT_EQ(SelectOrbitalTarget(t, Search(10.0), &target), core::Status::kOk);
  EXPECT_EQ(target.hazard_posts, 0);
  EXPECT_DOUBLE_EQ(target.clearance_m, 10.0);
  EXPECT_DOUBLE_EQ(target.distance_m, 0.0);
  EXPECT_NEAR(target.target_m.norm(), 0.0, 1e-12);
}

TEST(OrbitalTest, SteepGroundEverywhereIsAllHazardAndKeepsTheNominalTarget) {
  TerrainOptions o = Flat();
  o.tilt_x =
      std::tan(15.0 * std::numbers::pi / 180.0);  // steeper than the 10 deg threshold everywhere
  Terrain t;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  OrbitalTarget target;
  ASSERT_EQ(SelectOrbitalTarget(t, Search(10.0), &target), core::Status::kOk);
  EXPECT_DOUBLE_EQ(target.clearance_m, 0.0);
  EXPECT_DOUBLE_EQ(target.distance_m, 0.0);
}

// On a rock and crater field the target moves off the nominal point only as far as it must, and
// every orbit-visible hazard (big rocks here) stays beyond the clearance it reports.
TEST(OrbitalTest, TargetKeepsItsClearanceFromResolvedRocks) {
  TerrainOptions o = TerrainPresetOptions(TerrainPreset::kRockField, 1);
  o.size = 1024;  // 102.3 m square: search 20 m + cap 10 m fits
  Terrain t;
  ASSERT_EQ(t.Configure(o), core::Status::kOk);
  const OrbitalSelectionOptions so = Search(20.0);
  OrbitalTarget target;
  ASSERT_EQ(SelectOrbitalTarget(t, so, &target), core::Status::kOk);
  EXPECT_GT(target.hazard_posts, 0);
  EXPECT_LE(target.distance_m, so.search_radius_m);
  EXPECT_GT(target.clearance_m, 2.0 * 1.5);  // well beyond a 1.5 m lander footprint
  for (const Rock& rock : t.Rocks()) {
    if (rock.diameter_m < so.min_rock_diameter_m) continue;
    // A rock touches a hazard post at most half a post diagonal beyond its edge.
    EXPECT_GT((rock.center_m - target.target_m).norm() - 0.5 * rock.diameter_m,
              target.clearance_m - std::sqrt(0.5) * so.post_m);
  }
  OrbitalTarget again;
  ASSERT_EQ(SelectOrbitalTarget(t, so, &again), core::Status::kOk);
  EXPECT_EQ(again.target_m, target.target_m);
}

TEST(OrbitalTest, RejectsSearchesOutsideTheTerrainAndBadOptions) {
  Terrain t;
  ASSERT_EQ(t.Configure(Flat()), core::Status::kOk);
  OrbitalTarget target;
  EXPECT_EQ(SelectOrbitalTarget(t, Search(20.0), &target), core::Status::kInvalidArgument);
  OrbitalSelectionOptions o = Search(5.0);
  o.post_m = 0.0;
  EXPECT_EQ(SelectOrbitalTarget(t, o, &target), core::Status::kInvalidArgument);
  EXPECT_EQ(SelectOrbitalTarget(Terrain(), Search(5.0), &target), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::sim
