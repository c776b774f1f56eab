// The truth of a published hazard map from the terrain (see map_metrics.hpp).
#include "swf/hazard_eval/map_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace swf::hazard_eval {

HazardMapView ViewOf(const app::HazardRecord& r) {
  return evaluation::ViewOfFields(r, r.cells_per_side,
                                  [](const auto& field) { return field.get(); });
}

namespace {

// The terrain's truth nodes near a point.
class TruthNodes {
 public:
  TruthNodes(const sim::Terrain& terrain, const sim::HazardMap& truth)
      : terrain_(terrain), n_(truth.size), cell_(terrain.CellM()) {}

  // The node nearest (x, y); false when it is off the terrain (*i, *j still set).
  bool Nearest(double x, double y, int* i, int* j) const {
    *i = static_cast<int>(std::lround((x - terrain_.NodeX(0)) / cell_));
    *j = static_cast<int>(std::lround((y - terrain_.NodeY(0)) / cell_));
    return *i >= 0 && *j >= 0 && *i < n_ && *j < n_;
  }

  // f(node index, distance) for each node within radius of (x, y).
  template <typename F>
  void ForEachWithin(double x, double y, double radius, F&& f) const {
    int ci = 0;
    int cj = 0;
    Nearest(x, y, &ci, &cj);
    const int rn = static_cast<int>(std::ceil(radius / cell_));
    // Squared distances, and a root only for the nodes inside: this runs for every cell of
    // every map on the SIL's output thread, beside the flight threads.
    const double radius2 = radius * radius;
    for (int j = std::max(0, cj - rn); j <= std::min(n_ - 1, cj + rn); ++j) {
      const double dy = terrain_.NodeY(j) - y;
      for (int i = std::max(0, ci - rn); i <= std::min(n_ - 1, ci + rn); ++i) {
        const double dx = terrain_.NodeX(i) - x;
        const double d2 = dx * dx + dy * dy;
        if (d2 <= radius2) f(static_cast<std::size_t>(j) * n_ + i, std::sqrt(d2));
      }
    }
  }

 private:
  const sim::Terrain& terrain_;
  int n_;
  double cell_;
};

// Per cell: the true mean height, the true slope at the nearest node, and rock_free.
void FillCells(const HazardMapView& m, const sim::Terrain& terrain, const sim::HazardMap& truth,
               const TruthNodes& nodes, double max_rock_height_m, swf_msgs::hazard_truth_t* t) {
  const int n = m.cells_per_side;
  const double cell = m.cell_m;
  const std::size_t cells = static_cast<std::size_t>(n) * n;
  t->elevation_m.assign(cells, NAN);
  t->slope_deg.assign(cells, NAN);
  t->rock_free.assign(cells, 0);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      const double x = m.origin_world_m[0] + (i + 0.5) * cell;
      const double y = m.origin_world_m[1] + (j + 0.5) * cell;
      double mean = 0.0;
      for (int b = 0; b < 4; ++b) {
        for (int a = 0; a < 4; ++a) {
          mean += terrain.HeightAt(x + (a - 1.5) * cell / 4.0, y + (b - 1.5) * cell / 4.0);
        }
      }
      t->elevation_m[c] = mean / 16.0;
      int ti = 0;
      int tj = 0;
      if (nodes.Nearest(x, y, &ti, &tj))
        t->slope_deg[c] = truth.slope_deg[static_cast<std::size_t>(tj) * truth.size + ti];
      float rock = 0.0f;
      nodes.ForEachWithin(x, y, 0.5 * cell + 0.3, [&](std::size_t k, double) {
        rock = std::max(rock, truth.rock_height_m[k]);
      });
      t->rock_free[c] = rock < 0.5 * max_rock_height_m ? 1 : 0;
    }
  }
}

// The rocks at least max_rock_height_m tall whose centre lies on the map.
void FillRocks(const HazardMapView& m, const std::vector<sim::Rock>& rocks,
               double max_rock_height_m, swf_msgs::hazard_truth_t* t) {
  const int n = m.cells_per_side;
  for (const sim::Rock& rock : rocks) {
    if (rock.height_m < max_rock_height_m) continue;
    const double fx = (rock.center_m.x() - m.origin_world_m[0]) / m.cell_m;
    const double fy = (rock.center_m.y() - m.origin_world_m[1]) / m.cell_m;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < n && fy < n)) continue;
    t->rock_center_world_m.push_back({rock.center_m.x(), rock.center_m.y()});
    t->rock_diameter_m.push_back(rock.diameter_m);
    t->rock_height_m.push_back(rock.height_m);
  }
  t->num_rocks = static_cast<std::int32_t>(t->rock_height_m.size());
}

}  // namespace

swf_msgs::hazard_truth_t HazardTruthOf(const HazardMapView& m, const sim::Terrain& terrain,
                                       const std::vector<sim::Rock>& rocks,
                                       const sim::HazardMap& truth, const MetricOptions& o) {
  swf_msgs::hazard_truth_t t{};
  t.frame_seq = m.frame_seq;
  t.origin_world_m[0] = m.origin_world_m[0];
  t.origin_world_m[1] = m.origin_world_m[1];
  t.cell_size_m = m.cell_m;
  const int n = m.cells_per_side > 0 && m.cell_m > 0.0 ? m.cells_per_side : 0;
  t.rows = n;
  t.cols = n;
  t.num_cells = n * n;
  t.max_rock_height_m = o.max_rock_height_m;
  t.footprint_radius_m = o.footprint_radius_m;
  t.site_search_m = kSiteSearchM;
  t.site_clearance_m = -1.0;
  if (n == 0) return t;
  const TruthNodes nodes(terrain, truth);
  FillCells(m, terrain, truth, nodes, o.max_rock_height_m, &t);
  FillRocks(m, rocks, o.max_rock_height_m, &t);
  t.site_valid = m.site_valid;
  if (m.site_valid) {
    t.site_world_m[0] = m.site_world_m[0];
    t.site_world_m[1] = m.site_world_m[1];
    double nearest = kSiteSearchM;
    nodes.ForEachWithin(t.site_world_m[0], t.site_world_m[1], kSiteSearchM,
                        [&](std::size_t k, double d) {
                          if (truth.hazard[k] != 0) nearest = std::min(nearest, d);
                        });
    t.site_clearance_m = nearest;
  }
  return t;
}

HazardMapMetrics EvaluateHazardMap(const HazardMapView& map, const sim::Terrain& terrain,
                                   const std::vector<sim::Rock>& rocks, const sim::HazardMap& truth,
                                   const MetricOptions& options) {
  return evaluation::JudgeHazardMap(map, HazardTruthOf(map, terrain, rocks, truth, options),
                                    options.cell_errors);
}

}  // namespace swf::hazard_eval
