#include "swf/sim/hazard.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace swf::sim {

core::Status ComputeHazardTruth(const Terrain& terrain, const HazardOptions& options,
                                HazardMap* map) {
  if (terrain.Size() < 2 || !(options.max_slope_deg > 0.0) || !(options.max_rock_height_m > 0.0) ||
      !(options.slope_baseline_m > 0.0) || map == nullptr) {
    return core::Status::kInvalidArgument;
  }
  const std::int32_t n = terrain.Size();
  const double cell = terrain.CellM();
  const auto half = std::max<std::int32_t>(
      1, static_cast<std::int32_t>(std::lround(0.5 * options.slope_baseline_m / cell)));
  const std::vector<float>& base = terrain.BaseHeights();
  const std::vector<float>& full = terrain.Heights();
  map->size = n;
  map->cell_m = cell;
  map->slope_deg.assign(static_cast<size_t>(n) * n, 0.0f);
  map->rock_height_m.assign(static_cast<size_t>(n) * n, 0.0f);
  map->hazard.assign(static_cast<size_t>(n) * n, 0);
  for (std::int32_t j = 0; j < n; ++j) {
    const std::int32_t jd = std::max(0, j - half);
    const std::int32_t ju = std::min(n - 1, j + half);
    for (std::int32_t i = 0; i < n; ++i) {
      const std::int32_t il = std::max(0, i - half);
      const std::int32_t ir = std::min(n - 1, i + half);
      const size_t k = static_cast<size_t>(j) * n + i;
      const double gx = (static_cast<double>(base[static_cast<size_t>(j) * n + ir]) -
                         base[static_cast<size_t>(j) * n + il]) /
                        ((ir - il) * cell);
      const double gy = (static_cast<double>(base[static_cast<size_t>(ju) * n + i]) -
                         base[static_cast<size_t>(jd) * n + i]) /
                        ((ju - jd) * cell);
      const double slope_deg = std::atan(std::hypot(gx, gy)) * 180.0 / std::numbers::pi;
      const double rock = static_cast<double>(full[k]) - base[k];
      map->slope_deg[k] = static_cast<float>(slope_deg);
      map->rock_height_m[k] = static_cast<float>(rock);
      std::uint8_t bits = 0;
      if (slope_deg > options.max_slope_deg) bits |= kHazardSlope;
      if (rock > options.max_rock_height_m) bits |= kHazardRock;
      map->hazard[k] = bits;
    }
  }
  return core::Status::kOk;
}

}  // namespace swf::sim
