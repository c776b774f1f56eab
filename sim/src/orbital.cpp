#include "swf/sim/orbital.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace swf::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

core::Status SelectOrbitalTarget(const Terrain& terrain, const OrbitalSelectionOptions& o,
                                 OrbitalTarget* target) {
  if (target == nullptr || terrain.Size() <= 0 || !(o.search_radius_m >= 0.0) ||
      !(o.post_m > 0.0) || !(o.max_slope_deg > 0.0) || !(o.min_rock_diameter_m > 0.0) ||
      !(o.clearance_cap_m > 0.0) || !o.nominal_m.allFinite()) {
    return core::Status::kInvalidArgument;
  }
  // Posts p = 0 .. n-1 per side, centred on the nominal target; one ring beyond the search disc
  // and the clearance cap so that every post a candidate's clearance looks at has a slope.
  const int half =
      static_cast<int>(std::ceil((o.search_radius_m + o.clearance_cap_m) / o.post_m)) + 1;
  const int n = 2 * half + 1;
  const double reach = (half + 0.5) * o.post_m;
  if (std::abs(o.nominal_m.x()) + reach > terrain.HalfExtentM() ||
      std::abs(o.nominal_m.y()) + reach > terrain.HalfExtentM()) {
    return core::Status::kInvalidArgument;
  }
  const auto centre = [&](int p, int q) {
    return Eigen::Vector2d(o.nominal_m.x() + (p - half) * o.post_m,
                           o.nominal_m.y() + (q - half) * o.post_m);
  };
  // 1. DEM: the mean of k x k height samples per post (terrain node spacing).
  const int k = std::max(1, static_cast<int>(std::lround(o.post_m / terrain.CellM())));
  std::vector<double> dem(static_cast<std::size_t>(n) * n);
  for (int q = 0; q < n; ++q) {
    for (int p = 0; p < n; ++p) {
      const Eigen::Vector2d c = centre(p, q);
      double sum = 0.0;
      for (int b = 0; b < k; ++b) {
        for (int a = 0; a < k; ++a) {
          sum += terrain.HeightAt(c.x() + ((a + 0.5) / k - 0.5) * o.post_m,
                                  c.y() + ((b + 0.5) / k - 0.5) * o.post_m);
        }
      }
      dem[static_cast<std::size_t>(q) * n + p] = sum / (k * k);
    }
  }
  // 2. Orbital hazards: slope over the 3 x 3 posts plane, resolved rocks.
  std::vector<std::uint8_t> hazard(dem.size(), 0);
  const double max_gradient = std::tan(o.max_slope_deg * kPi / 180.0);
  const auto z = [&](int p, int q) { return dem[static_cast<std::size_t>(q) * n + p]; };
  for (int q = 1; q + 1 < n; ++q) {
    for (int p = 1; p + 1 < n; ++p) {
      const double gx = ((z(p + 1, q - 1) + 2.0 * z(p + 1, q) + z(p + 1, q + 1)) -
                         (z(p - 1, q - 1) + 2.0 * z(p - 1, q) + z(p - 1, q + 1))) /
                        (8.0 * o.post_m);
      const double gy = ((z(p - 1, q + 1) + 2.0 * z(p, q + 1) + z(p + 1, q + 1)) -
                         (z(p - 1, q - 1) + 2.0 * z(p, q - 1) + z(p + 1, q - 1))) /
                        (8.0 * o.post_m);
      if (std::hypot(gx, gy) > max_gradient) hazard[static_cast<std::size_t>(q) * n + p] = 1;
    }
  }
  for (const Rock& rock : terrain.Rocks()) {
    if (rock.diameter_m < o.min_rock_diameter_m) continue;
    const double r = 0.5 * rock.diameter_m;
    // Posts whose square overlaps the rock's disc.
    const Eigen::Vector2d g = (rock.center_m - o.nominal_m) / o.post_m;
    const int reach_posts = static_cast<int>(std::ceil(r / o.post_m)) + 1;
    const int p0 = static_cast<int>(std::lround(g.x())) + half;
    const int q0 = static_cast<int>(std::lround(g.y())) + half;
    for (int q = std::max(0, q0 - reach_posts); q <= std::min(n - 1, q0 + reach_posts); ++q) {
      for (int p = std::max(0, p0 - reach_posts); p <= std::min(n - 1, p0 + reach_posts); ++p) {
        const Eigen::Vector2d c = centre(p, q);
        const double dx = std::max(0.0, std::abs(rock.center_m.x() - c.x()) - 0.5 * o.post_m);
        const double dy = std::max(0.0, std::abs(rock.center_m.y() - c.y()) - 0.5 * o.post_m);
        if (std::hypot(dx, dy) <= r) hazard[static_cast<std::size_t>(q) * n + p] = 1;
      }
    }
  }
  OrbitalTarget best;
  best.clearance_m = -1.0;
  for (std::uint8_t h : hazard) best.hazard_posts += h;
  // 3./4. Capped clearance of every candidate; the largest, then the nearest to the nominal.
  const int window = static_cast<int>(std::ceil(o.clearance_cap_m / o.post_m));
  for (int q = 0; q < n; ++q) {
    for (int p = 0; p < n; ++p) {
      const double distance = std::hypot(p - half, q - half) * o.post_m;
      if (distance > o.search_radius_m) continue;
      ++best.candidates;
      double clearance = o.clearance_cap_m;
      for (int b = std::max(0, q - window); b <= std::min(n - 1, q + window); ++b) {
        for (int a = std::max(0, p - window); a <= std::min(n - 1, p + window); ++a) {
          if (hazard[static_cast<std::size_t>(b) * n + a] == 0) continue;
          clearance = std::min(clearance, std::hypot(a - p, b - q) * o.post_m);
        }
      }
      if (clearance > best.clearance_m ||
          (clearance == best.clearance_m && distance < best.distance_m)) {
        best.clearance_m = clearance;
        best.distance_m = distance;
        best.target_m = centre(p, q);
      }
    }
  }
  *target = best;
  return core::Status::kOk;
}

}  // namespace swf::sim
