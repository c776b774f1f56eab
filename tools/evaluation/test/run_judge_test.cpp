// RunJudge: estimates paired with truth by frame and landmark id, whatever the order; the
// figures against hand-computed values; bad bytes counted and named, never fatal.
#include "swf/evaluation/run_judge.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace swf::evaluation {
namespace {

swf_msgs::nav_state_t Nav(std::int64_t frame, double x, double z, std::int8_t status,
                          double sigma_m, double pl_m) {
  swf_msgs::nav_state_t m{};
  m.frame_seq = frame;
  m.position_world_m[0] = x;
  m.position_world_m[2] = z;
  m.orientation_world_q[0] = 1.0;
  for (int i = 0; i < 3; ++i) m.covariance[6 * i + i] = sigma_m * sigma_m;
  m.status = status;
  m.horizontal_protection_m = pl_m;
  m.vertical_protection_m = pl_m;
  return m;
}

swf_msgs::truth_state_t Truth(std::int64_t frame, double z, double altitude_m) {
  swf_msgs::truth_state_t m{};
  m.frame_seq = frame;
  m.position_world_m[2] = z;
  m.orientation_world_q[0] = 1.0;
  m.altitude_m = altitude_m;
  return m;
}

swf_msgs::landmark_map_t Map(std::int64_t frame, const std::vector<std::int64_t>& ids,
                             const std::vector<double>& x) {
  swf_msgs::landmark_map_t m{};
  m.frame_seq = frame;
  m.num_landmarks = static_cast<std::int32_t>(ids.size());
  m.id = ids;
  for (double xi : x) m.position_world_m.push_back({xi, 0.0, 0.0});
  m.covariance_m2.assign(ids.size(), std::vector<double>(6, 0.0));
  m.num_observations.assign(ids.size(), 1);
  return m;
}

template <typename Msg>
std::vector<std::uint8_t> Encode(const Msg& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// A 4 x 4 map of 1 m cells at the origin: all known but cell (0, 3), elevation sigma 0.05 m (the
// pose's share), relief sigma 0.05 m but 0.001 m at cell (1, 1), safe but a rock at cell (1, 1)
// and one at (3, 3); its site at (0.5, 0.5).
swf_msgs::hazard_map_t HazardMap(std::int64_t frame) {
  swf_msgs::hazard_map_t m{};
  m.frame_seq = frame;
  m.cell_size_m = 1.0;
  m.rows = 4;
  m.cols = 4;
  m.num_cells = 16;
  m.elevation_m.assign(16, 0.0f);
  m.elevation_m[3 * 4 + 0] = NAN;
  m.sigma_m.assign(16, 0.05f);
  m.relief_sigma_m.assign(16, 0.05f);
  m.relief_sigma_m[1 * 4 + 1] = 0.001f;
  m.slope_deg.assign(16, 1.0f);
  m.roughness_m.assign(16, 0.0f);
  m.hazard_class.assign(16, swf_msgs::hazard_map_t::CLASS_SAFE);
  m.hazard_class[1 * 4 + 1] = swf_msgs::hazard_map_t::CLASS_ROCK;
  m.hazard_class[3 * 4 + 3] = swf_msgs::hazard_map_t::CLASS_ROCK;
  m.safe_site_valid = true;
  m.safe_site_world_m[0] = 0.5;
  m.safe_site_world_m[1] = 0.5;
  return m;
}

// Its truth: flat, one 0.5 m rock of 1 m diameter on cell (1, 1) (the only cell not rock-free),
// the site 1.2 m from a hazard (inside the 1.5 m footprint).
swf_msgs::hazard_truth_t HazardTruth(std::int64_t frame, double cell_m = 1.0) {
  swf_msgs::hazard_truth_t t{};
  t.frame_seq = frame;
  t.cell_size_m = cell_m;
  t.rows = 4;
  t.cols = 4;
  t.num_cells = 16;
  t.elevation_m.assign(16, 0.1);
  t.slope_deg.assign(16, 3.0f);
  t.rock_free.assign(16, 1);
  t.rock_free[1 * 4 + 1] = 0;
  t.max_rock_height_m = 0.3;
  t.footprint_radius_m = 1.5;
  t.num_rocks = 1;
  t.rock_center_world_m = {{1.5, 1.5}};
  t.rock_diameter_m = {1.0};
  t.rock_height_m = {0.5};
  t.site_valid = true;
  t.site_world_m[0] = 0.5;
  t.site_world_m[1] = 0.5;
  t.site_clearance_m = 1.2;
  t.site_search_m = 20.0;
  return t;
}

TEST(RunJudge, PairsEstimatesWithTheTruthOfTheirFrame) {
  RunJudge judge;
  // Truth of frame 2 arrives before its estimate, frame 1's after; frame 3 has no truth.
  judge.AddTruth(Truth(2, 50.0, 48.0));
  judge.AddNav(Nav(1, 0.3, 60.0, swf_msgs::nav_state_t::STATUS_VALID, 0.1, 0.5));
  judge.AddNav(Nav(2, 0.0, 50.4, swf_msgs::nav_state_t::STATUS_VALID, 0.2, 0.3));
  judge.AddNav(Nav(3, 0.0, 40.0, swf_msgs::nav_state_t::STATUS_DEGRADED, 0.1, 0.5));
  judge.AddTruth(Truth(1, 60.0, 58.0));
  const RunScore s = judge.Score();
  ASSERT_EQ(s.outputs.size(), 2u);
  EXPECT_EQ(s.navs_without_truth, 1);
  EXPECT_EQ(s.outputs[0].frame_seq, 1);
  EXPECT_DOUBLE_EQ(s.outputs[0].horizontal_error_m, 0.3);
  EXPECT_DOUBLE_EQ(s.outputs[0].altitude_m, 58.0);
  EXPECT_NEAR(s.outputs[0].position_nees, 9.0, 1e-9);  // (0.3 / 0.1)^2
  EXPECT_NEAR(s.outputs[1].vertical_error_m, 0.4, 1e-12);
  EXPECT_NEAR(s.outputs[1].position_nees, 4.0, 1e-9);  // (0.4 / 0.2)^2
  EXPECT_NEAR(s.mean_position_nees, 6.5, 1e-9);
  EXPECT_NEAR(s.pose_rms_error_m, std::sqrt((0.09 + 0.16) / 2), 1e-12);
  EXPECT_NEAR(s.final_pose_error_m, 0.4, 1e-12);
  EXPECT_EQ(s.final_attitude_error_deg, 0.0);
  // Frame 2 erred 0.4 m against a 0.3 m protection level while VALID: an integrity failure.
  EXPECT_EQ(s.valid_navs, 2);
  EXPECT_EQ(s.protection_violations, 1);
  EXPECT_NEAR(s.max_error_over_protection, 0.4 / 0.3, 1e-12);
}

// What the plots show per output: its time, the sigmas of its own covariance, and the attitude
// error about the estimate's camera axes in the covariance's convention (true R = est R Exp(phi)).
TEST(RunJudge, KeepsTimeSigmasAndAttitudeErrorPerCameraAxis) {
  RunJudge judge;
  swf_msgs::nav_state_t nav = Nav(4, 0.0, 30.0, swf_msgs::nav_state_t::STATUS_VALID, 0.2, 1.0);
  nav.utime = 1'234'567;
  nav.covariance[6 * 4 + 4] = 0.01 * 0.01;  // phi_y sigma 0.01 rad; phi_x, phi_z have none
  // The estimate is the truth turned by 0.02 rad about the camera's y axis: est R = true R
  // Exp(0.02 y), so Log(est R^T true R) = -0.02 y.
  const double half = 0.5 * 0.02;
  nav.orientation_world_q[0] = std::cos(half);
  nav.orientation_world_q[2] = std::sin(half);
  judge.AddNav(nav);
  judge.AddTruth(Truth(4, 30.0, 29.0));
  const RunScore s = judge.Score();
  ASSERT_EQ(s.outputs.size(), 1u);
  const OutputScore& o = s.outputs[0];
  EXPECT_EQ(o.utime, 1'234'567);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(o.position_sigma_m[i], 0.2, 1e-12);
  EXPECT_TRUE(std::isnan(o.attitude_sigma_deg[0]));
  EXPECT_NEAR(o.attitude_sigma_deg[1], 0.01 * 180.0 / M_PI, 1e-12);
  EXPECT_TRUE(std::isnan(o.attitude_sigma_deg[2]));
  EXPECT_NEAR(o.attitude_error_axes_deg[0], 0.0, 1e-12);
  EXPECT_NEAR(o.attitude_error_axes_deg[1], -0.02 * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(o.attitude_error_axes_deg[2], 0.0, 1e-12);
  EXPECT_NEAR(o.attitude_error_deg, 0.02 * 180.0 / M_PI, 1e-9);
}

TEST(RunJudge, JudgesLandmarksOfEachMapAgainstTheirTruthById) {
  RunJudge judge;
  judge.AddLandmarks(Map(5, {7, 8, 9}, {1.0, 2.0, 3.0}));
  judge.AddTruthLandmarks(Map(5, {9, 7}, {3.5, 1.0}));  // 8 has no truth (its ray missed)
  judge.AddLandmarks(Map(6, {7}, {1.0}));               // no truth map for frame 6
  const RunScore s = judge.Score();
  ASSERT_EQ(s.maps.size(), 1u);
  EXPECT_EQ(s.maps_without_truth, 1);
  EXPECT_EQ(s.maps[0].landmarks_evaluated, 2);
  EXPECT_NEAR(s.maps[0].rms_error_m, std::sqrt(0.25 / 2), 1e-12);
  EXPECT_DOUBLE_EQ(s.maps[0].median_error_m, 0.5);  // upper median of {0, 0.5}
  ASSERT_EQ(s.last_map.size(), 2u);
  EXPECT_EQ(s.last_map[1].id, 9);
  EXPECT_DOUBLE_EQ(s.last_map[1].truth_m[0], 3.5);
}

// GIVEN a map whose landmarks state covariances WHEN it is judged THEN each landmark of the last
// map keeps its stated covariance and observations and its NEES e^T P^-1 e; a landmark without
// a positive definite covariance has none (NaN), not a number made up.
TEST(RunJudge, KeepsEachLandmarksStatedCovarianceAndNees) {
  RunJudge judge;
  swf_msgs::landmark_map_t m = Map(5, {7, 9}, {1.0, 3.0});
  m.covariance_m2[0] = {0.04, 0.0, 0.0, 1.0, 0.0, 1.0};  // x: 0.2 m 1-sigma
  m.num_observations[0] = 4;
  judge.AddLandmarks(m);
  judge.AddTruthLandmarks(Map(5, {7, 9}, {1.5, 3.5}));  // both 0.5 m off in x
  const RunScore s = judge.Score();
  ASSERT_EQ(s.last_map.size(), 2u);
  EXPECT_EQ(s.last_map[0].num_observations, 4);
  EXPECT_DOUBLE_EQ(s.last_map[0].covariance_m2[0], 0.04);
  EXPECT_NEAR(s.last_map[0].nees, 0.25 / 0.04, 1e-12);
  EXPECT_TRUE(std::isnan(s.last_map[1].nees));  // a zero covariance
}

TEST(RunJudge, ReadsBytesByChannelAndCountsWhatDoesNotDecode) {
  RunJudge judge;
  const std::vector<std::uint8_t> nav =
      Encode(Nav(1, 0.0, 10.0, swf_msgs::nav_state_t::STATUS_VALID, 0.1, 1.0));
  const std::vector<std::uint8_t> truth = Encode(Truth(1, 10.0, 9.0));
  EXPECT_TRUE(judge.Add("SWF_NAV", nav.data(), nav.size()));
  EXPECT_TRUE(judge.Add("SIM_TRUTH", truth.data(), truth.size()));
  EXPECT_TRUE(judge.Add("SWF_HEALTH", nav.data(), nav.size()));  // not judged: ignored
  // A truth state on the estimates' channel, and a cut message: counted, named.
  EXPECT_FALSE(judge.Add("SWF_NAV", truth.data(), truth.size()));
  EXPECT_FALSE(judge.Add("SIM_TRUTH", truth.data(), truth.size() - 3));
  const RunScore s = judge.Score();
  EXPECT_EQ(s.outputs.size(), 1u);
  EXPECT_EQ(s.undecodable, 2);
  EXPECT_NE(s.first_decode_error.find("SWF_NAV"), std::string::npos) << s.first_decode_error;
}

TEST(RunJudge, NothingToJudgeGivesNoNumbersNotZeros) {
  const RunScore s = RunJudge().Score();
  EXPECT_TRUE(s.outputs.empty());
  EXPECT_TRUE(std::isnan(s.pose_rms_error_m));
  EXPECT_TRUE(std::isnan(s.mean_position_nees));
}

TEST(RunJudge, JudgesHazardMapsAgainstTheTruthOfTheirGrid) {
  RunJudge judge;
  judge.AddTruth(Truth(10, 60.0, 58.0));
  // Truth before its map (frame 10) and after it (20); a map never answered (30); a truth drawn
  // for another grid (40).
  judge.AddTruthHazard(HazardTruth(10));
  judge.AddHazard(HazardMap(10));
  judge.AddHazard(HazardMap(20));
  judge.AddTruthHazard(HazardTruth(20));
  judge.AddHazard(HazardMap(30));
  judge.AddHazard(HazardMap(40));
  judge.AddTruthHazard(HazardTruth(40, 2.0));
  const RunScore s = judge.Score();
  ASSERT_EQ(s.hazard_maps.size(), 2u);
  EXPECT_EQ(s.hazard_maps[0].frame_seq, 10);
  EXPECT_EQ(s.hazard_maps[0].altitude_m, 58.0);
  EXPECT_TRUE(std::isnan(s.hazard_maps[1].altitude_m));  // no truth state of frame 20
  EXPECT_EQ(s.hazard_maps_without_truth, 1);
  EXPECT_EQ(s.hazard_truth_mismatched, 1);
  const HazardMapMetrics& m = s.hazard_maps[0].map;
  EXPECT_EQ(m.known_cells, 15);
  EXPECT_EQ(m.rock_cells, 2);
  // Resolved (hazard::RockCriterion): 1 m cells, a 5 m reference quadric window (centre weights
  // alpha + beta |x|^2, alpha = 27 / 175, beta = -1 / 35); the threshold rock (0.3 m x 0.6 m)
  // fits in a cell's quarter and shows 0.3 pi 0.09 / 6 = 14.137 mm less its lift of the quadric
  // (alpha V + beta (4/15 pi H R^4 + V / 2), V = 2/3 pi R^2 H) 7.859 mm = 6.279 mm, so the
  // threshold is resolved for a relief sigma <= 6.279 / 4.735 = 1.326 mm (0.001 m at the rock's
  // cell, whose elevation sigma of 0.05 m would not resolve it; not the others' 0.05 m,
  // although 3 sigma <= h there); the 0.5 m rock shows more.
  EXPECT_EQ(m.rocks_resolved, 1);
  EXPECT_EQ(m.rocks_detected, 1);               // the rock cell (1, 1) lies on it
  EXPECT_EQ(m.rocks_resolved_by_height[0], 1);  // 0.5 m: [1, 2) x 0.3 m
  EXPECT_EQ(m.rock_free_cells, 14);             // the known cells but (1, 1)
  EXPECT_EQ(m.false_rock_cells, 1);             // (3, 3)
  EXPECT_DOUBLE_EQ(m.false_alarm_rate, 1.0 / 14.0);
  EXPECT_EQ(m.site_clearance_m, 1.2);
  EXPECT_TRUE(m.site_on_hazard);
  EXPECT_TRUE(m.elevation_errors_m.empty());  // the judge reports counts, not per-cell errors
  // Per-cell errors when asked: |0 - 0.1| per known cell, |1 - 3| degrees of slope.
  const HazardMapMetrics cells = JudgeHazardMap(ViewOf(HazardMap(10)), HazardTruth(10), true);
  ASSERT_EQ(cells.elevation_errors_m.size(), 15u);
  EXPECT_DOUBLE_EQ(cells.elevation_errors_m[0], 0.1);
  EXPECT_EQ(cells.slope_errors_deg[0], 2.0);
}

TEST(RunJudge, HazardMessagesAreReadByChannel) {
  RunJudge judge;
  const std::vector<std::uint8_t> map = Encode(HazardMap(5));
  const std::vector<std::uint8_t> truth = Encode(HazardTruth(5));
  EXPECT_TRUE(judge.Add("SWF_HAZARD", map.data(), map.size()));
  EXPECT_FALSE(judge.Add("SIM_TRUTH_HAZARD", map.data(), map.size()));  // a map is no truth
  EXPECT_TRUE(judge.Add("SIM_TRUTH_HAZARD", truth.data(), truth.size()));
  const RunScore s = judge.Score();
  EXPECT_EQ(s.hazard_maps.size(), 1u);
  EXPECT_EQ(s.undecodable, 1);
}

}  // namespace
}  // namespace swf::evaluation
