// Hazard-mapping evaluation against simulator truth (see hazard_eval.hpp).
#include "swf/hazard_eval/hazard_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

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

FrameMetrics World::Evaluate(const hazard::HazardMapper& m, double altitude_m) const {
  FrameMetrics r;
  r.altitude_m = altitude_m;
  r.cell_m = m.CellM();
  const int n = m.GridCells();
  const double cell = m.CellM();
  const double tcell = terrain_.CellM();
  const int tn = terrain_.Size();
  const auto node_of = [&](double x, double y, int* i, int* j) {
    *i = static_cast<int>(std::lround((x - terrain_.NodeX(0)) / tcell));
    *j = static_cast<int>(std::lround((y - terrain_.NodeY(0)) / tcell));
    return *i >= 0 && *j >= 0 && *i < tn && *j < tn;
  };
  // Max truth rock height within radius of (x, y).
  const auto max_rock_near = [&](double x, double y, double radius) {
    int ci = 0;
    int cj = 0;
    node_of(x, y, &ci, &cj);
    const int rn = static_cast<int>(std::ceil(radius / tcell));
    float best = 0.0f;
    for (int j = std::max(0, cj - rn); j <= std::min(tn - 1, cj + rn); ++j) {
      for (int i = std::max(0, ci - rn); i <= std::min(tn - 1, ci + rn); ++i) {
        if (std::hypot(terrain_.NodeX(i) - x, terrain_.NodeY(j) - y) > radius) continue;
        best = std::max(best, truth_.rock_height_m[static_cast<std::size_t>(j) * tn + i]);
      }
    }
    return best;
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      if (std::isnan(m.Elevation()[c])) continue;
      ++r.known_cells;
      const double x = m.CornerX() + (i + 0.5) * cell;
      const double y = m.CornerY() + (j + 0.5) * cell;
      // Truth: mean height over the cell (4 x 4 samples).
      double mean = 0.0;
      for (int b = 0; b < 4; ++b) {
        for (int a = 0; a < 4; ++a) {
          mean += terrain_.HeightAt(x + (a - 1.5) * cell / 4.0, y + (b - 1.5) * cell / 4.0);
        }
      }
      mean /= 16.0;
      r.elevation_errors_m.push_back(std::fabs(m.Elevation()[c] - mean));
      r.elevation_sigmas_m.push_back(m.Sigma()[c]);
      int ti = 0;
      int tj = 0;
      if (!std::isnan(m.SlopeDeg()[c]) && node_of(x, y, &ti, &tj)) {
        r.slope_errors_deg.push_back(
            std::fabs(m.SlopeDeg()[c] - truth_.slope_deg[static_cast<std::size_t>(tj) * tn + ti]));
      }
      const bool rock_near =
          max_rock_near(x, y, 0.5 * cell + 0.3) >= 0.5 * options_.max_rock_height_m;
      const bool is_rock = m.Classes()[c] == hazard::HazardClass::kRock;
      r.rock_cells += is_rock;
      if (!rock_near) {
        ++r.rock_free_cells;
        r.false_rock_cells += is_rock;
      }
    }
  }
  for (const sim::Rock& rock : terrain_.Rocks()) {
    if (rock.height_m < options_.max_rock_height_m) continue;
    int ci = 0;
    int cj = 0;
    if (!m.CellOf(rock.center_m.x(), rock.center_m.y(), &ci, &cj)) continue;
    // In view = inside the part of the map precise enough to resolve the threshold (the
    // mapper's own criterion: sigma <= threshold / 3); elsewhere a rock can only be kUncertain.
    const float sigma = m.Sigma()[static_cast<std::size_t>(cj) * n + ci];
    if (!(sigma * 3.0 <= options_.max_rock_height_m)) continue;
    ++r.rocks_in_view;
    const double radius = 0.5 * rock.diameter_m + cell;
    const int rc = static_cast<int>(std::ceil(radius / cell));
    bool found = false;
    bool flagged = false;
    for (int j = std::max(0, cj - rc); j <= std::min(n - 1, cj + rc); ++j) {
      for (int i = std::max(0, ci - rc); i <= std::min(n - 1, ci + rc); ++i) {
        const double x = m.CornerX() + (i + 0.5) * cell;
        const double y = m.CornerY() + (j + 0.5) * cell;
        if (std::hypot(x - rock.center_m.x(), y - rock.center_m.y()) > radius) continue;
        const hazard::HazardClass k = m.Classes()[static_cast<std::size_t>(j) * n + i];
        found = found || k == hazard::HazardClass::kRock;
        flagged =
            flagged || k == hazard::HazardClass::kRock || k == hazard::HazardClass::kUncertain;
      }
    }
    r.rocks_detected += found;
    r.rocks_flagged += flagged;
  }
  const hazard::SafeSite& site = m.Site();
  r.site_valid = site.valid;
  if (site.valid) {
    const double search = options_.footprint_radius_m + 10.0;
    int ci = 0;
    int cj = 0;
    node_of(site.position_world_m.x(), site.position_world_m.y(), &ci, &cj);
    const int rn = static_cast<int>(std::ceil(search / tcell));
    double nearest = search;
    for (int j = std::max(0, cj - rn); j <= std::min(tn - 1, cj + rn); ++j) {
      for (int i = std::max(0, ci - rn); i <= std::min(tn - 1, ci + rn); ++i) {
        if (truth_.hazard[static_cast<std::size_t>(j) * tn + i] == 0) continue;
        nearest = std::min(nearest, std::hypot(terrain_.NodeX(i) - site.position_world_m.x(),
                                               terrain_.NodeY(j) - site.position_world_m.y()));
      }
    }
    r.site_clearance_m = nearest;
    r.site_on_hazard = nearest < options_.footprint_radius_m;
  }
  return r;
}

