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
};

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
