// The hazard-map-vs-truth metric: one published hazard map (what guidance receives) against the
// truth of that map (hazard_truth_t: the simulator's terrain and rocks on the map's own grid,
// sent on SIM_TRUTH_HAZARD). The one definition every evaluation reports with: RunJudge (swf-sil's
// summary `hazard`, `hazard_by_map`, `safe_site`; swf-judge on logs), `swf-hazard eval|flight` and
// hazard_sim_test. How the truth is drawn from a terrain: swf/hazard_eval/map_metrics.hpp.
//
// Definitions (threshold h = truth.max_rock_height_m, footprint radius r, cell size c):
// - known cell: elevation not NaN.
// - resolved rock: a truth rock of height >= h that the rock criterion (swf/hazard/
//   hazard_mapper.hpp, RockCriterion: the mapper's own decision rule, window radius at its
//   default) calls resolvable at the relief sigma of the cell holding its centre (the published
//   relief_sigma_m: the number the mapper decided that cell with, the pose error common to the
//   plane window left out): the map must detect it with probability >= 0.95. A cell without a
//   relief sigma (no plane fitted) resolves nothing. Detected: a CLASS_ROCK cell centre within the
//   rock's radius + c of its centre. Flagged: a CLASS_ROCK or CLASS_UNCERTAIN cell there (never a
//   landing site). Counted also by height class [1, 2), [2, 4), [4, inf) x h.
// - false alarm: a CLASS_ROCK cell among the rock-free known cells (truth.rock_free).
// - safe site: on hazard when the truth's clearance of the map's site is <= r. `<=` because a
//   hazard at exactly r lies on the footprint's edge, inside the closed disc the lander occupies:
//   a safety claim takes the conservative side.
// - per-cell errors (cell_errors): |elevation - truth cell mean| with the cell's sigma beside it,
//   and |slope - truth slope| where both are known.
#pragma once

#include <cstdint>
#include <vector>

#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/hazard_truth_t.hpp"

namespace swf::evaluation {

// A published hazard map (hazard_map_t, or the flight process's record of one) as plain arrays,
// not owned. Cell (i, j) is centred at (origin + (i + 0.5) cell_m, ...); arrays row-major
// j * n + i.
struct HazardMapView {
  std::int64_t frame_seq = -1;
  double origin_world_m[2] = {0.0, 0.0};
  double cell_m = 0.0;
  int cells_per_side = 0;
  const float* elevation_m = nullptr;         // NaN: unknown
  const float* sigma_m = nullptr;             // the elevation's
  const float* relief_sigma_m = nullptr;      // the relief's (the rock criterion's); NaN: no plane
  const float* slope_deg = nullptr;           // may be null (no slope errors then)
  const std::int8_t* hazard_class = nullptr;  // hazard_map_t.CLASS_*
  bool site_valid = false;
  double site_world_m[2] = {0.0, 0.0};
  double site_score = 0.0;
};

// The view of a decoded message (its arrays stay the message's). A map that is not square has no
// cells in the view (cells_per_side 0): the flight process publishes square maps only.
HazardMapView ViewOf(const swf_msgs::hazard_map_t& map);

// The view of a map whose fields are named as hazard_map_t's: the decoded message, or the flight
// process's record of it (swf/hazard_eval/map_metrics.hpp). What differs is said by the caller:
// the side of the square grid (0: no cells) and how an array field yields its first element.
template <typename Map, typename Data>
HazardMapView ViewOfFields(const Map& m, int cells_per_side, Data data) {
  HazardMapView v;
  v.frame_seq = m.frame_seq;
  v.origin_world_m[0] = m.origin_world_m[0];
  v.origin_world_m[1] = m.origin_world_m[1];
  v.cell_m = m.cell_size_m;
  v.cells_per_side = cells_per_side;
  v.elevation_m = data(m.elevation_m);
  v.sigma_m = data(m.sigma_m);
  v.relief_sigma_m = data(m.relief_sigma_m);
  v.slope_deg = data(m.slope_deg);
  v.hazard_class = data(m.hazard_class);
  v.site_valid = m.safe_site_valid;
  v.site_world_m[0] = m.safe_site_world_m[0];
  v.site_world_m[1] = m.safe_site_world_m[1];
  v.site_score = m.safe_site_score;
  return v;
}

inline constexpr int kRockHeightClasses = 3;

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
  double site_clearance_m = -1.0;          // capped at the truth's site_search_m; -1 without a site
  std::vector<double> elevation_errors_m;  // per known cell (cell_errors only)
  std::vector<double> elevation_sigmas_m;  // the same cells' sigma
  std::vector<double> slope_errors_deg;    // per known cell with a slope
};

// True when `truth` is the truth of `map`'s grid (frame, origin, cell size, cells).
bool SameGrid(const HazardMapView& map, const swf_msgs::hazard_truth_t& truth);

// The map against its truth (which must be on the same grid: SameGrid).
HazardMapMetrics JudgeHazardMap(const HazardMapView& map, const swf_msgs::hazard_truth_t& truth,
                                bool cell_errors);

}  // namespace swf::evaluation
