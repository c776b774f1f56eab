// The hazard-map-vs-truth metric on a hand-built map and truth whose answers are counted by hand.
//
// Geometry: a flat terrain tilted 0.1 in x, 81 x 81 nodes at 0.125 m (node x = -5 + 0.125 i,
// exact in binary, so boundary distances are exact); a published map of 16 x 16 cells of 0.5 m
// from (-4, -4), cell (i, j) centred at (-3.75 + 0.5 i, -3.75 + 0.5 j). Truth rocks are 0.2 m
// wide, so each occupies only the node at its centre; with threshold h = 0.08 m a cell is
// rock-free unless a rock >= 0.04 m is within 0.25 + 0.3 = 0.55 m of its centre (its own cell and
// the 4 neighbours at 0.5 m), and a rock is detected by a rock cell within 0.1 + 0.5 = 0.6 m.
// Resolvability (hazard::RockCriterion): a rock of radius R <= c / 2 fits in a quarter of a cell,
// so its relief is pi R^2 H / (6 c^2) less its lift of the reference quadric over 7 x 7 cells
// (3.5 m; centre weights alpha + beta |x|^2 with alpha = 11 / 147, beta = -1 / 147): (alpha V +
// beta (4/15 pi H R^4 + V c^2 / 2) / c^2) / c^2, V = 2/3 pi R^2 H. The threshold rock (0.08 m x
// 0.16 m) shows r_h = 1.07233 - 0.30608 = 0.76625 mm (averaged down), so the map resolves the
// threshold where r_h >= (3.090 + 1.645) sigma: sigma <= 0.16183 mm, sigma being the published
// relief sigma (the elevation sigma, 0.25 m everywhere here as if the pose error dominated it,
// resolves nothing). The truth rocks (0.2 m wide) show 0.0149691 H >= r_h.
#include "swf/hazard_eval/map_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "swf/app/hazard_stage.hpp"

namespace swf::hazard_eval {
namespace {

constexpr int kN = 16;
constexpr double kCellM = 0.5;
constexpr double kOriginM = -4.0;
constexpr double kRockThresholdM = 0.08;
constexpr double kFootprintM = 1.5;
constexpr float kTruthSlopeDeg = 5.0f;

double Centre(int i) { return kOriginM + (i + 0.5) * kCellM; }

class MapMetricsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    sim::TerrainOptions to;
    to.size = 81;
    to.cell_m = 0.125;
    to.tilt_x = 0.1;
    to.relief_rms_m = 0.0;
    ASSERT_EQ(terrain_.Configure(to), core::Status::kOk);
    ASSERT_DOUBLE_EQ(terrain_.NodeX(0), -5.0);
    const int tn = terrain_.Size();
    truth_.size = tn;
    truth_.cell_m = terrain_.CellM();
    truth_.slope_deg.assign(static_cast<std::size_t>(tn) * tn, kTruthSlopeDeg);
    truth_.rock_height_m.assign(truth_.slope_deg.size(), 0.0f);
    truth_.hazard.assign(truth_.slope_deg.size(), 0);
    // A: resolved, detected (height class [1, 2) h). B: resolved, flagged but missed (class
    // [2, 4) h). C: unresolved (class [4, inf) h). D: below the threshold but above half of it.
    // E: outside the map.
    AddRock(Centre(2), Centre(2), 0.10);   // A, cell (2, 2)
    AddRock(Centre(12), Centre(2), 0.20);  // B, cell (12, 2)
    AddRock(Centre(2), Centre(12), 0.40);  // C, cell (2, 12)
    AddRock(Centre(8), Centre(8), 0.05);   // D, cell (8, 8)
    AddRock(4.5, 4.5, 0.30);               // E

    const std::size_t cells = static_cast<std::size_t>(kN) * kN;
    elevation_.assign(cells, 0.0f);
    sigma_.assign(cells, 0.25f);
    relief_sigma_.assign(cells, 0.5f);  // unresolvable unless set below
    slope_.assign(cells, kTruthSlopeDeg + 1.0f);
    classes_.assign(cells, app::HazardClassCode(hazard::HazardClass::kSafe));
    for (int j = 0; j < kN; ++j) {
      for (int i = 0; i < kN; ++i) {
        // 5 cm above the tilted plane's cell mean (exact for a plane).
        At(&elevation_, i, j) = static_cast<float>(0.1 * Centre(i) + 0.05);
      }
    }
    for (int i = 0; i < kN; ++i) At(&elevation_, i, 15) = NAN;  // row 15 unknown: 240 known
    At(&slope_, 0, 0) = NAN;                                    // no slope there
    const std::int8_t rock = app::HazardClassCode(hazard::HazardClass::kRock);
    const std::int8_t uncertain = app::HazardClassCode(hazard::HazardClass::kUncertain);
    At(&relief_sigma_, 2, 2) = 0.00015f;  // A resolved (<= 0.00016183)
    At(&classes_, 3, 2) = rock;  // 0.5 m from A: detected; A's neighbour, so no false alarm
    At(&relief_sigma_, 12, 2) = 0.00015f;  // B resolved
    At(&relief_sigma_, 2, 12) = 0.02f;     // C not, though 3 sigma <= h
    At(&classes_, 12, 2) = uncertain;
    At(&classes_, 13, 2) = uncertain;
    At(&classes_, 14, 2) = rock;  // 1.0 m from B (> 0.6): missed; rock-free: a false alarm
    At(&classes_, 2, 12) = rock;  // on C, unresolved: not counted, not a false alarm
    At(&classes_, 8, 8) = rock;   // on D: not a false alarm (D >= h / 2)
    At(&classes_, 5, 15) = rock;  // unknown cell: not counted at all
  }

