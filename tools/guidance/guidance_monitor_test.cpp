// The guidance consumer over in-process LCM (memq://): sequence gaps are counted as lost, and a
// malformed or foreign message on a subscribed channel is counted and ignored.
#include "guidance_monitor.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <vector>

#include "swf/testing/encode.hpp"
#include "swf/testing/sample_messages.hpp"

namespace swf::guidance {
namespace {

using swf::testing::Encode;
using swf::testing::WithInt32;

// Each test's in-process LCM (memq://: a publish is queued until handled) and the monitor
// subscribed on it.
class GuidanceMonitorTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(lcm_.good()); }

  void PublishNav(std::int64_t seq) {
    swf_msgs::nav_state_t nav{};
    nav.seq = seq;
    nav.frame_seq = seq;
    nav.position_world_m[2] = 100.0 - seq;
    ASSERT_EQ(lcm_.publish("SWF_NAV", &nav), 0);
  }

  // Hands everything published so far to the monitor.
  void Deliver() {
    for (int i = 0; i < 20 && lcm_.handleTimeout(10) > 0; ++i) {
    }
  }

  // One channel's counts after Deliver().
  static void ExpectCounts(const ChannelStats& channel, std::int64_t received,
                           std::int64_t malformed, std::int64_t lost) {
    EXPECT_EQ(channel.received, received);
    EXPECT_EQ(channel.malformed, malformed);
    EXPECT_EQ(channel.lost, lost);
  }

  lcm::LCM lcm_{"memq://"};
  GuidanceMonitor monitor_{&lcm_, "SWF_", false};
};

TEST_F(GuidanceMonitorTest, CountsLostAndMalformedAndKeepsGoing) {
  PublishNav(0);
  PublishNav(1);
  const std::vector<std::uint8_t> garbage = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  ASSERT_EQ(lcm_.publish("SWF_NAV", garbage.data(), static_cast<unsigned>(garbage.size())), 0);
  swf_msgs::health_t foreign{};  // the right channel, the wrong type
  ASSERT_EQ(lcm_.publish("SWF_NAV", &foreign), 0);
  PublishNav(4);  // 2 and 3 lost
  PublishNav(5);
  PublishNav(3);  // late
  Deliver();
  ExpectCounts(monitor_.Nav(), 5, 2, 2);
  EXPECT_EQ(monitor_.Nav().out_of_order, 1);
  EXPECT_EQ(monitor_.LastNav().seq, 3);
  EXPECT_DOUBLE_EQ(monitor_.LastNav().position_world_m[2], 97.0);
}

// GIVEN hazard maps on SWF_HAZARD WHEN one is consistent, one claims more cells than rows x cols
// and one carries an unknown class THEN only the first is accepted, the others are counted as
// malformed, and the sequence check sees no gap.
TEST_F(GuidanceMonitorTest, HazardMapsAreCheckedForConsistency) {
  swf_msgs::hazard_map_t good = swf::testing::SafeAndRockCells();
  good.seq = 0;
  good.frame_seq = 4;
  ASSERT_EQ(lcm_.publish("SWF_HAZARD", &good), 0);
  swf_msgs::hazard_map_t wrong_size = good;
  wrong_size.seq = 1;
  wrong_size.rows = 2;
  ASSERT_EQ(lcm_.publish("SWF_HAZARD", &wrong_size), 0);
  swf_msgs::hazard_map_t bad_class = good;
  bad_class.seq = 1;
  bad_class.hazard_class[1] = 42;
  ASSERT_EQ(lcm_.publish("SWF_HAZARD", &bad_class), 0);
  swf_msgs::hazard_map_t next = good;
  next.seq = 1;
  next.frame_seq = 9;
  ASSERT_EQ(lcm_.publish("SWF_HAZARD", &next), 0);
  Deliver();
  ExpectCounts(monitor_.Hazard(), 2, 2, 0);
  EXPECT_EQ(monitor_.LastHazard().frame_seq, 9);
}

// GIVEN landmark maps and health messages whose length fields are negative, huge or disagree with
// the bytes (lcm-gen's decode() threw std::length_error on the first: swf-guidance aborted)
// WHEN they arrive THEN each is counted as malformed and ignored, and the good ones around them
// are still received in sequence.
TEST_F(GuidanceMonitorTest, HostileLengthFieldsAreCountedNotFatal) {
  swf_msgs::landmark_map_t map{};
  map.num_landmarks = 1;
  map.id = {7};
  map.position_world_m = {{1, 2, 3}};
  map.covariance_m2 = {{1, 0, 0, 1, 0, 1}};
  map.num_observations = {2};
  ASSERT_EQ(lcm_.publish("SWF_LANDMARKS", &map), 0);
  constexpr std::size_t kNumLandmarks = 8 + 24;  // fingerprint, utime, seq, frame_seq
  for (const std::int32_t bad : {-1, 2147483647, 2}) {
    const std::vector<std::uint8_t> bytes = WithInt32(Encode(map), kNumLandmarks, bad);
    ASSERT_EQ(lcm_.publish("SWF_LANDMARKS", bytes.data(), static_cast<unsigned>(bytes.size())), 0);
  }
  // The stage name's length: 0 (with its NUL it is >= 1).
  const std::vector<std::uint8_t> bytes =
      WithInt32(Encode(swf::testing::OneStageHealth()), 8 + 153 + 4 + 4, 0);
  ASSERT_EQ(lcm_.publish("SWF_HEALTH", bytes.data(), static_cast<unsigned>(bytes.size())), 0);
  map.seq = 1;
  map.position_world_m[0][2] = 4.0;
  ASSERT_EQ(lcm_.publish("SWF_LANDMARKS", &map), 0);
  Deliver();
  ExpectCounts(monitor_.Landmarks(), 2, 3, 0);
  EXPECT_EQ(monitor_.Health().malformed, 1);
  EXPECT_DOUBLE_EQ(monitor_.LastMap().position_world_m[0][2], 4.0);
}

// GIVEN sequence numbers a publisher never sends (negative, the largest int64) WHEN they arrive
// THEN the negative one is malformed and the largest counts a (saturating) gap without overflow.
TEST_F(GuidanceMonitorTest, ExtremeSequenceNumbersDoNotOverflow) {
  PublishNav(-5);
  PublishNav(0);
  PublishNav(std::numeric_limits<std::int64_t>::max());
  PublishNav(5);  // a step back: out of order
  Deliver();
  ExpectCounts(monitor_.Nav(), 3, 1, std::numeric_limits<std::int64_t>::max() - 1);
  EXPECT_EQ(monitor_.Nav().out_of_order, 1);
}

}  // namespace
}  // namespace swf::guidance
