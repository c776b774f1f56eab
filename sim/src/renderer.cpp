#include "swf/sim/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "swf/sim/rng.hpp"

namespace swf::sim {
namespace {

constexpr std::size_t kGaussianTableSize = 1u << 16;
constexpr std::int32_t kTile = 16;  // pixels per side of a tile sharing one ray start height
// Rotated-grid 2x2 supersampling offsets (pixels).
constexpr double kSubPixel[4][2] = {
    {-0.125, -0.375}, {0.375, -0.125}, {0.125, 0.375}, {-0.375, 0.125}};

}  // namespace

core::Status Renderer::Configure(const RenderOptions& options) {
  configured_ = false;
  if (ValidateRig(options.rig) != core::Status::kOk ||
      (options.samples_per_pixel != 1 && options.samples_per_pixel != 4) ||
      !(options.exposure_dn > 0.0) || !(options.electrons_per_dn > 0.0) ||
      !(options.read_noise_e >= 0.0)) {
    return core::Status::kInvalidArgument;
  }
  for (const Fiducial& f : options.fiducials) {
    if (!(f.sigma_m > 0.0) || !f.center_m.allFinite()) return core::Status::kInvalidArgument;
  }
  options_ = options;
  camera_ = MakeStereoCamera(options.rig);
  Rng rng(options.seed ^ 0x5A17E5EEDull);
  gaussian_table_.resize(kGaussianTableSize);
  for (float& g : gaussian_table_) g = static_cast<float>(rng.Gaussian());
  configured_ = true;
  return core::Status::kOk;
}

double Renderer::Shade(const Appearance& appearance, const Eigen::Vector3d& p,
                       double footprint_m) const {
  double radiance = appearance.Radiance(p.x(), p.y(), footprint_m);
  for (const Fiducial& f : options_.fiducials) {
    const double dx = p.x() - f.center_m.x();
    const double dy = p.y() - f.center_m.y();
    const double r2 = dx * dx + dy * dy;
    if (r2 < 25.0 * f.sigma_m * f.sigma_m) {
      radiance *= 1.0 - f.contrast * std::exp(-r2 / (2.0 * f.sigma_m * f.sigma_m));
    }
  }
  return radiance;
}

core::Status Renderer::Render(const Terrain& terrain, const Appearance& appearance,
                              const estimator::Pose<double>& world_T_camera,
                              std::uint64_t frame_index, StereoImages* out) const {
  if (!configured_) return core::Status::kNotConfigured;
  if (appearance.Size() != terrain.Size() || out == nullptr) return core::Status::kInvalidArgument;
  const std::int32_t w = options_.rig.width_px;
  const std::int32_t h = options_.rig.height_px;
  const size_t n = static_cast<size_t>(w) * h;
  if (out->width != w || out->height != h || out->left.size() != n) {
    out->width = w;
    out->height = h;
    out->left.assign(n, 0);
    out->right.assign(n, 0);
    out->depth_m.assign(n, 0.0f);
    out->disparity_px.assign(n, 0.0f);
  }
  RenderCamera(terrain, appearance, world_T_camera, 0, frame_index, out);
  RenderCamera(terrain, appearance, world_T_camera, 1, frame_index, out);
  return core::Status::kOk;
}

void Renderer::RenderCamera(const Terrain& terrain, const Appearance& appearance,
                            const estimator::Pose<double>& world_T_camera, int camera_index,
                            std::uint64_t frame_index, StereoImages* out) const {
  const std::int32_t w = options_.rig.width_px;
  const std::int32_t h = options_.rig.height_px;
  const Eigen::Matrix3d& r = world_T_camera.R;
  const Eigen::Vector3d center =
      world_T_camera.Apply(Eigen::Vector3d(camera_index * camera_.baseline_m, 0.0, 0.0));
  const double inv_fx = 1.0 / camera_.fx;
  const double inv_fy = 1.0 / camera_.fy;
  const double read_sigma_dn = options_.read_noise_e / options_.electrons_per_dn;
  const double read_var = read_sigma_dn * read_sigma_dn;
  const double inv_e_per_dn = 1.0 / options_.electrons_per_dn;
  const std::uint64_t noise_key =
      Mix64(options_.seed ^ Mix64(frame_index * 2u + static_cast<std::uint64_t>(camera_index)));
  std::vector<std::uint8_t>& image = camera_index == 0 ? out->left : out->right;
  const double nan = std::numeric_limits<double>::quiet_NaN();

  const double disparity_numerator = camera_.fx * camera_.baseline_m;
  // Per pixel the camera ray is (xn, yn, 1) with xn = (u - cx) / fx; a sub-pixel offset moves its
  // world direction along these steps.
  const Eigen::Vector3d step = r.col(0) * inv_fx;
  const Eigen::Vector3d step_v = r.col(1) * inv_fy;
  const double top_m = terrain.MaxHeightM();
  const double bottom_m = terrain.MinHeightM();
  const double pad_m = 2.0 * terrain.CellM();

  // The ground a tile of pixels can see lies in the box spanned by its corner rays between the
  // terrain's lowest and highest heights; the rays of the tile start below that box's highest
  // block instead of the global maximum (Terrain::IntersectBelow).
  auto tile_top = [&](std::int32_t u0, std::int32_t v0, std::int32_t u1, std::int32_t v1) {
    double x_lo = std::numeric_limits<double>::max();
    double y_lo = x_lo;
    double x_hi = -x_lo;
    double y_hi = -x_lo;
    for (const double cu : {u0 - 0.5, u1 + 0.5}) {
      for (const double cv : {v0 - 0.5, v1 + 0.5}) {
        const Eigen::Vector3d d =
            r * Eigen::Vector3d((cu - camera_.cx) * inv_fx, (cv - camera_.cy) * inv_fy, 1.0);
        if (!(d.z() < 0.0)) return top_m;  // a corner looks up: no useful box
        for (const double z : {top_m, bottom_m}) {
          const double s = std::max(0.0, (center.z() - z) / -d.z());
          x_lo = std::min(x_lo, center.x() + s * d.x());
          x_hi = std::max(x_hi, center.x() + s * d.x());
          y_lo = std::min(y_lo, center.y() + s * d.y());
          y_hi = std::max(y_hi, center.y() + s * d.y());
        }
      }
    }
    return terrain.MaxHeightInBox(x_lo - pad_m, y_lo - pad_m, x_hi + pad_m, y_hi + pad_m);
  };

  auto render_pixel = [&](std::int32_t u, std::int32_t v, double tile_top_m) {
    const size_t k = static_cast<size_t>(v) * w + u;
    const double xn = (u - camera_.cx) * inv_fx;
    const double yn = (v - camera_.cy) * inv_fy;
    const Eigen::Vector3d dir = r * Eigen::Vector3d(xn, yn, 1.0);
    double t = 0.0;
    double dn = 0.0;
    double depth = nan;
    if (terrain.IntersectBelow(center, dir, tile_top_m, &t)) {
      depth = t;  // the camera-frame ray has z == 1: t is the camera-frame depth
      const double footprint_m = t * std::sqrt(xn * xn + yn * yn + 1.0) * inv_fx;
      double radiance = 0.0;
      if (options_.samples_per_pixel == 1) {
        radiance = Shade(appearance, center + t * dir, footprint_m);
      } else {
        for (const auto& offset : kSubPixel) {
          const Eigen::Vector3d sub = dir + offset[0] * step + offset[1] * step_v;
          double ts = 0.0;
          if (terrain.IntersectBelow(center, sub, tile_top_m, &ts)) {
            radiance += 0.25 * Shade(appearance, center + ts * sub, 0.5 * footprint_m);
          }
        }
      }
      dn = options_.exposure_dn * radiance;
    }
    if (options_.add_noise) {
      const double sigma = std::sqrt(read_var + std::max(0.0, dn) * inv_e_per_dn);
      const std::uint64_t hash = Mix64(noise_key ^ k);
      dn += sigma * gaussian_table_[hash & (kGaussianTableSize - 1)];
    }
    // Round half up after clamping (the value is non-negative there).
    image[k] = static_cast<std::uint8_t>(std::clamp(dn, 0.0, 255.0) + 0.5);
    if (camera_index == 0) {
      out->depth_m[k] = static_cast<float>(depth);
      out->disparity_px[k] = static_cast<float>(disparity_numerator / depth);
    }
  };

  for (std::int32_t v0 = 0; v0 < h; v0 += kTile) {
    const std::int32_t v1 = std::min(h, v0 + kTile) - 1;
    for (std::int32_t u0 = 0; u0 < w; u0 += kTile) {
      const std::int32_t u1 = std::min(w, u0 + kTile) - 1;
      const double tile_top_m = tile_top(u0, v0, u1, v1);
      for (std::int32_t v = v0; v <= v1; ++v) {
        for (std::int32_t u = u0; u <= u1; ++u) render_pixel(u, v, tile_top_m);
      }
    }
  }
}

}  // namespace swf::sim