  void AddRock(double x, double y, double height_m) {
    sim::Rock r;
    r.center_m = {x, y};
    r.diameter_m = 0.2;
    r.height_m = height_m;
    rocks_.push_back(r);
    const int i = static_cast<int>(std::lround((x - terrain_.NodeX(0)) / terrain_.CellM()));
    const int j = static_cast<int>(std::lround((y - terrain_.NodeY(0)) / terrain_.CellM()));
    truth_.rock_height_m[static_cast<std::size_t>(j) * truth_.size + i] =
        static_cast<float>(height_m);
  }
  template <typename T>
  static T& At(std::vector<T>* v, int i, int j) {
    return (*v)[static_cast<std::size_t>(j) * kN + i];
  }
  void SetHazardNode(double x, double y) {
    const int i = static_cast<int>(std::lround((x - terrain_.NodeX(0)) / terrain_.CellM()));
    const int j = static_cast<int>(std::lround((y - terrain_.NodeY(0)) / terrain_.CellM()));
    ASSERT_DOUBLE_EQ(terrain_.NodeX(i), x);
    ASSERT_DOUBLE_EQ(terrain_.NodeY(j), y);
    truth_.hazard[static_cast<std::size_t>(j) * truth_.size + i] = sim::kHazardRock;
  }
  HazardMapView View() const {
    HazardMapView v;
    v.frame_seq = 7;
    v.origin_world_m[0] = kOriginM;
    v.origin_world_m[1] = kOriginM;
    v.cell_m = kCellM;
    v.cells_per_side = kN;
    v.elevation_m = elevation_.data();
    v.sigma_m = sigma_.data();
    v.relief_sigma_m = relief_sigma_.data();
    v.slope_deg = slope_.data();
    v.hazard_class = classes_.data();
    return v;
  }
  HazardMapMetrics Evaluate(const HazardMapView& v, bool cell_errors = true) const {
    MetricOptions o;
    o.max_rock_height_m = kRockThresholdM;
    o.footprint_radius_m = kFootprintM;
    o.cell_errors = cell_errors;
    return EvaluateHazardMap(v, terrain_, rocks_, truth_, o);
  }

  sim::Terrain terrain_;
  sim::HazardMap truth_;
  std::vector<sim::Rock> rocks_;
  std::vector<float> elevation_;
  std::vector<float> sigma_;
  std::vector<float> relief_sigma_;
  std::vector<float> slope_;
  std::vector<std::int8_t> classes_;
};

TEST_F(MapMetricsTest, RocksDetectedMissedUnresolvedAndOneFalseAlarm) {
  const HazardMapMetrics m = Evaluate(View());
  EXPECT_EQ(m.cell_m, kCellM);
  EXPECT_EQ(m.known_cells, 240);
  EXPECT_EQ(m.rock_cells, 4);      // (3, 2), (14, 2), (2, 12), (8, 8); not the unknown (5, 15)
  EXPECT_EQ(m.rocks_resolved, 2);  // A and B; C unresolved (averaged down), D below h, E outside
  EXPECT_EQ(m.rocks_detected, 1);  // A
  EXPECT_EQ(m.rocks_flagged, 2);   // A (rock), B (uncertain)
  EXPECT_EQ(m.rocks_resolved_by_height[0], 1);
  EXPECT_EQ(m.rocks_resolved_by_height[1], 1);
  EXPECT_EQ(m.rocks_resolved_by_height[2], 0);
  EXPECT_EQ(m.rocks_detected_by_height[0], 1);
  EXPECT_EQ(m.rocks_detected_by_height[1], 0);
  EXPECT_DOUBLE_EQ(m.detection_probability, 0.5);
  // Not rock-free: each of A, B, C, D's cell and its 4 neighbours (all known).
  EXPECT_EQ(m.rock_free_cells, 240 - 4 * 5);
  EXPECT_EQ(m.false_rock_cells, 1);  // (14, 2)
  EXPECT_DOUBLE_EQ(m.false_alarm_rate, 1.0 / 220.0);
  EXPECT_FALSE(m.site_valid);
  EXPECT_EQ(m.site_clearance_m, -1.0);
}

// GIVEN a rock whose cell has no relief sigma (no plane was fitted there) THEN it is not resolved,
// whatever the elevation sigma says: the metric judges with the number the mapper decided with.
TEST_F(MapMetricsTest, ACellWithoutReliefSigmaResolvesNothing) {
  At(&relief_sigma_, 12, 2) = NAN;  // B
  At(&sigma_, 12, 2) = 0.0001f;
  const HazardMapMetrics m = Evaluate(View());
  EXPECT_EQ(m.rocks_resolved, 1);  // A only
  EXPECT_EQ(m.rocks_detected, 1);
  EXPECT_DOUBLE_EQ(m.detection_probability, 1.0);
}

