// The simulator's side of evaluation (ground side). During the run it sends the truth beside the
// estimates on channels of their own (evaluation::JudgeChannels: truth_state_t on SIM_TRUTH for
// every navigation output's frame, the true positions of every published map's landmarks on
// SIM_TRUTH_LANDMARKS, the truth of every published hazard map on its grid on SIM_TRUTH_HAZARD),
// so that they are published and recorded with the run, and it hands every message the run emits
// to evaluation::RunJudge, the same judge swf-judge runs on logs. A landmark's true position is
// where the ray through the pixel it was first seen at (the frame group's NewSighting), from the
// true camera pose of that frame, meets the terrain. A hazard map's truth is drawn from the
// terrain at the mapper's thresholds (hazard_eval::HazardTruthOf). The tracking error of every
// fused measurement of a known landmark (the feature marks, after refinement in the loop) is the
// pixel distance to that true point projected from the frame's true pose.
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
#include "swf/hazard_eval/map_metrics.hpp"
#include "swf/plot/plot.hpp"
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

class Evaluation : public app::OutputObserver {
 public:
  // Before the run: the descent whose truth is sent, the rectified rig the pipeline measures
  // with, the hazard mapper's thresholds, and the thread that publishes and records (this
  // observer's callbacks run on it).
  void Attach(const sim::Trajectory* trajectory, const sim::Terrain* terrain,
              const estimator::StereoCamera<double>& camera,
              const hazard::HazardMapperOptions& mapper, app::OutputThread* output);

  void OnNav(const app::NavRecord& r) override;  // first sightings, truth state, tracking error
  void OnMap(const app::MapRecord& r) override;  // the true positions of the map's landmarks
  void OnHazard(const app::HazardRecord& r) override;  // the map's truth; keeps the last map
  void OnMessage(const std::string& channel, const std::uint8_t* data, int size) override;

  // After the run (the output thread stopped).
  evaluation::RunScore Score() const { return judge_.Score(); }
  // The frame and pixel a landmark was first seen at, and where that ray meets the terrain
  // (false: never seen, or the ray misses the terrain).
  bool FirstSeen(std::int64_t id, app::NewSighting* sighting) const;
  bool TrueLandmark(std::int64_t id, Eigen::Vector3d* position);
  // TrackingErrors::relief_fraction of a true landmark first seen from `pose`.
  double ReliefFraction(const Eigen::Vector3d& point, const estimator::Pose<double>& pose) const;
  // |(u, v) - true projection| of every fused measurement of a known landmark (pixels), its
  // signed components (the paper's Fig. 2a histogram), and of those whose landmark was first
  // seen in the first frame, with the frames since.
  struct TrackingErrors {
    std::vector<double> all_px;
    std::vector<double> du_px;  // u - true u, left image
    std::vector<double> dv_px;  // v - true v
    std::vector<double> first_frame_px;
    std::vector<int> first_frame_age;
    // Per entry of du_px / dv_px: frames since the landmark's first sighting, the true
    // magnification of its neighbourhood since then (depth then / depth now), the true altitude,
    // and the sigma the filter was told for the measurement (FeatureMark::sigma_px).
    std::vector<int> age;
    std::vector<double> magnification;
    std::vector<double> altitude_m;
    std::vector<double> stated_sigma_px;
    // The error along the ray from the principal point (the descent's focus of expansion), over
    // the true distance from it: a tracker that under- or over-follows the image's expansion
    // shows as a non-zero median here, which scales the motion the filter sees.
    std::vector<double> radial_fraction;
    // The relief under the template at the first sighting: the landmark's height over the mean
    // of the ground on a ring of the tracker's patch radius around it, over its depth then
    // (positive: the landmark stands above what surrounds it, e.g. on a rock).
    std::vector<double> relief_fraction;
  };
  const TrackingErrors& Tracking() const { return tracking_; }
  // The stereo match's own error: per fused measurement of a known landmark, the first sighting
  // included (its left error is 0 by the truth's construction, see the file comment), the signed
  // errors of u (left), of u_right and of the disparity u - u_right against the true projection
  // from the frame's true pose, with the properties they may depend on and the sigmas the filter
  // was told (FeatureMark::sigma_px, sigma_disparity_px).
  struct StereoErrors {
    std::vector<double> du_left_px;
    std::vector<double> du_right_px;
    std::vector<double> dd_px;  // disparity - true disparity = du_left - du_right
    std::vector<double> true_disparity_px;
    std::vector<int> age;  // frames since the first sighting (0: the first sighting)
    std::vector<double> magnification;
    std::vector<double> altitude_m;
    std::vector<double> stated_sigma_px;
    std::vector<double> stated_sigma_disparity_px;
    std::vector<double> quality;  // FeatureMark::quality
    // The left column's sub-pixel phase, u - floor(u): bilinear sampling blurs a patch by an
    // amount that depends on it, and LK between differently blurred patches is biased.
    std::vector<double> left_subpixel_phase;
    // Does the stereo point stay where it was first measured? The measurement triangulated from
    // the frame's true pose, minus the first sighting's triangulated the same way, along the
    // current optical axis, over the current depth (positive: it reads farther away now). A
    // static landmark's should scatter about 0; a median that moves with the magnification is
    // a bias the filter can only absorb in its pose (NaN on the first sighting).
    std::vector<double> depth_drift_fraction;
    // The same track's errors in consecutive frames (the filter takes them as independent):
    // per pair the left u error and the disparity error then and now, and the age now.
    std::vector<double> left_then_px, left_now_px, disparity_then_px, disparity_now_px;
    std::vector<int> pair_age;
  };
  const StereoErrors& Stereo() const { return stereo_; }
  // The terrain with the hazard truth maps are judged against (the mapper's thresholds), for
  // plot::DrawTerrainHazard; empty when the truth could not be drawn.
  plot::HeightGrid TerrainTruth() const;
  // The last published hazard map (a copy kept after the run); null when none was published.
  const app::HazardRecord* LastHazardMap() const {
    return last_hazard_map_.capacity_cells > 0 ? &last_hazard_map_ : nullptr;
  }

