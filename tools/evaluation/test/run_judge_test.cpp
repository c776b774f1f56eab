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

}  // namespace
}  // namespace swf::evaluation
