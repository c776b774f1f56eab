// The simulator's side of the hazard-map-vs-truth metric: the truth of one published hazard map
// drawn from the terrain (hazard_truth_t on the map's grid, what swf-sil sends on
// SIM_TRUTH_HAZARD), and the metric of the map against it in one call for the tools that hold the
// terrain (swf-hazard eval|flight, hazard_sim_test). The metric itself is evaluation's
// (swf/evaluation/hazard_score.hpp: the definitions), written once for live runs and logs alike.
//
// The truth of a map (threshold h = MetricOptions::max_rock_height_m, cell size c):
// - elevation: the mean of 4 x 4 terrain samples in the cell; slope: sim::HazardMap's slope at
//   the terrain node nearest the cell centre (NaN off the terrain);
// - rock_free: no truth rock node >= h / 2 within c / 2 + 0.3 m of the cell centre;
// - rocks: the terrain's rocks >= h whose centre lies on the map;
// - the site's clearance: the distance from the map's safe site to the nearest truth hazard node
//   (slope or rock, sim::HazardMap's bits), searched and capped at kSiteSearchM = 20 m. The cap
//   bounds the search; it is the value swf-sil's summary has always documented
//   (`clearance_to_truth_hazard_m`, read by campaign tooling).
// Which truth (slope baseline, thresholds) is the caller's: sim::ComputeHazardTruth's options.
#pragma once

#include <vector>

#include "swf/app/records.hpp"
#include "swf/evaluation/hazard_score.hpp"
#include "swf/sim/hazard.hpp"
#include "swf/sim/terrain.hpp"
#include "swf_msgs/hazard_truth_t.hpp"

namespace swf::hazard_eval {

using evaluation::HazardMapMetrics;
using evaluation::HazardMapView;
using evaluation::kRockHeightClasses;

// The view of a published record (its arrays stay the record's).
HazardMapView ViewOf(const app::HazardRecord& record);

inline constexpr double kSiteSearchM = 20.0;

struct MetricOptions {
  double max_rock_height_m = 0.3;  // the mapper's threshold (HazardMapperOptions)
  double footprint_radius_m = 1.5;
  bool cell_errors = true;  // fill the per-cell error vectors (swf-hazard's calibration figures)
};

// The truth of `map`'s grid and site: `terrain` gives the truth grid (node positions) and the
// true heights, `rocks` the truth rock list (terrain.Rocks(); a test passes its own), `truth` the
// per-node layers on the terrain's grid (sim::ComputeHazardTruth of the terrain, or hand-built).
swf_msgs::hazard_truth_t HazardTruthOf(const HazardMapView& map, const sim::Terrain& terrain,
                                       const std::vector<sim::Rock>& rocks,
                                       const sim::HazardMap& truth, const MetricOptions& options);

// evaluation::JudgeHazardMap against HazardTruthOf the same map.
HazardMapMetrics EvaluateHazardMap(const HazardMapView& map, const sim::Terrain& terrain,
                                   const std::vector<sim::Rock>& rocks, const sim::HazardMap& truth,
                                   const MetricOptions& options);

}  // namespace swf::hazard_eval
