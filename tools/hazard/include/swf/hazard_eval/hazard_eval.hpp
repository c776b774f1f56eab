// Hazard-mapping evaluation against the simulator's truth (tools only, never flight code):
// seeded descents over a simulated terrain, each map published as the flight process publishes it
// and judged by the one hazard-map-vs-truth metric (map_metrics.hpp), and the hazard-map PNG
// rendering of a published map.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/app/records.hpp"
#include "swf/core/status.hpp"
#include "swf/hazard/hazard_mapper.hpp"
#include "swf/hazard_eval/map_metrics.hpp"
#include "swf/sim/appearance.hpp"
#include "swf/sim/hazard.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/terrain.hpp"

namespace swf::hazard_eval {

struct EvalOptions {
  int image_width = 512;  // rendered resolution (the EDL rig's 25 deg FOV is kept)
  int image_height = 384;
  int downsample = 1;                      // mapper's dense-stereo reduction
  int terrain_size = 1024;                 // nodes (0.1 m): 102.4 m square
  double pose_sigma_per_altitude = 0.002;  // position sigma per axis = this x altitude (m)
  double attitude_sigma_deg = 0.02;
  int num_landmarks = 60;
  double footprint_radius_m = 1.5;
  double max_rock_height_m = 0.3;
  double max_slope_deg = 10.0;
  std::string shared_dir;  // the shared data folder (swf-hazard: ground_cli::SharedDir())
};

class World {
 public:
  // Builds terrain (preset, seed, reduced size) + appearance + renderer + truth. On failure
  // *error (when given) says which part failed and names the imagery files it read.
  core::Status Configure(sim::TerrainPreset preset, std::uint64_t seed, const EvalOptions& o,
                         std::string* error = nullptr);
  const sim::Terrain& Terrain() const { return terrain_; }
  const sim::HazardMap& Truth() const { return truth_; }
  const sim::Renderer& Renderer() const { return renderer_; }
  const sim::Appearance& Appearance() const { return appearance_; }
  // The pair rendered by the last Step() (with its exact depth).
  const sim::StereoImages& Images() const { return images_; }
  // Renders a pair at world_T_camera and feeds the mapper (pose perturbed by its covariance,
  // noisy landmarks from the truth depth). rng_seed drives the perturbations.
  // With `pose_error` / `pose_covariance` (both or neither): the mapper gets
  // world_T_camera.Retract(*pose_error) and *pose_covariance instead (e.g. a running SWF's error
  // and covariance along the same descent).
  core::Status Step(const estimator::Pose<double>& world_T_camera, std::uint64_t frame,
                    std::uint64_t rng_seed, hazard::HazardMapper* mapper, double* update_ms,
                    const Eigen::Matrix<double, 6, 1>* pose_error = nullptr,
                    const Eigen::Matrix<double, 6, 6>* pose_covariance = nullptr);
  // Publishes the mapper's map into Published() as the flight process's hazard group does
  // (app::FillHazardRecord); kFull when the record cannot be sized.
  core::Status Publish(const hazard::HazardMapper& mapper);
  const app::HazardRecord& Published() const { return published_; }
  // Publishes the mapper's map and judges it against truth (EvaluateHazardMap, per-cell errors
  // included, the options' rock threshold and footprint).
  core::Status Evaluate(const hazard::HazardMapper& mapper, HazardMapMetrics* metrics);
  hazard::HazardMapperOptions MapperOptions() const;

 private:
  EvalOptions options_;
  sim::Terrain terrain_;
  sim::Appearance appearance_;
  sim::Renderer renderer_;
  sim::HazardMap truth_;
  sim::StereoImages images_;
  std::vector<hazard::HazardLandmark> landmarks_;
  app::HazardRecord published_;
};

}  // namespace swf::hazard_eval
