// The simulator's side of evaluation (ground side). During the run it sends the truth beside the
// estimates on channels of their own (evaluation::JudgeChannels: truth_state_t on SIM_TRUTH for
// every navigation output's frame, the true positions of every published map's landmarks on
// SIM_TRUTH_LANDMARKS), so that they are published and recorded with the run, and it hands every
// message the run emits to evaluation::RunJudge, the same judge swf-judge runs on logs. A
// landmark's true position is where the ray through the pixel it was first seen at (the frame
// group's NewSighting), from the true camera pose of that frame, meets the terrain. Hazard maps
// are kept for the hazard evaluation against the terrain's truth after the run.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/evaluation/run_judge.hpp"
#include "swf/hazard/hazard_mapper.hpp"
#include "swf/sim/hazard.hpp"
#include "swf/sim/imu_model.hpp"
#include "swf/sim/terrain.hpp"
#include "swf/sim/trajectory.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

namespace swf::sil {

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

class Evaluation : public app::OutputObserver {
 public:
  // Before the run: the descent whose truth is sent, the rectified rig the pipeline measures
  // with, and the thread that publishes and records (this observer's callbacks run on it).
  void Attach(const sim::Trajectory* trajectory, const sim::Terrain* terrain,
              const estimator::StereoCamera<double>& camera, app::OutputThread* output);

  void OnNav(const app::NavRecord& r) override;  // first sightings; the frame's truth state
  void OnMap(const app::MapRecord& r) override;  // the true positions of the map's landmarks
  void OnHazard(const app::HazardRecord& r) override;
  void OnMessage(const std::string& channel, const std::uint8_t* data, int size) override;

  // After the run (the output thread stopped).
  evaluation::RunScore Score() const { return judge_.Score(); }
  // The frame and pixel a landmark was first seen at, and where that ray meets the terrain
  // (false: never seen, or the ray misses the terrain).
  bool FirstSeen(std::int64_t id, app::NewSighting* sighting) const;
  bool TrueLandmark(std::int64_t id, Eigen::Vector3d* position);
  // Gnuplot data of a judged run into plot_dir: trajectory.dat, landmark_error.dat, map.dat.
  static void WritePlots(const evaluation::RunScore& score, const std::string& plot_dir);
  // Every published hazard map, in order, against the truth of the mapper's thresholds.
  std::vector<HazardEvaluation> EvaluateHazard(const hazard::HazardMapperOptions& thresholds,
                                               const sim::Trajectory& trajectory,
                                               const sim::Terrain& terrain) const;

 private:
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
  template <typename Message>
  void Send(const std::string& channel, const Message& m);

  static HazardEvaluation EvaluateHazardMap(const PublishedHazardMap& map,
                                            const hazard::HazardMapperOptions& thresholds,
                                            const sim::Terrain& terrain,
                                            const sim::HazardMap& truth);
  const sim::Trajectory* trajectory_ = nullptr;
  const sim::Terrain* terrain_ = nullptr;
  estimator::StereoCamera<double> camera_;
  app::OutputThread* output_ = nullptr;
  evaluation::JudgeChannels channels_;
  evaluation::RunJudge judge_;
  std::unordered_map<std::int64_t, app::NewSighting> first_seen_;
  std::unordered_map<std::int64_t, Eigen::Vector3d> true_landmarks_;  // NaN: the ray missed
  swf_msgs::truth_state_t truth_;
  swf_msgs::landmark_map_t truth_map_;
  std::vector<std::uint8_t> buffer_;
  std::vector<PublishedHazardMap> hazard_maps_;
};

}  // namespace swf::sil
