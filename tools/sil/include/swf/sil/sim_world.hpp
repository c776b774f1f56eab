// The simulated world behind `source: sim`: terrain, appearance, rig, trajectory, camera timing
// faults, motion input and IMU unit built from the configuration, and the descent rendered
// before start for sim::PrerenderedStereoSource. Truth (poses, terrain) stays available for the
// evaluation after the run.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "swf/app/config.hpp"
#include "swf/app/flight_loop.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/drivers/stereo_source.hpp"
#include "swf/sim/appearance.hpp"
#include "swf/sim/imu_model.hpp"
#include "swf/sim/orbital.hpp"
#include "swf/sim/prerendered_source.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/terrain.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sil {

// The terrain of a sim configuration (seconds for 2048^2 nodes).
bool SimTerrain(const app::FswConfig& config, sim::Terrain* terrain, std::string* error);

// The camera rig of a sim configuration.
sim::RigOptions SimRig(const app::FswConfig& config);

// The simulated IMU unit of a sim configuration (sim.imu_unit, mounted at imu.camera_*_imu);
// false for "none".
bool SimImuUnit(const app::FswConfig& config, sim::ImuModelOptions* unit);

// The stereo-inertial estimator's IMU (imu.enabled): the flight process's imu.* options
// (app::ImuOptionsFor), with the simulator's unit's rate, noise, ranges, gravity and bias sigmas
// when sim.imu_unit names one, and with `truth` (initial: truth) the true velocity at start.
app::ImuOptions SimImuOptions(const app::FswConfig& config, const sim::Trajectory* truth);

// initial: truth: the state guidance hands over at the first frame, the true camera pose and
// (SimImuOptions) IMU velocity, with sim.handover_error: drawn an error drawn from the first
// state's stated sigmas added to both (pose: po->swf's first_pose_sigma_*, in the estimator's
// Retract convention on the first state, world_T_imu or world_T_camera; velocity: po->imu's
// first_velocity_sigma_mps). Seeded by sim.seed on a stream of its own.
void SimHandover(const app::FswConfig& config, const sim::Trajectory& truth,
                 app::PipelineOptions* po);

// The trajectory (and rig) of a sim configuration. Cheap (no terrain) unless `sim.target:
// orbital`: the descent target then comes from `terrain` (built here when null), and `chosen`
// (optional) receives the selection.
bool SimTrajectory(const app::FswConfig& config, sim::Trajectory* trajectory, sim::RigOptions* rig,
                   std::string* error, const sim::Terrain* terrain = nullptr,
                   sim::OrbitalTarget* chosen = nullptr);

class SimWorld : public drivers::MotionProvider, public drivers::ImuProvider {
 public:
  // Builds terrain, appearance and renderer (seconds for a 2048^2 terrain).
  bool Build(const app::FswConfig& config, std::string* error);
  const sim::Terrain& Terrain() const { return terrain_; }
  const sim::Trajectory& Trajectory() const { return trajectory_; }
  // The orbital pre-selection (`sim.target: orbital`; default-constructed otherwise).
  const sim::OrbitalTarget& Target() const { return target_; }
  const estimator::StereoCamera<double>& Camera() const { return renderer_.Camera(); }
  std::int32_t Width() const { return rig_.width_px; }
  std::int32_t Height() const { return rig_.height_px; }
  std::int32_t NumFrames() const { return num_frames_; }
  // Camera timing faults (sim.frame_drop_probability, sim.timestamp_jitter_ms), drawn once from
  // the seed: whether frame k reaches the flight loop, and its exposure stamp (the trajectory's
  // frame time plus the jitter; the image and the truth stay those of the frame time). Frame 0,
  // the hand-over whose true state starts the filter, is always delivered on time.
  bool Delivered(std::int32_t k) const { return frames_.delivered[k] != 0; }
  core::TimeNs ExposureNs(std::int32_t k) const { return frames_.exposure_ns[k]; }
  std::int32_t DeliveredFrames() const { return delivered_frames_; }

  // Renders frames [0, NumFrames()) with `threads` threads; progress(done, total) is called from
  // the calling thread.
  bool RenderAll(int threads, void (*progress)(int done, int total), std::string* error);
  const std::uint8_t* Left(std::int32_t k) const { return frames_.left[k].data(); }
  const std::uint8_t* Right(std::int32_t k) const { return frames_.right[k].data(); }
  // The rendered frames as the camera delivers them (sim::PrerenderedStereoSource serves them).
  const sim::RenderedDescent& Frames() const { return frames_; }
  // The simulated IMU: noisy true relative motion into frame seq from the frame served before it
  // (across dropped frames; none for frame 0 or when sim.imu is false).
  bool Motion(std::uint64_t seq, drivers::MotionInput* input) override;
  // The simulated IMU unit's samples (sim.imu_unit), in time order.
  bool NextImu(std::int64_t until_utime, estimator::ImuSample<double>* sample) override;
  // The unit (nullptr for sim.imu_unit none): its samples, true biases and noise model.
  const sim::ImuModel* ImuUnit() const { return has_imu_unit_ ? &imu_unit_ : nullptr; }

 private:
  void DrawCameraTiming(const app::FswConfig& config);
  void DrawMotionInputs(const app::FswConfig& config);  // after DrawCameraTiming

  sim::RigOptions rig_;
  sim::Terrain terrain_;
  sim::Appearance appearance_;
  sim::Renderer renderer_;
  sim::Trajectory trajectory_;
  sim::OrbitalTarget target_;
  std::int32_t num_frames_ = 0;
  std::int32_t delivered_frames_ = 0;
  std::vector<drivers::MotionInput> motion_;
  bool imu_ = false;
  bool has_imu_unit_ = false;
  drivers::StoredImuProvider imu_samples_;
  std::int64_t black_from_ = -1;  // inject.black_from / black_frames
  std::int64_t black_frames_ = 0;
  sim::ImuModel imu_unit_;
  sim::RenderedDescent frames_;
};

}  // namespace swf::sil
