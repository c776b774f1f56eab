// The hazard-map-vs-truth metric: one published hazard map (what guidance receives) against the
// simulator's terrain and hazard truth. The one definition every evaluation reports with: swf-sil's
// summary (`hazard`, `hazard_by_map`, `safe_site`), `swf-hazard eval|flight` and hazard_sim_test.
//
// Definitions (threshold h = MetricOptions::max_rock_height_m, footprint radius r, cell size c):
// - known cell: elevation not NaN.
// - resolved rock: a truth rock of height >= h whose centre lies in a cell with 3 sigma <= h
//   (the mapper's own criterion for declaring kRock; elsewhere a rock can only be kUncertain).
//   Detected: a CLASS_ROCK cell centre within the rock's radius + c of its centre. Flagged: a
//   CLASS_ROCK or CLASS_UNCERTAIN cell there (never a landing site). Counted also by height class
//   [1, 2), [2, 4), [4, inf) x h.
// - false alarm: a CLASS_ROCK cell among the rock-free known cells, i.e. those with no truth rock
//   node >= h / 2 within c / 2 + 0.3 m of the cell centre.
// - safe site: clearance = distance from the site to the nearest truth hazard node, searched (and
//   capped) at kSiteSearchM = 20 m; on hazard when clearance <= r. `<=` because a node at exactly r
//   lies on the footprint's edge, i.e. inside the closed disc the lander occupies: a safety claim
//   takes the conservative side. The cap bounds the search, and its value is the one swf-sil's
//   summary has always documented (`clearance_to_truth_hazard_m`, read by campaign tooling);
//   swf-hazard used footprint + 10 m, which cut its clearances at 11.5 m.
// - per-cell errors (MetricOptions::cell_errors): |elevation - truth cell mean| with the truth
//   mean over 4 x 4 terrain samples in the cell, the cell's sigma beside it, and |slope - truth
//   slope| at the terrain node nearest the cell centre where the map has a slope.
// Which truth (slope baseline, thresholds) is the caller's: sim::ComputeHazardTruth's options.
#pragma once

#include <cstdint>
#include <vector>

#include "swf/app/records.hpp"
#include "swf/sim/hazard.hpp"
#include "swf/sim/terrain.hpp"

namespace swf::hazard_eval {

// A published hazard map (app::HazardRecord, hazard_map_t) as plain arrays, not owned.
// Cell (i, j) is centred at (origin + (i + 0.5) cell_m, ...); arrays row-major j * n + i.
struct HazardMapView {
  std::int64_t frame_seq = -1;
  double origin_world_m[2] = {0.0, 0.0};
  double cell_m = 0.0;
  int cells_per_side = 0;
  const float* elevation_m = nullptr;  // NaN: unknown
  const float* sigma_m = nullptr;
  const float* slope_deg = nullptr;           // may be null (no slope errors then)
  const std::int8_t* hazard_class = nullptr;  // hazard_map_t.CLASS_* (app::HazardClassCode)
  bool site_valid = false;
  double site_world_m[2] = {0.0, 0.0};
  double site_score = 0.0;
};

// The view of a published record (its arrays stay the record's).
HazardMapView ViewOf(const app::HazardRecord& record);

inline constexpr int kRockHeightClasses = 3;
inline constexpr double kSiteSearchM = 20.0;

struct MetricOptions {
  double max_rock_height_m = 0.3;  // the mapper's threshold (HazardMapperOptions)
  double footprint_radius_m = 1.5;
  bool cell_errors = true;  // fill the per-cell error vectors (swf-hazard's calibration figures)
};

struct HazardMapMetrics {
  double cell_m = 0.0;
  int known_cells = 0;
  int rock_cells = 0;  // known cells classified rock
  int rocks_resolved = 0;
  int rocks_detected = 0;
  int rocks_flagged = 0;
  int rocks_resolved_by_height[kRockHeightClasses] = {};
  int rocks_detected_by_height[kRockHeightClasses] = {};
  double detection_probability = -1.0;  // detected / resolved; -1: none resolved
  int rock_free_cells = 0;
  int false_rock_cells = 0;
  double false_alarm_rate = 0.0;  // false_rock_cells / rock_free_cells; 0 without such cells
  bool site_valid = false;
  double site_world_m[2] = {0.0, 0.0};
  double site_score = 0.0;
  bool site_on_hazard = false;
  double site_clearance_m = -1.0;          // capped at kSiteSearchM; -1 without a site
  std::vector<double> elevation_errors_m;  // per known cell (cell_errors only)
  std::vector<double> elevation_sigmas_m;  // the same cells' sigma
  std::vector<double> slope_errors_deg;    // per known cell with a slope
};

// `terrain` gives the truth grid (node positions) and the true cell heights, `rocks` the truth
// rock list (terrain.Rocks(); a test passes its own), `truth` the per-node layers on the terrain's
// grid (sim::ComputeHazardTruth of the terrain, or hand-built).
HazardMapMetrics EvaluateHazardMap(const HazardMapView& map, const sim::Terrain& terrain,
                                   const std::vector<sim::Rock>& rocks, const sim::HazardMap& truth,
                                   const MetricOptions& options);

}  // namespace swf::hazard_eval
