// The hazard-map-vs-truth metric (see map_metrics.hpp for the definitions).
#include "swf/hazard_eval/map_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "swf/app/hazard_stage.hpp"

namespace swf::hazard_eval {

HazardMapView ViewOf(const app::HazardRecord& r) {
  HazardMapView v;
  v.frame_seq = r.frame_seq;
  v.origin_world_m[0] = r.origin_world_m[0];
  v.origin_world_m[1] = r.origin_world_m[1];
  v.cell_m = r.cell_size_m;
  v.cells_per_side = r.cells_per_side;
  v.elevation_m = r.elevation_m.get();
  v.sigma_m = r.sigma_m.get();
  v.slope_deg = r.slope_deg.get();
  v.hazard_class = r.hazard_class.get();
  v.site_valid = r.safe_site_valid;
  v.site_world_m[0] = r.safe_site_world_m[0];
  v.site_world_m[1] = r.safe_site_world_m[1];
  v.site_score = r.safe_site_score;
  return v;
}

namespace {

// The height class of a rock of height h against the threshold (kRockHeightClasses classes).
int RockHeightClass(double h, double threshold) {
  if (h < 2.0 * threshold) return 0;
  return h < 4.0 * threshold ? 1 : 2;
}

}  // namespace

HazardMapMetrics EvaluateHazardMap(const HazardMapView& m, const sim::Terrain& terrain,
                                   const std::vector<sim::Rock>& rocks, const sim::HazardMap& truth,
                                   const MetricOptions& o) {
  HazardMapMetrics r;
  const int n = m.cells_per_side;
  const double cell = m.cell_m;
  r.cell_m = cell;
  if (n <= 0 || !(cell > 0.0)) return r;
  const std::int8_t rock_code = app::HazardClassCode(hazard::HazardClass::kRock);
  const std::int8_t uncertain_code = app::HazardClassCode(hazard::HazardClass::kUncertain);
  const int tn = truth.size;
  const double tcell = terrain.CellM();
  const auto centre_x = [&](int i) { return m.origin_world_m[0] + (i + 0.5) * cell; };
  const auto centre_y = [&](int j) { return m.origin_world_m[1] + (j + 0.5) * cell; };
  // The truth node nearest (x, y); false when it is off the terrain (*i, *j still set).
  const auto node_of = [&](double x, double y, int* i, int* j) {
    *i = static_cast<int>(std::lround((x - terrain.NodeX(0)) / tcell));
    *j = static_cast<int>(std::lround((y - terrain.NodeY(0)) / tcell));
    return *i >= 0 && *j >= 0 && *i < tn && *j < tn;
  };
  // Truth nodes within radius of (x, y); f(node index, distance) for each.
  const auto for_nodes_near = [&](double x, double y, double radius, auto&& f) {
    int ci = 0;
    int cj = 0;
    node_of(x, y, &ci, &cj);
    const int rn = static_cast<int>(std::ceil(radius / tcell));
    for (int j = std::max(0, cj - rn); j <= std::min(tn - 1, cj + rn); ++j) {
      for (int i = std::max(0, ci - rn); i <= std::min(tn - 1, ci + rn); ++i) {
        const double d = std::hypot(terrain.NodeX(i) - x, terrain.NodeY(j) - y);
        if (d <= radius) f(static_cast<std::size_t>(j) * tn + i, d);
      }
    }
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      if (std::isnan(m.elevation_m[c])) continue;
      ++r.known_cells;
      const double x = centre_x(i);
      const double y = centre_y(j);
      if (o.cell_errors) {
        double mean = 0.0;
        for (int b = 0; b < 4; ++b) {
          for (int a = 0; a < 4; ++a) {
            mean += terrain.HeightAt(x + (a - 1.5) * cell / 4.0, y + (b - 1.5) * cell / 4.0);
          }
        }
        mean /= 16.0;
        r.elevation_errors_m.push_back(std::fabs(m.elevation_m[c] - mean));
        r.elevation_sigmas_m.push_back(m.sigma_m[c]);
        int ti = 0;
        int tj = 0;
        if (m.slope_deg != nullptr && !std::isnan(m.slope_deg[c]) && node_of(x, y, &ti, &tj)) {
          r.slope_errors_deg.push_back(
              std::fabs(m.slope_deg[c] - truth.slope_deg[static_cast<std::size_t>(tj) * tn + ti]));
        }
      }
      const bool is_rock = m.hazard_class[c] == rock_code;
      r.rock_cells += is_rock;
      float rock = 0.0f;
      for_nodes_near(x, y, 0.5 * cell + 0.3,
                     [&](std::size_t k, double) { rock = std::max(rock, truth.rock_height_m[k]); });
      if (rock >= 0.5 * o.max_rock_height_m) continue;
      ++r.rock_free_cells;
      r.false_rock_cells += is_rock;
    }
  }
  if (r.rock_free_cells > 0) {
    r.false_alarm_rate = static_cast<double>(r.false_rock_cells) / r.rock_free_cells;
  }
  for (const sim::Rock& rock : rocks) {
    if (rock.height_m < o.max_rock_height_m) continue;
    const double fx = (rock.center_m.x() - m.origin_world_m[0]) / cell;
    const double fy = (rock.center_m.y() - m.origin_world_m[1]) / cell;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < n && fy < n)) continue;
    const int ci = static_cast<int>(fx);
    const int cj = static_cast<int>(fy);
    const float sigma = m.sigma_m[static_cast<std::size_t>(cj) * n + ci];
    if (!(3.0 * sigma <= o.max_rock_height_m)) continue;
    const int height_class = RockHeightClass(rock.height_m, o.max_rock_height_m);
    ++r.rocks_resolved;
    ++r.rocks_resolved_by_height[height_class];
    const double radius = 0.5 * rock.diameter_m + cell;
    const int rc = static_cast<int>(std::ceil(radius / cell));
    bool detected = false;
    bool flagged = false;
    for (int j = std::max(0, cj - rc); j <= std::min(n - 1, cj + rc); ++j) {
      for (int i = std::max(0, ci - rc); i <= std::min(n - 1, ci + rc); ++i) {
        if (std::hypot(centre_x(i) - rock.center_m.x(), centre_y(j) - rock.center_m.y()) > radius)
          continue;
        const std::int8_t k = m.hazard_class[static_cast<std::size_t>(j) * n + i];
        detected = detected || k == rock_code;
        flagged = flagged || k == rock_code || k == uncertain_code;
      }
    }
    r.rocks_detected += detected;
    r.rocks_detected_by_height[height_class] += detected;
    r.rocks_flagged += flagged;
  }
  if (r.rocks_resolved > 0) {
    r.detection_probability = static_cast<double>(r.rocks_detected) / r.rocks_resolved;
  }
  r.site_valid = m.site_valid;
  if (m.site_valid) {
    r.site_world_m[0] = m.site_world_m[0];
    r.site_world_m[1] = m.site_world_m[1];
    r.site_score = m.site_score;
    double nearest = kSiteSearchM;
    for_nodes_near(r.site_world_m[0], r.site_world_m[1], kSiteSearchM,
                   [&](std::size_t k, double d) {
                     if (truth.hazard[k] != 0) nearest = std::min(nearest, d);
                   });
    r.site_clearance_m = nearest;
    r.site_on_hazard = nearest <= o.footprint_radius_m;
  }
  return r;
}

}  // namespace swf::hazard_eval
