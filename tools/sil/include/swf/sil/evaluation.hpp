// Evaluation of a simulated run against the simulator's truth (ground side, after the run):
// pose error of every navigation output, the error of every landmark of every published map, and
// every published hazard map against the terrain's hazard truth. A landmark's true position is
// where the ray through the pixel it was first seen at, from the true camera pose of that frame,
// meets the terrain.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/hazard/hazard_mapper.hpp"
#include "swf/sim/hazard.hpp"
#include "swf/sim/imu_model.hpp"
#include "swf/sim/terrain.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sil {

struct EvaluationResult {
  std::int64_t navs = 0;
  double pose_rms_error_m = 0.0;
  double final_pose_error_m = 0.0;
  std::int64_t maps = 0;
  double landmark_rms_error_m = 0.0;     // the last published map
  double landmark_median_error_m = 0.0;  // the last published map
  std::int64_t landmarks_evaluated = 0;  // in the last map
  // Integrity against truth: VALID outputs, and those whose true horizontal or vertical error
  // exceeded its protection level (each one an integrity failure: VALID promised otherwise).
  std::int64_t valid_navs = 0;
  std::int64_t protection_violations = 0;
  double max_error_over_protection = 0.0;  // largest true error / protection level (VALID)
  // Consistency of the published covariance: e^T P^-1 e of the position error against the
  // output's 3x3 position covariance, per output (NaN where it had none); chi-square with 3
  // degrees of freedom, mean 3, for a consistent estimator.
  std::vector<double> position_nees;
  double mean_position_nees = 0.0;  // over the outputs with a covariance
  // Per output, in output order: the true altitude of the camera above the terrain below it,
  // the errors (the simulator's world is z-up: horizontal = x, y) and what the output claimed.
  struct Output {
    std::int64_t frame_seq = 0;
    double altitude_m = 0.0;
    double horizontal_error_m = 0.0;
    double vertical_error_m = 0.0;
    double attitude_error_deg = 0.0;  // angle of est_R^T true_R
    std::int8_t status = 0;           // nav_state_t.STATUS_*
    double hpl_m = 0.0;
    double vpl_m = 0.0;
  };
  std::vector<Output> outputs;
  double final_attitude_error_deg = 0.0;
};

// The IMU alone from the filter's starting state (its pose, the guidance's velocity, zero
// biases): each frame interval preintegrated and propagated, no camera. Returns the RMS of the
// camera position error over the frames, the yardstick stereo-inertial estimation is against.
double ImuOnlyPoseRms(const sim::ImuModel& unit, const sim::Trajectory& trajectory,
                      const app::ImuOptions& imu,
                      const estimator::Pose<double>& initial_world_T_camera);

// A published hazard map against the simulator's hazard truth (sim/hazard.hpp, same thresholds).
// Rocks are counted in height classes [1, 2), [2, 4) and [4, inf) times the rock threshold.
inline constexpr int kRockHeightClasses = 3;
struct HazardEvaluation {
  std::int64_t frame_seq = -1;  // the frame the map belongs to
  double altitude_m = 0.0;      // true altitude of the camera above the terrain at that frame
  int known_cells = 0;
  int rocks_resolved = 0;               // truth rocks >= the threshold whose cell resolves it
                                        // (sigma <= threshold / 3)
  int rocks_detected = 0;               // ... with a rock cell within the rock's radius + one cell
  double detection_probability = -1.0;  // detected / resolved (-1: none resolved)
  int rocks_resolved_by_height[kRockHeightClasses] = {};
  int rocks_detected_by_height[kRockHeightClasses] = {};
  int rock_free_cells = 0;        // known cells without a truth rock >= threshold / 2 nearby
  int false_rock_cells = 0;       // ... classified rock
  double false_alarm_rate = 0.0;  // false_rock_cells / rock_free_cells
  bool site_valid = false;
  double site_x_m = 0.0;
  double site_y_m = 0.0;
  double site_score = 0.0;
  bool site_on_hazard = false;     // a truth hazard node within the footprint of the site
  double site_clearance_m = -1.0;  // site to the nearest truth hazard node (capped at 20 m)
};

// Keeps copies of the outputs (output thread) for the evaluation after the run.
class Evaluation : public app::OutputObserver {
 public:
  void OnNav(const app::NavRecord& r) override;
  void OnMap(const app::MapRecord& r) override;
  void OnHazard(const app::HazardRecord& r) override;

  // After the run (the pipeline is idle). Writes gnuplot data into plot_dir when not empty.
  EvaluationResult Evaluate(const app::Pipeline& pipeline, const sim::Trajectory& trajectory,
                            const sim::Terrain& terrain, const std::string& plot_dir) const;
  // Every published hazard map, in order, against the truth of the mapper's thresholds.
  std::vector<HazardEvaluation> EvaluateHazard(const hazard::HazardMapperOptions& thresholds,
                                               const sim::Trajectory& trajectory,
                                               const sim::Terrain& terrain) const;

 private:
  struct Nav {
    std::int64_t frame_seq;
    double p[3];
    double q[4];  // world_R_camera (w, x, y, z)
    std::int8_t status;
    double hpl_m;
    double vpl_m;
    double position_covariance[9];
  };
  struct Landmark {
    std::int64_t id;
    double p[3];
  };
  struct Map {
    std::int64_t frame_seq;
    std::vector<Landmark> landmarks;
  };
  // The fields of a published hazard map the evaluation reads.
  struct PublishedHazardMap {
    std::int64_t frame_seq = 0;
    double origin_m[2] = {0.0, 0.0};
    double cell_m = 0.0;
    int cells_per_side = 0;
    std::vector<float> elevation_m;
    std::vector<float> sigma_m;
    std::vector<std::int8_t> classes;  // hazard_map_t.CLASS_*
    bool site_valid = false;
    double site_m[2] = {0.0, 0.0};
    double site_score = 0.0;
  };
  static HazardEvaluation EvaluateHazardMap(const PublishedHazardMap& map,
                                            const hazard::HazardMapperOptions& thresholds,
                                            const sim::Terrain& terrain,
                                            const sim::HazardMap& truth);
  std::vector<Nav> navs_;
  std::vector<Map> maps_;
  std::vector<PublishedHazardMap> hazard_maps_;
};

}  // namespace swf::sil
