#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/health_t.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace {

template <typename Msg>
Msg RoundTrip(const Msg& in, std::vector<std::uint8_t>* buffer) {
  buffer->assign(static_cast<std::size_t>(in.getEncodedSize()), 0);
  EXPECT_EQ(in.encode(buffer->data(), 0, static_cast<int>(buffer->size())),
            static_cast<int>(buffer->size()));
  Msg out;
  EXPECT_EQ(out.decode(buffer->data(), 0, static_cast<int>(buffer->size())),
            static_cast<int>(buffer->size()));
  return out;
}

TEST(Messages, StereoFrameRoundTripsAndRejectsTruncation) {
  swf_msgs::stereo_frame_t frame{};
  frame.utime = 123456789;
  frame.seq = 42;
  frame.width = 4;
  frame.height = 2;
  frame.num_bytes = 8;
  frame.left.assign(8, 7);
  frame.right.assign(8, 9);
  frame.has_motion = true;
  frame.motion_translation_m[2] = -1.0;
  frame.motion_rotation_rad[0] = 1e-3;
  std::vector<std::uint8_t> buffer;
  const swf_msgs::stereo_frame_t out = RoundTrip(frame, &buffer);
  EXPECT_EQ(out.seq, 42);
  EXPECT_TRUE(out.has_motion);
  EXPECT_EQ(out.motion_translation_m[2], -1.0);
  EXPECT_EQ(out.motion_rotation_rad[0], 1e-3);
  EXPECT_EQ(out.right[7], 9);
  // A truncated record must fail to decode (negative), never read past the end.
  swf_msgs::stereo_frame_t broken;
  EXPECT_LT(broken.decode(buffer.data(), 0, static_cast<int>(buffer.size()) - 3), 0);
  // A wrong fingerprint (another type's bytes) is refused too.
  swf_msgs::nav_state_t nav;
  EXPECT_LT(nav.decode(buffer.data(), 0, static_cast<int>(buffer.size())), 0);
}

TEST(Messages, NavStateLandmarksHazardHealthRoundTrip) {
  std::vector<std::uint8_t> buffer;
  swf_msgs::nav_state_t nav{};
  nav.position_world_m[2] = 100.0;
  nav.covariance[35] = 1e-4;
  nav.mode = swf_msgs::nav_state_t::MODE_SWF;
  EXPECT_EQ(RoundTrip(nav, &buffer).covariance[35], 1e-4);

  swf_msgs::landmark_map_t map{};
  map.num_landmarks = 2;
  map.id = {5, 6};
  map.position_world_m = {{1, 2, 3}, {4, 5, 6}};
  map.covariance_m2 = {{1, 0, 0, 1, 0, 1}, {2, 0, 0, 2, 0, 2}};
  map.num_observations = {3, 4};
  map.frame_seq = 17;
  EXPECT_EQ(RoundTrip(map, &buffer).position_world_m[1][2], 6.0);
  EXPECT_EQ(RoundTrip(map, &buffer).frame_seq, 17);

  swf_msgs::hazard_map_t hazard{};
  hazard.rows = 1;
  hazard.cols = 2;
  hazard.num_cells = 2;
  hazard.elevation_m = {0.5f, 0.25f};
  hazard.sigma_m = {0.1f, 0.1f};
  hazard.slope_deg = {1.0f, 2.0f};
  hazard.roughness_m = {0.0f, 0.3f};
  hazard.hazard_class = {swf_msgs::hazard_map_t::CLASS_SAFE, swf_msgs::hazard_map_t::CLASS_ROCK};
  EXPECT_EQ(RoundTrip(hazard, &buffer).hazard_class[1], swf_msgs::hazard_map_t::CLASS_ROCK);
  hazard.hazard_class[1] = swf_msgs::hazard_map_t::CLASS_UNCERTAIN;  // its own class, not safe
  EXPECT_EQ(RoundTrip(hazard, &buffer).hazard_class[1], swf_msgs::hazard_map_t::CLASS_UNCERTAIN);
  EXPECT_NE(swf_msgs::hazard_map_t::CLASS_UNCERTAIN, swf_msgs::hazard_map_t::CLASS_SAFE);

  swf_msgs::health_t health{};
  health.num_stages = 1;
  health.stage_name = {"track"};
  health.stage_p50_ms = {1.5f};
  health.stage_p99_ms = {2.5f};
  health.stage_max_ms = {3.5f};
  EXPECT_EQ(RoundTrip(health, &buffer).stage_name[0], "track");
}

}  // namespace
