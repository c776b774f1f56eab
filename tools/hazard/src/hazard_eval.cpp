// Hazard-mapping evaluation against simulator truth (see hazard_eval.hpp).
#include "swf/hazard_eval/hazard_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "swf/app/hazard_stage.hpp"
#include "swf/sim/appearance.hpp"
#include "swf/sim/rng.hpp"

namespace swf::hazard_eval {

core::Status World::Configure(sim::TerrainPreset preset, std::uint64_t seed, const EvalOptions& o,
                              std::string* error) {
  std::string unused;
  std::string& why = error != nullptr ? *error : unused;
  options_ = o;
  sim::TerrainOptions to = sim::TerrainPresetOptions(preset, seed);
  to.size = o.terrain_size;
  to.largest_wavelength_m = std::min(to.largest_wavelength_m, o.terrain_size * to.cell_m);
  if (core::Status s = terrain_.Configure(to); s != core::Status::kOk) {
    why = "the terrain generator refuses a terrain of " + std::to_string(o.terrain_size) +
          " nodes (" + core::ToString(s) + ")";
    return s;
  }
  const sim::AppearanceOptions imagery = sim::DefaultImagery(o.shared_dir);
  if (core::Status s = appearance_.Configure(terrain_, imagery); s != core::Status::kOk) {
    why = "cannot build the surface appearance from " + imagery.intensity_image_path + ", " +
          imagery.mask_image_path + " and " + imagery.global_albedo_path + " (" +
          core::ToString(s) + "; --shared or SWF_SHARED_DIR must name the shared folder)";
    return s;
  }
  sim::RenderOptions ro;
  ro.rig = sim::EdlRig();
  ro.rig.width_px = o.image_width;
  ro.rig.height_px = o.image_height;
  ro.seed = seed;
  if (core::Status s = renderer_.Configure(ro); s != core::Status::kOk) {
    why = "the renderer refuses a " + std::to_string(o.image_width) + "x" +
          std::to_string(o.image_height) + " px image (" + core::ToString(s) + ")";
    return s;
  }
  sim::HazardOptions ho;
  ho.max_rock_height_m = o.max_rock_height_m;
  ho.max_slope_deg = o.max_slope_deg;
  ho.slope_baseline_m = 2.0 * o.footprint_radius_m;
  const core::Status s = sim::ComputeHazardTruth(terrain_, ho, &truth_);
  if (s != core::Status::kOk) why = std::string("hazard truth failed (") + core::ToString(s) + ")";
  return s;
}

hazard::HazardMapperOptions World::MapperOptions() const {
  hazard::HazardMapperOptions m;
  m.camera = renderer_.Camera();
  m.image_width = options_.image_width;
  m.image_height = options_.image_height;
  m.downsample = options_.downsample;
  m.footprint_radius_m = options_.footprint_radius_m;
  m.max_rock_height_m = options_.max_rock_height_m;
  m.max_slope_deg = options_.max_slope_deg;
  return m;
}

core::Status World::Step(const estimator::Pose<double>& world_T_camera, std::uint64_t frame,
                         std::uint64_t rng_seed, hazard::HazardMapper* mapper, double* update_ms,
                         const Eigen::Matrix<double, 6, 1>* pose_error,
                         const Eigen::Matrix<double, 6, 6>* pose_covariance) {
  if (core::Status s = renderer_.Render(terrain_, appearance_, world_T_camera, frame, &images_);
      s != core::Status::kOk) {
    return s;
  }
  sim::Rng rng(rng_seed);
  const double altitude =
      world_T_camera.t.z() - terrain_.HeightAt(world_T_camera.t.x(), world_T_camera.t.y());
  const double sp = options_.pose_sigma_per_altitude * std::max(altitude, 1.0);
  const double sa = options_.attitude_sigma_deg * M_PI / 180.0;
  Eigen::Matrix<double, 6, 1> sig;
  sig << sp, sp, sp, sa, sa, sa;
  Eigen::Matrix<double, 6, 1> delta;
  for (int k = 0; k < 6; ++k) delta[k] = sig[k] * rng.Gaussian();
  hazard::HazardFrame f;
  if (pose_error != nullptr && pose_covariance != nullptr) {
    f.world_T_camera = world_T_camera.Retract(*pose_error);
    f.pose_covariance = *pose_covariance;
  } else {
    f.world_T_camera = world_T_camera.Retract(delta);
    f.pose_covariance = sig.cwiseProduct(sig).asDiagonal();
  }
  // Landmarks: true surface points at random pixels, with stereo-like noise (0.3 px).
  const estimator::StereoCamera<double>& cam = renderer_.Camera();
  landmarks_.clear();
  for (int k = 0; k < options_.num_landmarks; ++k) {
    const int u = static_cast<int>(rng.UniformInt(0, images_.width - 1));
    const int v = static_cast<int>(rng.UniformInt(0, images_.height - 1));
    const float z = images_.depth_m[static_cast<std::size_t>(v) * images_.width + u];
    if (!std::isfinite(z)) continue;
    const Eigen::Vector3d pc(z * (u - cam.cx) / cam.fx, z * (v - cam.cy) / cam.fy, z);
    const Eigen::Vector3d pw = world_T_camera.Apply(pc);
    const double sz = static_cast<double>(z) * z * 0.3 / (cam.fx * cam.baseline_m);
    const double sl = static_cast<double>(z) * 0.3 / cam.fx;
    hazard::HazardLandmark l;
    l.position_world_m =
        pw + Eigen::Vector3d(sl * rng.Gaussian(), sl * rng.Gaussian(), sz * rng.Gaussian());
    l.covariance = Eigen::Vector3d(sl * sl, sl * sl, sz * sz).asDiagonal();
    landmarks_.push_back(l);
  }
  f.landmarks = landmarks_.data();
  f.num_landmarks = static_cast<int>(landmarks_.size());
  f.left = frontend::GrayView{images_.left.data(), images_.width, images_.height, images_.width};
  f.right = frontend::GrayView{images_.right.data(), images_.width, images_.height, images_.width};
  const auto t0 = std::chrono::steady_clock::now();
  const core::Status s = mapper->Update(f);
  const auto t1 = std::chrono::steady_clock::now();
  if (update_ms != nullptr) {
    *update_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  }
  return s;
}

core::Status World::Publish(const hazard::HazardMapper& mapper) {
  const std::int32_t cells = mapper.GridCells() * mapper.GridCells();
  if (cells > published_.capacity_cells) {
    if (core::Status s = published_.Allocate(cells); s != core::Status::kOk) return s;
  }
  return app::FillHazardRecord(mapper, &published_);
}

core::Status World::Evaluate(const hazard::HazardMapper& mapper, HazardMapMetrics* metrics) {
  if (core::Status s = Publish(mapper); s != core::Status::kOk) return s;
  MetricOptions o;
  o.max_rock_height_m = options_.max_rock_height_m;
  o.footprint_radius_m = options_.footprint_radius_m;
  *metrics = EvaluateHazardMap(ViewOf(published_), terrain_, terrain_.Rocks(), truth_, o);
  return core::Status::kOk;
}

}  // namespace swf::hazard_eval