void RenderHazardMap(const hazard::HazardMapper& m, int scale, std::vector<std::uint8_t>* rgb,
                     int* width, int* height) {
  const int n = m.GridCells();
  const double cell = m.CellM();
  *width = n * scale;
  *height = n * scale;
  rgb->assign(static_cast<std::size_t>(*width) * *height * 3, 0);
  const auto elev = [&](int i, int j) {
    i = std::clamp(i, 0, n - 1);
    j = std::clamp(j, 0, n - 1);
    return m.Elevation()[static_cast<std::size_t>(j) * n + i];
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      double r = 20;
      double g = 30;
      double b = 70;  // unknown
      if (!std::isnan(m.Elevation()[c])) {
        float ex = elev(i + 1, j) - elev(i - 1, j);
        float ey = elev(i, j + 1) - elev(i, j - 1);
        if (std::isnan(ex)) ex = 0.0f;
        if (std::isnan(ey)) ey = 0.0f;
        // Lambertian hill shade, light from the north-west, 45 deg elevation.
        const Eigen::Vector3d normal =
            Eigen::Vector3d(-ex / (2 * cell), -ey / (2 * cell), 1.0).normalized();
        const Eigen::Vector3d light = Eigen::Vector3d(-1.0, 1.0, 1.414).normalized();
        const double shade = 0.25 + 0.75 * std::max(0.0, normal.dot(light));
        double tr = 1.0;
        double tg = 1.0;
        double tb = 1.0;
        switch (m.Classes()[c]) {
          case hazard::HazardClass::kSafe:
            tr = 0.75;
            tg = 1.0;
            tb = 0.75;
            break;
          case hazard::HazardClass::kUncertain:
            tr = 1.0;
            tg = 0.9;
            tb = 0.3;
            break;
          case hazard::HazardClass::kSlope:
            tr = 1.0;
            tg = 0.55;
            tb = 0.1;
            break;
          case hazard::HazardClass::kRock:
            tr = 1.0;
            tg = 0.1;
            tb = 0.1;
            break;
          case hazard::HazardClass::kUnknown:
            tr = 0.6;
            tg = 0.6;
            tb = 0.8;
            break;
        }
        r = 255.0 * shade * tr;
        g = 255.0 * shade * tg;
        b = 255.0 * shade * tb;
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
  const hazard::SafeSite& site = m.Site();
  if (!site.valid) return;
  const double px = (site.position_world_m.x() - m.CornerX()) / cell * scale;
  const double py = *height - (site.position_world_m.y() - m.CornerY()) / cell * scale;
  const double rad = m.Options().footprint_radius_m / cell * scale;
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

core::Status WriteHazardMapPng(const hazard::HazardMapper& mapper, const std::string& path) {
  std::vector<std::uint8_t> rgb;
  int w = 0;
  int h = 0;
  RenderHazardMap(mapper, 2, &rgb, &w, &h);
  return sim::WritePng(path, rgb.data(), w, h, 3, w * 3);
}

}  // namespace swf::hazard_eval