 private:
  template <typename Message>
  void Send(const std::string& channel, const Message& m);

  const sim::Trajectory* trajectory_ = nullptr;
  const sim::Terrain* terrain_ = nullptr;
  estimator::StereoCamera<double> camera_;
  app::OutputThread* output_ = nullptr;
  evaluation::JudgeChannels channels_;
  evaluation::RunJudge judge_;
  std::unordered_map<std::int64_t, app::NewSighting> first_seen_;
  std::unordered_map<std::int64_t, Eigen::Vector3d> true_landmarks_;  // NaN: the ray missed
  std::unordered_map<std::int64_t, double> relief_fraction_;          // TrackingErrors
  TrackingErrors tracking_;
  StereoErrors stereo_;
  struct LastStereoError {
    std::int64_t frame_seq = -2;  // none yet
    double du_left_px = 0.0;
    double dd_px = 0.0;
  };
  std::unordered_map<std::int64_t, LastStereoError> last_stereo_;         // per track id
  std::unordered_map<std::int64_t, Eigen::Vector3d> first_stereo_point_;  // depth_drift_fraction
  std::int64_t first_frame_ = -1;  // frame_seq of the first navigation output
  void ScoreTracking(const app::NavRecord& r, const estimator::Pose<double>& pose);
  void ScoreStereo(const app::FeatureMark& m, std::int64_t frame_seq, const Eigen::Vector3d& true_z,
                   int age, double magnification, const estimator::Pose<double>& pose);
  double DepthDriftFraction(const app::FeatureMark& m, int age,
                            const estimator::Pose<double>& pose);
  swf_msgs::truth_state_t truth_;
  swf_msgs::landmark_map_t truth_map_;
  std::vector<std::uint8_t> buffer_;
  hazard_eval::MetricOptions hazard_options_;
  sim::HazardMap hazard_truth_;        // per terrain node, at the mapper's thresholds
  app::HazardRecord last_hazard_map_;  // a copy: the output thread reuses its slots
};

}  // namespace swf::sil
