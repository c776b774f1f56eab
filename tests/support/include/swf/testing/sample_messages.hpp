// Small, valid messages that more than one module's tests start from (and then alter).
#pragma once

#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/health_t.hpp"
#include "swf_msgs/landmark_map_t.hpp"

namespace swf::testing {

// Two landmarks, the second at (4, 5, 6).
inline swf_msgs::landmark_map_t TwoLandmarks() {
  swf_msgs::landmark_map_t map{};
  map.num_landmarks = 2;
  map.id = {5, 6};
  map.position_world_m = {{1, 2, 3}, {4, 5, 6}};
  map.covariance_m2 = {{1, 0, 0, 1, 0, 1}, {2, 0, 0, 2, 0, 2}};
  map.num_observations = {3, 4};
  return map;
}

// A 1 x 2 hazard map: a safe cell and a rock.
inline swf_msgs::hazard_map_t SafeAndRockCells() {
  swf_msgs::hazard_map_t hazard{};
  hazard.rows = 1;
  hazard.cols = 2;
  hazard.num_cells = 2;
  hazard.elevation_m = {0.5f, 0.25f};
  hazard.sigma_m = {0.1f, 0.1f};
  hazard.relief_sigma_m = {0.05f, 0.05f};
  hazard.slope_deg = {1.0f, 2.0f};
  hazard.roughness_m = {0.0f, 0.3f};
  hazard.hazard_class = {swf_msgs::hazard_map_t::CLASS_SAFE, swf_msgs::hazard_map_t::CLASS_ROCK};
  return hazard;
}

// Health with one timed stage, "track".
inline swf_msgs::health_t OneStageHealth() {
  swf_msgs::health_t health{};
  health.num_stages = 1;
  health.stage_name = {"track"};
  health.stage_p50_ms = {1.5f};
  health.stage_p99_ms = {2.5f};
  health.stage_max_ms = {3.5f};
  return health;
}

}  // namespace swf::testing
