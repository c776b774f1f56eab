// The guidance consumer over in-process LCM (memq://): sequence gaps are counted as lost, and a
// malformed or foreign message on a subscribed channel is counted and ignored.
#include "guidance_monitor.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace swf::guidance {
namespace {

void PublishNav(lcm::LCM* lcm, std::int64_t seq) {
  swf_msgs::nav_state_t nav{};
  nav.seq = seq;
  nav.frame_seq = seq;
  nav.position_world_m[2] = 100.0 - seq;
  ASSERT_EQ(lcm->publish("SWF_NAV", &nav), 0);
}

TEST(GuidanceMonitorTest, CountsLostAndMalformedAndKeepsGoing) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  GuidanceMonitor monitor(&lcm, "SWF_", false);
  PublishNav(&lcm, 0);
  PublishNav(&lcm, 1);
  const std::vector<std::uint8_t> garbage = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  ASSERT_EQ(lcm.publish("SWF_NAV", garbage.data(), static_cast<unsigned>(garbage.size())), 0);
  swf_msgs::health_t foreign{};  // the right channel, the wrong type
  ASSERT_EQ(lcm.publish("SWF_NAV", &foreign), 0);
  PublishNav(&lcm, 4);  // 2 and 3 lost
  PublishNav(&lcm, 5);
  PublishNav(&lcm, 3);  // late
  for (int i = 0; i < 20 && lcm.handleTimeout(10) > 0; ++i) {
  }
  EXPECT_EQ(monitor.Nav().received, 5);
  EXPECT_EQ(monitor.Nav().malformed, 2);
  EXPECT_EQ(monitor.Nav().lost, 2);
  EXPECT_EQ(monitor.Nav().out_of_order, 1);
  EXPECT_EQ(monitor.LastNav().seq, 3);
  EXPECT_DOUBLE_EQ(monitor.LastNav().position_world_m[2], 97.0);
}

// GIVEN hazard maps on SWF_HAZARD WHEN one is consistent, one claims more cells than rows x cols
// and one carries an unknown class THEN only the first is accepted, the others are counted as
// malformed, and the sequence check sees no gap.
TEST(GuidanceMonitorTest, HazardMapsAreCheckedForConsistency) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  GuidanceMonitor monitor(&lcm, "SWF_", false);
  swf_msgs::hazard_map_t good{};
  good.seq = 0;
  good.frame_seq = 4;
  good.rows = 1;
  good.cols = 2;
  good.num_cells = 2;
  good.elevation_m = {0.5f, 0.25f};
  good.sigma_m = {0.1f, 0.1f};
  good.slope_deg = {1.0f, 2.0f};
  good.roughness_m = {0.0f, 0.3f};
  good.hazard_class = {swf_msgs::hazard_map_t::CLASS_SAFE, swf_msgs::hazard_map_t::CLASS_UNCERTAIN};
  ASSERT_EQ(lcm.publish("SWF_HAZARD", &good), 0);
  swf_msgs::hazard_map_t wrong_size = good;
  wrong_size.seq = 1;
  wrong_size.rows = 2;
  ASSERT_EQ(lcm.publish("SWF_HAZARD", &wrong_size), 0);
  swf_msgs::hazard_map_t bad_class = good;
  bad_class.seq = 1;
  bad_class.hazard_class[1] = 42;
  ASSERT_EQ(lcm.publish("SWF_HAZARD", &bad_class), 0);
  swf_msgs::hazard_map_t next = good;
  next.seq = 1;
  next.frame_seq = 9;
  ASSERT_EQ(lcm.publish("SWF_HAZARD", &next), 0);
  for (int i = 0; i < 20 && lcm.handleTimeout(10) > 0; ++i) {
  }
  EXPECT_EQ(monitor.Hazard().received, 2);
  EXPECT_EQ(monitor.Hazard().malformed, 2);
  EXPECT_EQ(monitor.Hazard().lost, 0);
  EXPECT_EQ(monitor.LastHazard().frame_seq, 9);
}

}  // namespace
}  // namespace swf::guidance
