// Evaluation of a simulated run against the simulator's truth (ground side, after the run):
// pose error of every navigation output, and the error of every landmark of every published map.
// A landmark's true position is where the ray through the pixel it was first seen at, from the
// true camera pose of that frame, meets the terrain.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/hazard/hazard_mapper.hpp"
#include "swf/sim/imu_model.hpp"
#include "swf/sim/terrain.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::app {

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
};

// The IMU alone from the filter's starting state (its pose, the guidance's velocity, zero
// biases): each frame interval preintegrated and propagated, no camera. Returns the RMS of the
// camera position error over the frames, the yardstick stereo-inertial estimation is against.
double ImuOnlyPoseRms(const sim::ImuModel& unit, const sim::Trajectory& trajectory,
                      const ImuOptions& imu, const estimator::Pose<double>& initial_world_T_camera);

// The final hazard map against the simulator's hazard truth (sim/hazard.hpp, same thresholds).
struct HazardEvaluation {
  std::int64_t maps = 0;  // hazard maps published
  int known_cells = 0;
  int rocks_resolved = 0;               // truth rocks >= the threshold whose cell resolves it
                                        // (sigma <= threshold / 3)
  int rocks_detected = 0;               // ... with a rock cell within the rock's radius + one cell
  double detection_probability = -1.0;  // detected / resolved (-1: none resolved)
  int rock_free_cells = 0;              // known cells without a truth rock >= threshold / 2 nearby
  int false_rock_cells = 0;             // ... classified rock
  double false_alarm_rate = 0.0;        // false_rock_cells / rock_free_cells
  bool site_valid = false;
  double site_x_m = 0.0;
  double site_y_m = 0.0;
  double site_score = 0.0;
  bool site_on_hazard = false;     // a truth hazard node within the footprint of the site
  double site_clearance_m = -1.0;  // site to the nearest truth hazard node (capped at 20 m)
};

HazardEvaluation EvaluateHazard(const hazard::HazardMapper& mapper, const sim::Terrain& terrain,
                                std::int64_t maps_published);

// Keeps copies of the outputs (output thread) for the evaluation after the run.
class Evaluation : public OutputObserver {
 public:
  void OnNav(const NavRecord& r) override;
  void OnMap(const MapRecord& r) override;

  // After the run (the pipeline is idle). Writes gnuplot data into plot_dir when not empty.
  EvaluationResult Evaluate(const Pipeline& pipeline, const sim::Trajectory& trajectory,
                            const sim::Terrain& terrain, const std::string& plot_dir) const;

 private:
  struct Nav {
    std::int64_t frame_seq;
    double p[3];
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
  std::vector<Nav> navs_;
  std::vector<Map> maps_;
};

}  // namespace swf::app
