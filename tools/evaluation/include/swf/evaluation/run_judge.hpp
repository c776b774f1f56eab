// RunJudge: the one evaluation of a run's navigation, landmark and hazard outputs against truth,
// from messages alone. It reads what a run published or recorded: the estimates (nav_state_t on
// SWF_NAV, landmark_map_t on SWF_LANDMARKS, hazard_map_t on SWF_HAZARD) and the truth a simulator
// or test range sent on channels of its own (truth_state_t on SIM_TRUTH, landmark_map_t with true
// positions on SIM_TRUTH_LANDMARKS, hazard_truth_t on SIM_TRUTH_HAZARD). Estimates and truth are
// paired by frame_seq, landmarks by id, whatever order they arrive in. So a live run (swf-sil feeds
// it the bytes it emits), a replay, a hardware-in-the-loop run and every campaign run are judged by
// the same code (swf-judge reads logs).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "swf/evaluation/hazard_score.hpp"
#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/hazard_truth_t.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

namespace swf::evaluation {

struct JudgeChannels {
  std::string nav = "SWF_NAV";
  std::string landmarks = "SWF_LANDMARKS";
  std::string truth = "SIM_TRUTH";
  std::string truth_landmarks = "SIM_TRUTH_LANDMARKS";
  std::string hazard = "SWF_HAZARD";
  std::string truth_hazard = "SIM_TRUTH_HAZARD";
};

// One navigation output against the truth of its frame. The world is z-up (horizontal = x, y).
struct OutputScore {
  std::int64_t frame_seq = 0;
  std::int64_t utime = 0;  // the estimate's frame time (nav_state_t.utime), microseconds
  double estimate_m[3] = {0.0, 0.0, 0.0};
  double truth_m[3] = {0.0, 0.0, 0.0};
  double error_m = 0.0;
  double altitude_m = 0.0;  // true height above the terrain below
  double horizontal_error_m = 0.0;
  double vertical_error_m = 0.0;
  double attitude_error_deg = 0.0;  // angle of est_R^T true_R
  // The same rotation as Log(est_R^T true_R) about the estimate's camera axes, degrees: the phi
  // of nav_state_t.covariance (geometry.hpp: R <- R Exp(phi)).
  double attitude_error_axes_deg[3] = {0.0, 0.0, 0.0};
  // 1-sigma of the output's own covariance: position per world axis (m), rotation per camera
  // axis (deg); NaN where the output had no usable covariance (all zero, or not positive).
  double position_sigma_m[3] = {0.0, 0.0, 0.0};
  double attitude_sigma_deg[3] = {0.0, 0.0, 0.0};
  std::int8_t status = 0;  // nav_state_t.STATUS_*
  double hpl_m = 0.0;
  double vpl_m = 0.0;
  // e^T P^-1 e against the output's 3x3 position covariance; NaN without a usable covariance.
  double position_nees = 0.0;
};

// One published landmark map: its landmarks with a true position.
struct MapScore {
  std::int64_t frame_seq = 0;
  std::int64_t utime = 0;  // landmark_map_t.utime, microseconds
  std::int64_t landmarks_evaluated = 0;
  double rms_error_m = 0.0;     // NaN when none was evaluated
  double median_error_m = 0.0;  // the upper median; NaN when none was evaluated
};

// One published hazard map against its truth (hazard_score.hpp; no per-cell errors).
struct HazardScore {
  std::int64_t frame_seq = 0;
  double altitude_m = 0.0;  // true altitude at the map's frame (SIM_TRUTH); NaN without it
  HazardMapMetrics map;
};

struct LandmarkScore {
  std::int64_t id = 0;
  double estimate_m[3] = {0.0, 0.0, 0.0};
  double truth_m[3] = {0.0, 0.0, 0.0};
  double error_m = 0.0;
  // The estimate's stated covariance (landmark_map_t: upper triangle xx xy xz yy yz zz, m^2),
  // its observations in the window, and e^T P^-1 e (NaN when P is not positive definite).
  double covariance_m2[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  std::int32_t num_observations = 0;
  double nees = 0.0;
};

struct RunScore {
  // Navigation outputs with the truth of their frame, in arrival order.
  std::vector<OutputScore> outputs;
  std::int64_t navs_without_truth = 0;
  double pose_rms_error_m = 0.0;  // NaN without outputs
  double final_pose_error_m = 0.0;
  double final_attitude_error_deg = 0.0;
  double mean_position_nees = 0.0;  // over the outputs with a covariance; NaN without any
  // Integrity against truth: VALID outputs, and those whose true horizontal or vertical error
  // exceeded its protection level (each one an integrity failure).
  std::int64_t valid_navs = 0;
  std::int64_t protection_violations = 0;
  double max_error_over_protection = 0.0;  // largest true error / protection level (VALID)
  // Landmark maps with their truth, in arrival order, and the last one landmark by landmark.
  std::vector<MapScore> maps;
  std::int64_t maps_without_truth = 0;
  std::vector<LandmarkScore> last_map;
  // Hazard maps with their truth, in arrival order; those still without truth at the end, and
  // those whose truth was for another grid (neither is judged).
  std::vector<HazardScore> hazard_maps;
  std::int64_t hazard_maps_without_truth = 0;
  std::int64_t hazard_truth_mismatched = 0;
  // Messages on a judged channel that did not decode (named in the first error).
  std::int64_t undecodable = 0;
  std::string first_decode_error;
};

class RunJudge {
 public:
  explicit RunJudge(JudgeChannels channels = {});

