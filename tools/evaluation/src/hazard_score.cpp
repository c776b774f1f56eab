// The hazard-map-vs-truth metric (see hazard_score.hpp for the definitions).
#include "swf/evaluation/hazard_score.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "swf/hazard/hazard_mapper.hpp"

namespace swf::evaluation {

HazardMapView ViewOf(const swf_msgs::hazard_map_t& m) {
  const bool square = m.rows == m.cols && std::int64_t{m.rows} * m.cols == m.num_cells;
  return ViewOfFields(m, square ? m.rows : 0, [](const auto& field) { return field.data(); });
}

bool SameGrid(const HazardMapView& m, const swf_msgs::hazard_truth_t& t) {
  return t.rows == m.cells_per_side && t.cols == m.cells_per_side &&
         std::int64_t{t.rows} * t.cols == t.num_cells && t.cell_size_m == m.cell_m &&
         t.origin_world_m[0] == m.origin_world_m[0] && t.origin_world_m[1] == m.origin_world_m[1];
}

namespace {

// The height class of a rock of height h against the threshold (kRockHeightClasses classes).
int RockHeightClass(double h, double threshold) {
  if (h < 2.0 * threshold) return 0;
  return h < 4.0 * threshold ? 1 : 2;
}

// Known cells, per-cell errors and false alarms.
void JudgeCells(const HazardMapView& m, const swf_msgs::hazard_truth_t& t, bool cell_errors,
                HazardMapMetrics* r) {
  const int n = m.cells_per_side;
  for (std::size_t c = 0; c < static_cast<std::size_t>(n) * n; ++c) {
    if (std::isnan(m.elevation_m[c])) continue;
    ++r->known_cells;
    if (cell_errors) {
      r->elevation_errors_m.push_back(std::fabs(m.elevation_m[c] - t.elevation_m[c]));
      r->elevation_sigmas_m.push_back(m.sigma_m[c]);
      if (m.slope_deg != nullptr && !std::isnan(m.slope_deg[c]) && !std::isnan(t.slope_deg[c]))
        r->slope_errors_deg.push_back(std::fabs(m.slope_deg[c] - t.slope_deg[c]));
    }
    const bool is_rock = m.hazard_class[c] == swf_msgs::hazard_map_t::CLASS_ROCK;
    r->rock_cells += is_rock;
    if (t.rock_free[c] == 0) continue;
    ++r->rock_free_cells;
    r->false_rock_cells += is_rock;
  }
  if (r->rock_free_cells > 0) {
    r->false_alarm_rate = static_cast<double>(r->false_rock_cells) / r->rock_free_cells;
  }
}

// Resolved, detected and flagged rocks.
void JudgeRocks(const HazardMapView& m, const swf_msgs::hazard_truth_t& t, HazardMapMetrics* r) {
  const int n = m.cells_per_side;
  const double cell = m.cell_m;
  const double h = t.max_rock_height_m;
  hazard::RockCriterionOptions criterion_options;
  criterion_options.max_height_m = h;
  const hazard::RockCriterion criterion(criterion_options, cell);
  for (std::int32_t k = 0; k < t.num_rocks; ++k) {
    const double rx = t.rock_center_world_m[k][0];
    const double ry = t.rock_center_world_m[k][1];
    if (t.rock_height_m[k] < h) continue;
    const double fx = (rx - m.origin_world_m[0]) / cell;
    const double fy = (ry - m.origin_world_m[1]) / cell;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < n && fy < n)) continue;
    const int ci = static_cast<int>(fx);
    const int cj = static_cast<int>(fy);
    const float sigma = m.relief_sigma_m[static_cast<std::size_t>(cj) * n + ci];
    if (!criterion.Resolvable(t.rock_height_m[k], t.rock_diameter_m[k], sigma)) continue;
    const int height_class = RockHeightClass(t.rock_height_m[k], h);
    ++r->rocks_resolved;
    ++r->rocks_resolved_by_height[height_class];
    const double radius = 0.5 * t.rock_diameter_m[k] + cell;
    const int rc = static_cast<int>(std::ceil(radius / cell));
    bool detected = false;
    bool flagged = false;
    for (int j = std::max(0, cj - rc); j <= std::min(n - 1, cj + rc); ++j) {
      for (int i = std::max(0, ci - rc); i <= std::min(n - 1, ci + rc); ++i) {
        const double x = m.origin_world_m[0] + (i + 0.5) * cell;
        const double y = m.origin_world_m[1] + (j + 0.5) * cell;
        if (std::hypot(x - rx, y - ry) > radius) continue;
        const std::int8_t c = m.hazard_class[static_cast<std::size_t>(j) * n + i];
        detected = detected || c == swf_msgs::hazard_map_t::CLASS_ROCK;
        flagged = flagged || c == swf_msgs::hazard_map_t::CLASS_ROCK ||
                  c == swf_msgs::hazard_map_t::CLASS_UNCERTAIN;
      }
    }
    r->rocks_detected += detected;
    r->rocks_detected_by_height[height_class] += detected;
    r->rocks_flagged += flagged;
  }
  if (r->rocks_resolved > 0) {
    r->detection_probability = static_cast<double>(r->rocks_detected) / r->rocks_resolved;
  }
}

}  // namespace

HazardMapMetrics JudgeHazardMap(const HazardMapView& m, const swf_msgs::hazard_truth_t& t,
                                bool cell_errors) {
  HazardMapMetrics r;
  r.cell_m = m.cell_m;
  if (m.cells_per_side <= 0 || !(m.cell_m > 0.0) || !SameGrid(m, t)) return r;
  JudgeCells(m, t, cell_errors, &r);
  JudgeRocks(m, t, &r);
  r.site_valid = m.site_valid;
  if (m.site_valid) {
    r.site_world_m[0] = m.site_world_m[0];
    r.site_world_m[1] = m.site_world_m[1];
    r.site_score = m.site_score;
    r.site_clearance_m = t.site_clearance_m;
    r.site_on_hazard = t.site_clearance_m <= t.footprint_radius_m;
  }
  return r;
}

}  // namespace swf::evaluation