TEST_F(MapMetricsTest, PerCellErrorsAgainstTheTerrain) {
  const HazardMapMetrics m = Evaluate(View());
  ASSERT_EQ(m.elevation_errors_m.size(), 240u);
  ASSERT_EQ(m.elevation_sigmas_m.size(), 240u);
  ASSERT_EQ(m.slope_errors_deg.size(), 239u);  // cell (0, 0) has no slope
  for (std::size_t k = 0; k < m.elevation_errors_m.size(); ++k) {
    EXPECT_NEAR(m.elevation_errors_m[k], 0.05, 1e-6);
  }
  for (double e : m.slope_errors_deg) EXPECT_DOUBLE_EQ(e, 1.0);
  EXPECT_EQ(m.elevation_sigmas_m[2 * kN + 2],
            0.25f);  // A's cell: the elevation's, not the relief's

  HazardMapView no_slope = View();
  no_slope.slope_deg = nullptr;
  EXPECT_TRUE(Evaluate(no_slope).slope_errors_deg.empty());
  const HazardMapMetrics counts_only = Evaluate(View(), /*cell_errors=*/false);
  EXPECT_TRUE(counts_only.elevation_errors_m.empty());
  EXPECT_EQ(counts_only.rocks_detected, 1);
  EXPECT_EQ(counts_only.false_rock_cells, 1);
}

// GIVEN one truth hazard node WHEN the site is exactly a footprint radius from it THEN it is on
// the hazard (the footprint is a closed disc); a hair further it is not.
TEST_F(MapMetricsTest, SiteOnHazardAtTheFootprintBoundary) {
  SetHazardNode(0.25, -3.25);
  HazardMapView v = View();
  v.site_valid = true;
  v.site_world_m[0] = 0.25;
  v.site_world_m[1] = -3.25 + kFootprintM;
  v.site_score = 0.75;
  HazardMapMetrics m = Evaluate(v);
  EXPECT_TRUE(m.site_valid);
  EXPECT_EQ(m.site_world_m[0], 0.25);
  EXPECT_EQ(m.site_world_m[1], -1.75);
  EXPECT_EQ(m.site_score, 0.75);
  EXPECT_EQ(m.site_clearance_m, kFootprintM);
  EXPECT_TRUE(m.site_on_hazard);

  v.site_world_m[1] = -3.25 + kFootprintM + std::ldexp(1.0, -20);
  m = Evaluate(v);
  EXPECT_GT(m.site_clearance_m, kFootprintM);
  EXPECT_LT(m.site_clearance_m, kFootprintM + 1e-5);
  EXPECT_FALSE(m.site_on_hazard);
}

// GIVEN no truth hazard within the search radius THEN the clearance is the cap, off hazard.
TEST_F(MapMetricsTest, ClearanceIsCappedAtTheSearchRadius) {
  HazardMapView v = View();
  v.site_valid = true;
  v.site_world_m[0] = 0.25;
  v.site_world_m[1] = -1.75;
  const HazardMapMetrics m = Evaluate(v);
  EXPECT_EQ(m.site_clearance_m, kSiteSearchM);
  EXPECT_FALSE(m.site_on_hazard);
}

// GIVEN a published record WHEN viewed THEN the view reads the record's own arrays and fields.
TEST(MapViewTest, ViewOfAPublishedRecord) {
  app::HazardRecord r;
  ASSERT_EQ(r.Allocate(4), core::Status::kOk);
  r.frame_seq = 12;
  r.origin_world_m[0] = -1.0;
  r.origin_world_m[1] = 2.0;
  r.cell_size_m = 0.25;
  r.cells_per_side = 2;
  r.safe_site_valid = true;
  r.safe_site_world_m[0] = -0.75;
  r.safe_site_world_m[1] = 2.25;
  r.safe_site_score = 0.5;
  const HazardMapView v = ViewOf(r);
  EXPECT_EQ(v.frame_seq, 12);
  EXPECT_EQ(v.origin_world_m[0], -1.0);
  EXPECT_EQ(v.origin_world_m[1], 2.0);
  EXPECT_EQ(v.cell_m, 0.25);
  EXPECT_EQ(v.cells_per_side, 2);
  EXPECT_EQ(v.elevation_m, r.elevation_m.get());
  EXPECT_EQ(v.sigma_m, r.sigma_m.get());
  EXPECT_EQ(v.relief_sigma_m, r.relief_sigma_m.get());
  EXPECT_EQ(v.slope_deg, r.slope_deg.get());
  EXPECT_EQ(v.hazard_class, r.hazard_class.get());
  EXPECT_TRUE(v.site_valid);
  EXPECT_EQ(v.site_world_m[0], -0.75);
  EXPECT_EQ(v.site_world_m[1], 2.25);
  EXPECT_EQ(v.site_score, 0.5);
}

}  // namespace
}  // namespace swf::hazard_eval