  // One message as it went over the bus or into a log. Channels the judge does not read are
  // ignored (true); a judged message that does not decode is counted and false.
  bool Add(const std::string& channel, const void* data, std::size_t size);

  void AddNav(const swf_msgs::nav_state_t& m);
  void AddLandmarks(const swf_msgs::landmark_map_t& m);
  void AddTruth(const swf_msgs::truth_state_t& m);
  void AddTruthLandmarks(const swf_msgs::landmark_map_t& m);
  // A map waits for its truth and a truth for its map (by frame_seq); the pair is judged when the
  // second arrives and neither is kept.
  void AddHazard(swf_msgs::hazard_map_t m);
  void AddTruthHazard(swf_msgs::hazard_truth_t m);

  RunScore Score() const;

  const JudgeChannels& Channels() const { return channels_; }

 private:
  struct Nav {
    std::int64_t frame_seq;
    std::int64_t utime;
    double p[3];
    double q[4];  // world_R_camera (w, x, y, z)
    std::int8_t status;
    double hpl_m;
    double vpl_m;
    double position_covariance[9];
    double sigma[6];  // sqrt of the covariance's diagonal, NaN where not positive
  };
  struct Truth {
    double p[3];
    double q[4];
    double altitude_m;
  };
  struct Landmark {
    std::int64_t id;
    double p[3];
    double covariance_m2[6];  // landmark_map_t's upper triangle (zero for a truth map)
    std::int32_t num_observations;
  };
  struct Map {
    std::int64_t frame_seq;
    std::int64_t utime;
    std::vector<Landmark> landmarks;
  };

  void JudgeHazard(const swf_msgs::hazard_map_t& map, const swf_msgs::hazard_truth_t& truth);

  JudgeChannels channels_;
  std::vector<Nav> navs_;
  std::vector<Map> maps_;
  std::map<std::int64_t, Truth> truth_;
  std::map<std::int64_t, std::map<std::int64_t, Landmark>> truth_maps_;    // frame_seq -> id
  std::map<std::int64_t, swf_msgs::hazard_map_t> hazard_waiting_;          // frame_seq -> map
  std::map<std::int64_t, swf_msgs::hazard_truth_t> hazard_truth_waiting_;  // frame_seq -> truth
  struct JudgedHazard {
    std::int64_t frame_seq;
    HazardMapMetrics map;
  };
  std::vector<JudgedHazard> hazard_judged_;
  std::int64_t hazard_truth_mismatched_ = 0;
  std::int64_t undecodable_ = 0;
  std::string first_decode_error_;
};

// What JudgeLogs read besides what it gave the judge.
struct LogTally {
  std::int64_t events = 0;
  swf_msgs::hazard_map_t
      last_hazard_map;  // the last map on the judge's hazard channel that decoded
  bool has_hazard_map = false;
};

// Every event of the LCM logs, log after log, to the judge (a recorded run judged like a live
// one); false at the first unreadable log or damaged record, with the error naming it.
bool JudgeLogs(const std::vector<std::string>& paths, RunJudge* judge, LogTally* tally,
               std::string* error);

}  // namespace swf::evaluation
