// Orbital pre-selection of the landing target: what a mission does before descent with its orbital
// data (digital elevation model and images), so that the onboard hazard mapper only has to deal
// with the hazards orbit cannot see (rocks below the image resolution, metre-scale relief).
//
// Procedure (deterministic, from the terrain's truth degraded to orbital resolution):
//   1. DEM: heights averaged over posts of post_m (HiRISE stereo DTMs: ~1 m posts), in a square
//      around the nominal target that holds the search disc plus the clearance cap;
//   2. orbital hazards: posts whose slope (3 x 3-post plane fit, Horn's gradient: a 2 posts
//      baseline, the lander-footprint scale at 1 m posts) exceeds max_slope_deg, and posts
//      touched by a rock of diameter >= min_rock_diameter_m (the smallest rock orbital images
//      resolve: HiRISE at 0.25-0.3 m per pixel counts rocks from ~1.5 m);
//   3. clearance of each post: distance between post centres to the nearest hazard post, capped
//      at clearance_cap_m (the ground the final fine hazard map covers; farther hazards do not
//      reach it);
//   4. target: among the posts whose centre lies within search_radius_m of the nominal target
//      (the reachable area), the largest capped clearance, ties broken by the distance to the
//      nominal target (then by post index): the nearest point whose surroundings orbit shows free
//      of hazards, or the clearest one when none is fully clear.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "swf/core/status.hpp"
#include "swf/sim/terrain.hpp"

namespace swf::sim {

struct OrbitalSelectionOptions {
  Eigen::Vector2d nominal_m{0.0, 0.0};
  double search_radius_m = 40.0;
  double post_m = 1.0;
  double max_slope_deg = 10.0;
  double min_rock_diameter_m = 1.5;
  double clearance_cap_m = 10.0;
};

struct OrbitalTarget {
  Eigen::Vector2d target_m{0.0, 0.0};
  double clearance_m = 0.0;     // capped orbital clearance of the chosen post
  double distance_m = 0.0;      // from the nominal target
  std::int32_t candidates = 0;  // posts in the search disc
  std::int32_t hazard_posts = 0;
};

// kInvalidArgument for an unconfigured terrain, non-positive lengths or thresholds, or a search
// square (search radius + clearance cap + one post) that leaves the terrain.
core::Status SelectOrbitalTarget(const Terrain& terrain, const OrbitalSelectionOptions& options,
                                 OrbitalTarget* target);

}  // namespace swf::sim
