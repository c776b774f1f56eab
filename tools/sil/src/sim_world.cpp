#include "swf/sil/sim_world.hpp"

#include "swf/app/app.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <random>
#include <thread>

#include "swf/ground_cli/shared_dir.hpp"
#include "swf/sim/rng.hpp"

namespace swf::sil {

using core::Status;

namespace {

// The lab scenarios (the paper's lab rig, section 4.2.2) see the terrain and its texture scaled by
// 0.1: the EDL scene at a tenth of the size, as the lab rig's 0.1 m baseline is the EDL rig's
// 1 m at a tenth.
double SceneScale(const app::FswConfig& config) {
  return config.sim.scenario == "lab" || config.sim.scenario == "lab_static" ? 0.1 : 1.0;
}

std::string SharedDir(const app::FswConfig& config) {
  if (!config.sim.shared_dir.empty()) return config.sim.shared_dir;
  return ground_cli::SharedDir();
}

}  // namespace

bool SimTerrain(const app::FswConfig& config, sim::Terrain* terrain, std::string* error) {
  sim::TerrainPreset preset;
  if (!sim::ParseTerrainPreset(config.sim.terrain.c_str(), &preset)) {
    *error = "sim.terrain: unknown preset";
    return false;
  }
  const double scale = SceneScale(config);
  sim::TerrainOptions to =
      sim::ScaleTerrain(sim::TerrainPresetOptions(preset, config.sim.seed), scale);
  // A smaller grid keeps the same cell size (the terrain shrinks, the texture stays).
  to.size = config.sim.terrain_size;
  if (terrain->Configure(to) != Status::kOk) {
    *error = "sim.terrain_size: the terrain was refused";
    return false;
  }
  return true;
}

sim::RigOptions SimRig(const app::FswConfig& config) {
  sim::RigOptions rig = SceneScale(config) < 1.0 ? sim::LabRig() : sim::EdlRig();
  rig.width_px = config.sim.width_px;
  rig.height_px = config.sim.height_px;
  rig.horizontal_fov_deg = config.sim.hfov_deg;
  rig.baseline_m = config.sim.baseline_m;
  return rig;
}

bool SimTrajectory(const app::FswConfig& config, sim::Trajectory* trajectory, sim::RigOptions* rig,
                   std::string* error, const sim::Terrain* terrain, sim::OrbitalTarget* chosen) {
  *rig = SimRig(config);
  sim::TrajectoryOptions t;
  if (config.sim.scenario == "descent") {
    const app::SimConfig& s = config.sim;
    t = sim::DescentTrajectory(config.rate_hz, s.start_altitude_m, s.end_altitude_m,
                               s.descent_rate_mps);
    t.velocity_world_mps.x() = s.horizontal_velocity_mps[0];
    t.velocity_world_mps.y() = s.horizontal_velocity_mps[1];
    const double deg = std::numbers::pi / 180.0;
    t.attitude_offset_rad =
        Eigen::Vector3d(s.attitude_deg[0], s.attitude_deg[1], s.attitude_deg[2]) * deg;
    t.body_rate_radps =
        Eigen::Vector3d(s.attitude_rate_dps[0], s.attitude_rate_dps[1], s.attitude_rate_dps[2]) *
        deg;
  } else if (config.sim.scenario == "hover") {
    t = sim::HoverTrajectory(50.0, 60);
    t.rate_hz = config.rate_hz;
  } else if (config.sim.scenario == "lab_static") {
    // Fig. 12 with the lab rig: the hover scaled like the lab scene (5 m above the surface).
    t = sim::HoverTrajectory(5.0, 60);
    t.rate_hz = config.rate_hz;
  } else if (config.sim.scenario == "sideways") {
    t = sim::SidewaysTrajectory(*rig, 50.0, 0.85, 40);
  } else {
    t = sim::LabTrajectory(config.rate_hz);
  }
  t.seed = config.sim.seed;
  if (config.sim.frames > 0 && config.sim.frames < t.num_frames) t.num_frames = config.sim.frames;
  if (config.sim.target == "orbital") {
    // The same vertical descent, over the target orbit picked around the nominal one (the
    // origin); the mapper's target is the nadir of the first frame, i.e. this point.
    sim::Terrain built;
    if (terrain == nullptr) {
      if (!SimTerrain(config, &built, error)) return false;
      terrain = &built;
    }
    sim::OrbitalSelectionOptions so;
    so.search_radius_m = config.sim.target_search_m;
    sim::OrbitalTarget target;
    if (sim::SelectOrbitalTarget(*terrain, so, &target) != Status::kOk) {
      *error =
          "sim.target_search_m: the orbital search square (radius + 10 m clearance cap) does not "
          "fit in the terrain (sim.terrain_size)";
      return false;
    }
    t.start_world_m.x() += target.target_m.x();
    t.start_world_m.y() += target.target_m.y();
    if (chosen != nullptr) *chosen = target;
  }
  if (trajectory->Configure(t) != Status::kOk) {
    *error = "sim.scenario: the trajectory was refused (rate_hz or frames)";
    return false;
  }
  return true;
}

bool SimWorld::Build(const app::FswConfig& config, std::string* error) {
  if (!SimTerrain(config, &terrain_, error)) return false;
  if (!SimTrajectory(config, &trajectory_, &rig_, error, &terrain_, &target_)) return false;
  num_frames_ = trajectory_.NumFrames();
  const double scale = SceneScale(config);
  sim::AppearanceOptions look = sim::DefaultImagery(SharedDir(config));
  look.image_pixel_m *= scale;
  look.seed = config.sim.seed;
  look.sun_elevation_deg = config.sim.sun_elevation_deg;
  look.sun_azimuth_deg = config.sim.sun_azimuth_deg;
  const Status a = appearance_.Configure(terrain_, look);
  if (a != Status::kOk) {
    *error = "sim.shared: the terrain imagery under '" + SharedDir(config) + "' cannot be read (" +
             core::ToString(a) + ")";
    return false;
  }
  black_from_ = config.inject_black_from;
  black_frames_ = config.inject_black_frames;
  DrawCameraTiming(config);
  DrawMotionInputs(config);
  sim::ImuModelOptions unit;
  has_imu_unit_ = SimImuUnit(config, &unit);
  // A jittered stamp may come up to 4 sigma after its frame: the unit samples that far past the
  // last one, so the last frame's interval is covered like every other.
  // A unit stamping early (sim.imu_clock_offset_ms < 0) samples that much longer.
  unit.tail_s = 4.0 * config.sim.timestamp_jitter_ms * 1e-3 +
                std::max(0.0, -config.sim.imu_clock_offset_ms * 1e-3);
  if (has_imu_unit_ && imu_unit_.Configure(unit, trajectory_) != Status::kOk) {
    *error = "sim.imu_unit: the IMU model refused the unit or the trajectory";
    return false;
  }
  imu_samples_.Reset(has_imu_unit_ ? &imu_unit_.Samples() : nullptr);
  sim::RenderOptions ro;
  ro.rig = rig_;
  ro.seed = config.sim.seed;
  ro.read_noise_e = config.sim.read_noise_e;
  ro.electrons_per_dn = config.sim.e_per_dn;
  ro.exposure_dn = config.sim.exposure_dn;
  // The true right camera; Camera() (what the pipeline is told) stays the calibrated rig.
  ro.baseline_error_m = config.sim.baseline_error_m;
  const double* r = config.sim.relative_rotation_error_rad;
  ro.right_rotation_error_rad = Eigen::Vector3d(r[0], r[1], r[2]);
  if (renderer_.Configure(ro) != Status::kOk) {
    *error = "sim.width_px: the renderer refused the rig";
    return false;
  }
  return true;
}

void SimWorld::DrawCameraTiming(const app::FswConfig& config) {
  frames_.width_px = rig_.width_px;
  frames_.height_px = rig_.height_px;
  std::vector<std::uint8_t>& delivered = frames_.delivered;
  std::vector<core::TimeNs>& exposure_ns = frames_.exposure_ns;
  delivered.assign(num_frames_, 1);
  exposure_ns.assign(num_frames_, 0);
  delivered_frames_ = num_frames_ > 0 ? 1 : 0;
  if (num_frames_ > 0) exposure_ns[0] = trajectory_.FrameTimeNs(0);
  // Its own stream of the seed, one drop and one jitter draw per frame whatever the settings:
  // changing the drop probability does not move the jitter, nor anything else drawn.
  sim::Rng rng(config.sim.seed * 6364136223846793005u + 1442695040888963407u);
  const double sigma_ns = config.sim.timestamp_jitter_ms * 1e6;
  for (std::int32_t k = 1; k < num_frames_; ++k) {
    const double u = rng.Uniform();
    const double g = std::clamp(rng.Gaussian(), -4.0, 4.0);  // stamps stay in order
    delivered[k] = u < config.sim.frame_drop_probability ? 0 : 1;
    delivered_frames_ += delivered[k];
    exposure_ns[k] = trajectory_.FrameTimeNs(k) + std::llround(g * sigma_ns);
  }
}

void SimWorld::DrawMotionInputs(const app::FswConfig& config) {
  // The simulated IMU, drawn once from the seed: same configuration, same motion inputs.
  imu_ = config.sim.imu;
  motion_.assign(num_frames_, drivers::MotionInput{});
  std::mt19937_64 rng(config.sim.seed * 7919u + 17u);
  std::normal_distribution<double> gauss(0.0, 1.0);
  estimator::Pose<double> since_delivered;  // the measured motion since the last frame served
  for (std::int32_t k = 1; k < num_frames_; ++k) {
    const estimator::Pose<double> u =
        trajectory_.WorldTCamera(k - 1).Inverse() * trajectory_.WorldTCamera(k);
    Eigen::Vector3d dt;
    Eigen::Vector3d dr;
    for (int i = 0; i < 3; ++i) dt[i] = config.sim.imu_sigma_m * gauss(rng);
    for (int i = 0; i < 3; ++i) dr[i] = config.sim.imu_sigma_rad * gauss(rng);
    const estimator::Pose<double> measured{Eigen::Matrix3d(u.R * estimator::ExpSO3<double>(dr)),
                                           Eigen::Vector3d(u.t + dt)};
    // After a dropped frame the input spans every interval since the frame before the gap, as an
    // IMU integrates through it.
    since_delivered = frames_.delivered[k - 1] != 0 ? measured : since_delivered * measured;
    const Eigen::AngleAxisd aa(since_delivered.R);
    const Eigen::Vector3d rv = aa.angle() * aa.axis();
    for (int i = 0; i < 3; ++i) {
      motion_[k].translation_m[i] = since_delivered.t[i];
      motion_[k].rotation_rad[i] = rv[i];
    }
  }
}

bool SimWorld::RenderAll(int threads, void (*progress)(int done, int total), std::string* error) {
  if (sim::RenderDescent(terrain_, appearance_, renderer_, trajectory_, threads, progress,
                         &frames_) != Status::kOk) {
    *error = "sim: rendering failed";
    return false;
  }
  // Fault injection: the camera blinded (black pairs) over inject.black_*.
  for (std::int64_t k = black_from_; k >= 0 && k < black_from_ + black_frames_ && k < num_frames_;
       ++k) {
    std::fill(frames_.left[k].begin(), frames_.left[k].end(), std::uint8_t{0});
    std::fill(frames_.right[k].begin(), frames_.right[k].end(), std::uint8_t{0});
  }
  return true;
}

bool SimImuUnit(const app::FswConfig& config, sim::ImuModelOptions* unit) {
  if (config.sim.imu_unit == "none") return false;
  *unit = config.sim.imu_unit == "tactical" ? sim::TacticalImu() : sim::MemsImu();
  // Its own stream of the seed: the unit's errors do not change when the scene does.
  unit->seed = config.sim.seed * 104729u + 3u;
  unit->clock_offset_s = config.sim.imu_clock_offset_ms * 1e-3;
  const app::ImuConfig& c = config.imu;
  unit->camera_T_imu.t =
      Eigen::Vector3d(c.camera_t_imu_m[0], c.camera_t_imu_m[1], c.camera_t_imu_m[2]);
  unit->camera_T_imu.R = estimator::ExpSO3<double>(
      Eigen::Vector3d(c.camera_r_imu_rad[0], c.camera_r_imu_rad[1], c.camera_r_imu_rad[2]));
  return true;
}

namespace {

// The IMU's velocity at the first frame: the camera's plus the lever arm turning at the
// trajectory's body rate (the jitter's own rate, 0.1 deg-sized, is left out).
estimator::Vec3<double> TrueImuVelocityAtStart(const sim::Trajectory& truth,
                                               const estimator::Vec3<double>& lever_m) {
  const sim::TrajectoryOptions& o = truth.Options();
  return o.velocity_world_mps + truth.WorldTCamera(0).R * o.body_rate_radps.cross(lever_m);
}

}  // namespace

app::ImuOptions SimImuOptions(const app::FswConfig& c, const sim::Trajectory* truth) {
  app::ImuOptions o = app::ImuOptionsFor(c);
  sim::ImuModelOptions unit;
  if (SimImuUnit(c, &unit)) {
    o.noise = sim::NoiseModelOf(unit);
    o.stream.gyro_range_radps = unit.gyro.range;
    o.stream.accel_range_mps2 = unit.accel.range;
    o.gravity_world_mps2 = estimator::Vec3<double>(0.0, 0.0, -unit.gravity_mps2);
    // The unit's own spread at start: turn-on offset and the in-run term's stationary sigma.
    o.first_gyro_bias_sigma_radps =
        std::hypot(unit.gyro.turn_on_bias_sigma, unit.gyro.bias_instability);
    o.first_accel_bias_sigma_mps2 =
        std::hypot(unit.accel.turn_on_bias_sigma, unit.accel.bias_instability);
    o.stream.nominal_period_us = std::max<std::int64_t>(1, std::llround(1e6 / unit.rate_hz));
  }
  if (truth != nullptr) {
    const double* lever = c.imu.camera_t_imu_m;
    o.initial_velocity_world_mps =
        TrueImuVelocityAtStart(*truth, estimator::Vec3<double>(lever[0], lever[1], lever[2]));
  }
  return o;
}

void SimHandover(const app::FswConfig& config, const sim::Trajectory& truth,
                 app::PipelineOptions* po) {
  po->imu = SimImuOptions(config, &truth);
  po->initial_world_T_camera = truth.WorldTCamera(0);
  if (config.sim.handover_error != "drawn") return;
  // Its own stream of the seed, as the IMU unit's: the draw does not change with the scene.
  sim::Rng rng(config.sim.seed * 7919u + 11u);
  estimator::Vec6<double> pose_error;
  for (int i = 0; i < 3; ++i) pose_error(i) = po->swf.first_pose_sigma_m * rng.Gaussian();
  for (int i = 3; i < 6; ++i) pose_error(i) = po->swf.first_pose_sigma_rad * rng.Gaussian();
  // The estimator's first state: the IMU's pose with the IMU, the camera's without.
  const estimator::Pose<double> state_T_camera =
      po->imu.enabled ? po->imu.imu_T_camera : estimator::Pose<double>::Identity();
  const estimator::Pose<double> world_T_state =
      (po->initial_world_T_camera * state_T_camera.Inverse()).Retract(pose_error);
  po->initial_world_T_camera = world_T_state * state_T_camera;
  if (!po->imu.enabled) return;
  for (int i = 0; i < 3; ++i) {
    po->imu.initial_velocity_world_mps(i) += po->imu.first_velocity_sigma_mps * rng.Gaussian();
  }
}

bool SimWorld::NextImu(std::int64_t until_utime, estimator::ImuSample<double>* sample) {
  return imu_samples_.NextImu(until_utime, sample);
}

bool SimWorld::Motion(std::uint64_t seq, drivers::MotionInput* input) {
  if (!imu_ || seq == 0 || seq >= motion_.size()) return false;
  *input = motion_[seq];
  return true;
}

}  // namespace swf::sil
