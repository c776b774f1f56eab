// Hazard ground truth from the terrain's exact layers, per height-field node:
//   slope_deg:      atan |grad h_base|, central differences over +-slope_baseline_m / 2 of the
//                   rock-free surface (the lander-footprint scale of the slope hazard);
//   rock_height_m:  full height minus rock-free height (exactly the rasterized rocks);
//   hazard:         bit 0 slope > max_slope_deg, bit 1 rock_height > max_rock_height_m.
#pragma once

#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/sim/terrain.hpp"

namespace swf::sim {

struct HazardOptions {
  double max_slope_deg = 10.0;
  double max_rock_height_m = 0.25;
  double slope_baseline_m = 1.0;
};

enum HazardBits : std::uint8_t { kHazardSlope = 1, kHazardRock = 2 };

struct HazardMap {
  std::int32_t size = 0;
  double cell_m = 0.0;
  std::vector<float> slope_deg;
  std::vector<float> rock_height_m;
  std::vector<std::uint8_t> hazard;
};

// kInvalidArgument for an unconfigured terrain or non-positive thresholds.
core::Status ComputeHazardTruth(const Terrain& terrain, const HazardOptions& options,
                                HazardMap* map);

}  // namespace swf::sim
