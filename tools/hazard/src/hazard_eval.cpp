// Hazard-mapping evaluation against simulator truth (see hazard_eval.hpp).
#include "swf/hazard_eval/hazard_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "swf/app/hazard_stage.hpp"
#include "swf/sim/appearance.hpp"
#include "swf/sim/image_io.hpp"
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

void RenderHazardMap(const HazardMapView& m, double footprint_radius_m, int scale,
                     std::vector<std::uint8_t>* rgb, int* width, int* height) {
  const int n = m.cells_per_side;
  const double cell = m.cell_m;
  *width = n * scale;
  *height = n * scale;
  rgb->assign(static_cast<std::size_t>(*width) * *height * 3, 0);
  const auto elev = [&](int i, int j) {
    i = std::clamp(i, 0, n - 1);
    j = std::clamp(j, 0, n - 1);
    return m.elevation_m[static_cast<std::size_t>(j) * n + i];
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      double r = 20;
      double g = 30;
      double b = 70;  // unknown
      if (!std::isnan(m.elevation_m[c])) {
        float ex = elev(i + 1, j) - elev(i - 1, j);
        float ey = elev(i, j + 1) - elev(i, j - 1);
        if (std::isnan(ex)) ex = 0.0f;
        if (std::isnan(ey)) ey = 0.0f;
        // Lambertian hill shade, light from the north-west, 45 deg elevation.
        const Eigen::Vector3d normal =
            Eigen::Vector3d(-ex / (2 * cell), -ey / (2 * cell), 1.0).normalized();
        const Eigen::Vector3d light = Eigen::Vector3d(-1.0, 1.0, 1.414).normalized();
        const double shade = 0.25 + 0.75 * std::max(0.0, normal.dot(light));
        // The tint of each published class code (app::HazardClassCode); other codes untinted.
        struct Tint {
          hazard::HazardClass hazard_class;
          double rgb[3];
        };
        static constexpr Tint kTints[] = {
            {hazard::HazardClass::kSafe, {0.75, 1.0, 0.75}},
            {hazard::HazardClass::kUncertain, {1.0, 0.9, 0.3}},
            {hazard::HazardClass::kSlope, {1.0, 0.55, 0.1}},
            {hazard::HazardClass::kRock, {1.0, 0.1, 0.1}},
            {hazard::HazardClass::kUnknown, {0.6, 0.6, 0.8}},
        };
        static constexpr double kUntinted[3] = {1.0, 1.0, 1.0};
        const double* tint = kUntinted;
        for (const Tint& t : kTints) {
          if (m.hazard_class[c] == app::HazardClassCode(t.hazard_class)) tint = t.rgb;
        }
        r = 255.0 * shade * tint[0];
        g = 255.0 * shade * tint[1];
        b = 255.0 * shade * tint[2];
      }
      for (int y = 0; y < scale; ++y) {
        const int py = (n - 1 - j) * scale + y;  // north up
        for (int x = 0; x < scale; ++x) {
          std::uint8_t* p =
              rgb->data() + (static_cast<std::size_t>(py) * *width + i * scale + x) * 3;
          p[0] = static_cast<std::uint8_t>(std::clamp(r, 0.0, 255.0));
          p[1] = static_cast<std::uint8_t>(std::clamp(g, 0.0, 255.0));
          p[2] = static_cast<std::uint8_t>(std::clamp(b, 0.0, 255.0));
        }
      }
    }
  }
  if (!m.site_valid) return;
  const double px = (m.site_world_m[0] - m.origin_world_m[0]) / cell * scale;
  const double py = *height - (m.site_world_m[1] - m.origin_world_m[1]) / cell * scale;
  const double rad = footprint_radius_m / cell * scale;
  const auto put = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= *width || y >= *height) return;
    std::uint8_t* p = rgb->data() + (static_cast<std::size_t>(y) * *width + x) * 3;
    p[0] = p[1] = p[2] = 255;
  };
  for (int k = 0; k < 720; ++k) {
    const double a = k * M_PI / 360.0;
    put(static_cast<int>(px + rad * std::cos(a)), static_cast<int>(py + rad * std::sin(a)));
  }
  const int arm = std::max(3, static_cast<int>(rad / 3));
  for (int d = -arm; d <= arm; ++d) {
    put(static_cast<int>(px) + d, static_cast<int>(py));
    put(static_cast<int>(px), static_cast<int>(py) + d);
  }
}

core::Status WriteHazardMapPng(const HazardMapView& map, double footprint_radius_m,
                               const std::string& path) {
  std::vector<std::uint8_t> rgb;
  int w = 0;
  int h = 0;
  RenderHazardMap(map, footprint_radius_m, 2, &rgb, &w, &h);
  return sim::WritePng(path, rgb.data(), w, h, 3, w * 3);
}

}  // namespace swf::hazard_eval
