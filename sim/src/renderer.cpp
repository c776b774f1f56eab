#include "swf/sim/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "lanes.hpp"
#include "swf/sim/rng.hpp"

namespace swf::sim {
namespace {

using V4f = Terrain::V4f;
using V4i = Terrain::V4i;

using lanes::SqrtLanes;

V4f LoadLanes(const float* p) {
  V4f v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// 4096 values (16 KB) stay in the L1 cache; a 64 K table (256 KB) missed it on every pixel.
constexpr std::size_t kGaussianTableSize = 1u << 12;
constexpr std::int32_t kTile = 8;  // pixels per side of a tile sharing one height range
constexpr int kRangeRounds = 4;    // box / height-range refinements per tile
// Rotated-grid 2x2 supersampling offsets (pixels).
constexpr double kSubPixel[4][2] = {
    {-0.125, -0.375}, {0.375, -0.125}, {0.125, 0.375}, {-0.375, 0.125}};

}  // namespace

core::Status Renderer::Configure(const RenderOptions& options) {
  configured_ = false;
  if (ValidateRig(options.rig) != core::Status::kOk ||
      (options.samples_per_pixel != 1 && options.samples_per_pixel != 4) ||
      !(options.exposure_dn > 0.0) || !(options.electrons_per_dn > 0.0) ||
      !(options.read_noise_e >= 0.0) || !std::isfinite(options.baseline_error_m) ||
      !(options.rig.baseline_m + options.baseline_error_m > 0.0) ||
      !options.right_rotation_error_rad.allFinite()) {
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
  RenderCamera(terrain, appearance, world_T_camera.R,
               world_T_camera.Apply(Eigen::Vector3d(0.0, 0.0, 0.0)), 0, frame_index, out);
  // The true right camera: the rig's, moved by the calibration error. Without a rotation error
  // the left attitude itself (not a product with an identity, which could flip the sign of a
  // zero entry): a rig without error renders bit-identically to the calibrated one.
  const Eigen::Vector3d right_center = world_T_camera.Apply(
      Eigen::Vector3d(camera_.baseline_m + options_.baseline_error_m, 0.0, 0.0));
  if ((options_.right_rotation_error_rad.array() == 0.0).all()) {
    RenderCamera(terrain, appearance, world_T_camera.R, right_center, 1, frame_index, out);
  } else {
    const Eigen::Matrix3d right_r =
        world_T_camera.R * estimator::ExpSO3<double>(options_.right_rotation_error_rad);
    RenderCamera(terrain, appearance, right_r, right_center, 1, frame_index, out);
  }
  return core::Status::kOk;
}

void Renderer::RenderCamera(const Terrain& terrain, const Appearance& appearance,
                            const Eigen::Matrix3d& r, const Eigen::Vector3d& center,
                            int camera_index, std::uint64_t frame_index, StereoImages* out) const {
  const std::int32_t w = options_.rig.width_px;
  const std::int32_t h = options_.rig.height_px;
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
  const double pad_m = 0.01 * terrain.CellM();

  // The first hit of every ray of a tile of pixels lies, by induction, at a height in [lo, hi]
  // (at first the terrain's lowest and highest heights), so in the box spanned by the tile's
  // corner rays between lo and hi (the rays of the tile are positive combinations of the corner
  // rays); the height range of the max/min pyramid over that box is then a tighter [lo, hi].
  // A few rounds shrink box and range together; the rays of the tile walk only that stretch
  // (Terrain::IntersectBetween).
  // inside: the box of the last round lies at least a cell inside the terrain, so no ray of the
  // tile needs clipping to the terrain's extent (Terrain::IntersectSpan directly).
  struct TileRange {
    double lo = 0.0;
    double hi = 0.0;
    bool inside = false;
  };
  const double half_extent_m = terrain.HalfExtentM() - terrain.CellM();
  auto tile_range = [&](std::int32_t u0, std::int32_t v0, std::int32_t u1, std::int32_t v1) {
    TileRange range{bottom_m, top_m, false};
    Eigen::Vector3d corner[4];
    int c = 0;
    for (const double cu : {u0 - 0.5, u1 + 0.5}) {
      for (const double cv : {v0 - 0.5, v1 + 0.5}) {
        corner[c] =
            r * Eigen::Vector3d((cu - camera_.cx) * inv_fx, (cv - camera_.cy) * inv_fy, 1.0);
        if (!(corner[c].z() < 0.0)) return range;  // a corner looks up: no useful box
        ++c;
      }
    }
    for (int round = 0; round < kRangeRounds; ++round) {
      double x_lo = std::numeric_limits<double>::max();
      double y_lo = x_lo;
      double x_hi = -x_lo;
      double y_hi = -x_lo;
      for (const Eigen::Vector3d& d : corner) {
        for (const double z : {range.hi, range.lo}) {
          const double s = std::max(0.0, (center.z() - z) / -d.z());
          x_lo = std::min(x_lo, center.x() + s * d.x());
          x_hi = std::max(x_hi, center.x() + s * d.x());
          y_lo = std::min(y_lo, center.y() + s * d.y());
          y_hi = std::max(y_hi, center.y() + s * d.y());
        }
      }
      range.inside = x_lo > -half_extent_m && x_hi < half_extent_m && y_lo > -half_extent_m &&
                     y_hi < half_extent_m;
      double box_lo = 0.0;
      double box_hi = 0.0;
      terrain.HeightRangeInBox(x_lo - pad_m, y_lo - pad_m, x_hi + pad_m, y_hi + pad_m, &box_lo,
                               &box_hi);
      if (box_lo <= range.lo && box_hi >= range.hi) break;  // no progress
      range.lo = std::max(range.lo, box_lo);
      range.hi = std::min(range.hi, box_hi);
    }
    return range;
  };
  // The first hit of the ray center + t d (d.z() < 0 inside a tile whose corners look down).
  const double inv_cell = 1.0 / terrain.CellM();
  const double gx0 = (center.x() - terrain.NodeX(0)) * inv_cell;
  const double gy0 = (center.y() - terrain.NodeY(0)) * inv_cell;
  const double height_pad_m = 1e-3 * terrain.CellM();  // as Terrain::IntersectBetween
  auto cast = [&](const Eigen::Vector3d& d, const TileRange& tile, double* t) {
    if (!tile.inside) return terrain.IntersectBetween(center, d, tile.hi, tile.lo, t);
    const double inv_descent = -1.0 / d.z();
    const double ta = std::max(0.0, (center.z() - tile.hi - height_pad_m) * inv_descent);
    const double tb = (center.z() - tile.lo + height_pad_m) * inv_descent;
    const Terrain::GridRay ray{gx0, gy0, d.x() * inv_cell, d.y() * inv_cell, center.z(), d.z()};
    return terrain.IntersectSpan(ray, ta, tb, t);
  };

  // Everything the pixel loop reads, in locals: the 8-bit image stores may alias any object, so
  // members read through `this` would be reloaded after every store.
  const bool add_noise = options_.add_noise;
  const bool one_sample = options_.samples_per_pixel == 1;
  const bool plain = options_.fiducials.empty();
  const double exposure_dn = options_.exposure_dn;
  const float* gaussian = gaussian_table_.data();
  std::uint8_t* const pixels = image.data();
  float* const depth_out = camera_index == 0 ? out->depth_m.data() : nullptr;
  float* const disparity_out = camera_index == 0 ? out->disparity_px.data() : nullptr;
  const auto disparity_numerator_f = static_cast<float>(disparity_numerator);
  const double cx = camera_.cx;
  const double cy = camera_.cy;
  const Eigen::Vector3d col_x = r.col(0);
  const Eigen::Vector3d col_y = r.col(1);
  const Eigen::Vector3d col_z = r.col(2);
  // cast for the four rays of pixels u .. u + 3 of a row in a tile inside the terrain, in single
  // precision (Terrain::IntersectSpan4; grid positions relative to the node under the camera);
  // a ray that needs the pyramid walk is cast again by cast.
  Terrain::GridRays4 rays4{};
  rays4.base_i = static_cast<std::int32_t>(std::floor(gx0));
  rays4.base_j = static_cast<std::int32_t>(std::floor(gy0));
  rays4.gx0 = static_cast<float>(gx0 - rays4.base_i);
  rays4.gy0 = static_cast<float>(gy0 - rays4.base_j);
  rays4.oz = static_cast<float>(center.z());
  const V4f lanes = {0.0f, 1.0f, 2.0f, 3.0f};
  const auto inv_fx_f = static_cast<float>(inv_fx);
  auto cast4 = [&](std::int32_t u, const Eigen::Vector3d& row, const TileRange& tile, double* t) {
    const V4f xn = (static_cast<float>(u - cx) + lanes) * inv_fx_f;
    const Eigen::Vector3d row_g = row * inv_cell;
    const Eigen::Vector3d col_g = col_x * inv_cell;
    rays4.dgx = static_cast<float>(col_g.x()) * xn + static_cast<float>(row_g.x());
    rays4.dgy = static_cast<float>(col_g.y()) * xn + static_cast<float>(row_g.y());
    rays4.dz = static_cast<float>(col_x.z()) * xn + static_cast<float>(row.z());
    const V4f inv_descent = -1.0f / rays4.dz;
    const V4f ta = static_cast<float>(center.z() - tile.hi - height_pad_m) * inv_descent;
    rays4.ta = ta > 0.0f ? ta : V4f{0.0f, 0.0f, 0.0f, 0.0f};
    rays4.tb = static_cast<float>(center.z() - tile.lo + height_pad_m) * inv_descent;
    V4f hit;
    V4i walk;
    terrain.IntersectSpan4(rays4, &hit, &walk);
    for (int k = 0; k < 4; ++k) {
      if (walk[k] == 0) {
        t[k] = hit[k];  // NaN stays NaN
        continue;
      }
      const Eigen::Vector3d dir = col_x * ((u + k - cx) * inv_fx) + row;
      double tk = 0.0;
      t[k] = cast(dir, tile, &tk) ? tk : std::numeric_limits<double>::quiet_NaN();
    }
  };
  auto shade = [&](const Eigen::Vector3d& p, double footprint_m) {
    return plain ? appearance.Radiance(p.x(), p.y(), footprint_m)
                 : Shade(appearance, p, footprint_m);
  };

  // A tile in three passes (rays, shading, noise and output), so that the long dependency chain
  // of one pixel (ray root, texture, noise) overlaps with its neighbours' in the CPU.
  double hit_t[kTile * kTile];
  double tile_dn[kTile * kTile];
  // Plain ground, one sample per pixel: the hit points' texture four at a time
  // (Appearance::Radiance4) after the shading pass has gathered them.
  double hit_x[kTile * kTile];
  double hit_y[kTile * kTile];
  double footprint[kTile * kTile];
  const bool four_points = one_sample && plain;
  auto render_tile = [&](std::int32_t u0, std::int32_t v0, std::int32_t u1, std::int32_t v1,
                         const TileRange& tile) {
    const std::int32_t tw = u1 - u0 + 1;
    for (std::int32_t v = v0; v <= v1; ++v) {
      const double yn = (v - cy) * inv_fy;
      const Eigen::Vector3d row = col_y * yn + col_z;
      std::int32_t u = u0;
      if (tile.inside) {  // four rays at a time
        for (; u + 3 <= u1; u += 4) cast4(u, row, tile, &hit_t[(v - v0) * tw + (u - u0)]);
      }
      for (; u <= u1; ++u) {
        const Eigen::Vector3d dir = col_x * ((u - cx) * inv_fx) + row;  // r * (xn, yn, 1)
        double t = 0.0;
        // The camera-frame ray has z == 1: t is the camera-frame depth.
        hit_t[(v - v0) * tw + (u - u0)] = cast(dir, tile, &t) ? t : nan;
      }
    }
    for (std::int32_t v = v0; v <= v1; ++v) {
      const double yn = (v - cy) * inv_fy;
      const Eigen::Vector3d row = col_y * yn + col_z;
      for (std::int32_t u = u0; u <= u1; ++u) {
        const std::int32_t q = (v - v0) * tw + (u - u0);
        const double t = hit_t[q];
        tile_dn[q] = 0.0;
        if (!(t == t)) continue;  // NaN: no hit
        const double xn = (u - cx) * inv_fx;
        const Eigen::Vector3d dir = col_x * xn + row;
        // Single precision where the result is only a filter width, a noise sigma or a float:
        // the divider is a bottleneck (sqrt and division are exact in IEEE, so deterministic
        // either way).
        const double footprint_m =
            t * std::sqrt(static_cast<float>(xn * xn + yn * yn + 1.0)) * inv_fx;
        double radiance = 0.0;
        if (four_points) {  // the texture below, four points at a time
          const Eigen::Vector3d p = center + t * dir;
          hit_x[q] = p.x();
          hit_y[q] = p.y();
          footprint[q] = footprint_m;
          continue;
        }
        if (one_sample) {
          radiance = shade(center + t * dir, footprint_m);
        } else {
          for (const auto& offset : kSubPixel) {
            const Eigen::Vector3d sub = dir + offset[0] * step + offset[1] * step_v;
            double ts = 0.0;
            if (cast(sub, tile, &ts)) {
              radiance += 0.25 * shade(center + ts * sub, 0.5 * footprint_m);
            }
          }
        }
        tile_dn[q] = exposure_dn * radiance;
      }
    }
    if (four_points) {
      const std::int32_t n = tw * (v1 - v0 + 1);
      for (std::int32_t q = 0; q < n; q += 4) {
        const std::int32_t m = std::min<std::int32_t>(4, n - q);
        double x[4];
        double y[4];
        double f[4];
        for (std::int32_t k = 0; k < 4; ++k) {
          // Misses (and lanes past the end) sample a valid point; their result is dropped.
          const bool use = k < m && hit_t[q + k] == hit_t[q + k];
          x[k] = use ? hit_x[q + k] : center.x();
          y[k] = use ? hit_y[q + k] : center.y();
          f[k] = use ? footprint[q + k] : 1.0;
        }
        double radiance[4];
        appearance.Radiance4(x, y, f, radiance);
        for (std::int32_t k = 0; k < m; ++k) {
          if (hit_t[q + k] == hit_t[q + k]) tile_dn[q + k] = exposure_dn * radiance[k];
        }
      }
    }
    for (std::int32_t v = v0; v <= v1; ++v) {
      for (std::int32_t u = u0; u <= u1; ++u) {
        const std::int32_t q = (v - v0) * tw + (u - u0);
        const size_t k = static_cast<size_t>(v) * w + u;
        double dn = tile_dn[q];
        if (add_noise) {
          const double sigma =
              std::sqrt(static_cast<float>(read_var + std::max(0.0, dn) * inv_e_per_dn));
          const std::uint64_t hash = Mix64(noise_key ^ k);
          dn += sigma * gaussian[hash & (kGaussianTableSize - 1)];
        }
        // Round half up after clamping (the value is non-negative there).
        pixels[k] = static_cast<std::uint8_t>(std::clamp(dn, 0.0, 255.0) + 0.5);
        if (depth_out != nullptr) {
          const double depth = hit_t[q];
          depth_out[k] = static_cast<float>(depth);
          disparity_out[k] = disparity_numerator_f / static_cast<float>(depth);
        }
      }
    }
  };

  // Plain ground, one sample per pixel, a tile inside the terrain whose rows split into groups of
  // four pixels (all tiles of a 1024x768 image): rays, texture, noise and output in 4-lane
  // single-precision vectors, one pixel per lane, with hit points in grid units relative to the
  // node under the camera (Appearance::Radiance4Grid on the terrain's grid).
  const bool vector_tiles = four_points && appearance.OriginM() == terrain.NodeX(0) &&
                            appearance.CellM() == terrain.CellM();
  const auto exposure_f = static_cast<float>(exposure_dn);
  const auto read_var_f = static_cast<float>(read_var);
  const auto inv_e_per_dn_f = static_cast<float>(inv_e_per_dn);
  const float* const gaussian_table = gaussian;
  float tile_t[kTile * kTile];
  // Rays of the tile that cross into a neighbour cell and miss the first one: their second cells
  // are solved four at a time after the tile's rays (instead of one mostly empty vector per group
  // that has any).
  std::int32_t pending_q[kTile * kTile];
  V4f pending_ray[kTile * kTile];  // dgx, dgy, dz, tb
  float pending_t0[kTile * kTile];
  std::int32_t pending_i[kTile * kTile];
  std::int32_t pending_j[kTile * kTile];
  auto render_tile_vector = [&](std::int32_t u0, std::int32_t v0, std::int32_t u1, std::int32_t v1,
                                const TileRange& tile) {
    const std::int32_t tw = u1 - u0 + 1;
    const float ta_num = static_cast<float>(center.z() - tile.hi - height_pad_m);
    const float tb_num = static_cast<float>(center.z() - tile.lo + height_pad_m);
    const Eigen::Vector3d col_g = col_x * inv_cell;
    const auto col_gx = static_cast<float>(col_g.x());
    const auto col_gy = static_cast<float>(col_g.y());
    const auto col_gz = static_cast<float>(col_x.z());
    const V4f zero = {0.0f, 0.0f, 0.0f, 0.0f};
    std::int32_t pending = 0;
    for (std::int32_t v = v0; v <= v1; ++v) {
      const double yn = (v - cy) * inv_fy;
      const Eigen::Vector3d row = col_y * yn + col_z;
      const Eigen::Vector3d row_g = row * inv_cell;
      for (std::int32_t u = u0; u <= u1; u += 4) {
        const std::int32_t q = (v - v0) * tw + (u - u0);
        // As cast4.
        const V4f xn = (static_cast<float>(u - cx) + lanes) * inv_fx_f;
        rays4.dgx = col_gx * xn + static_cast<float>(row_g.x());
        rays4.dgy = col_gy * xn + static_cast<float>(row_g.y());
        rays4.dz = col_gz * xn + static_cast<float>(row.z());
        const V4f inv_descent = -1.0f / rays4.dz;
        const V4f ta = ta_num * inv_descent;
        rays4.ta = ta > 0.0f ? ta : zero;
        rays4.tb = tb_num * inv_descent;
        V4f hit;
        V4i walk;
        Terrain::SecondCells4 second;
        terrain.IntersectSpan4(rays4, &hit, &walk, &second);
        std::memcpy(&tile_t[q], &hit, sizeof(hit));
        const V4i special = walk | second.pending;
        if (!(special[0] | special[1] | special[2] | special[3])) continue;
        for (int k = 0; k < 4; ++k) {
          if (walk[k] != 0) {
            const Eigen::Vector3d dir = col_x * ((u + k - cx) * inv_fx) + row;
            double tk = 0.0;
            tile_t[q + k] = cast(dir, tile, &tk) ? static_cast<float>(tk)
                                                 : std::numeric_limits<float>::quiet_NaN();
          } else if (second.pending[k] != 0) {
            pending_q[pending] = q + k;
            pending_ray[pending] = V4f{rays4.dgx[k], rays4.dgy[k], rays4.dz[k], rays4.tb[k]};
            pending_t0[pending] = second.t0[k];
            pending_i[pending] = second.i[k];
            pending_j[pending] = second.j[k];
            ++pending;
          }
        }
      }
    }
    for (std::int32_t p = 0; p < pending; p += 4) {
      Terrain::GridRays4 packed = rays4;  // origin and base node
      Terrain::SecondCells4 cells{};
      for (int k = 0; k < 4; ++k) {
        const std::int32_t e = std::min(p + k, pending - 1);  // spare lanes repeat the last ray
        packed.dgx[k] = pending_ray[e][0];
        packed.dgy[k] = pending_ray[e][1];
        packed.dz[k] = pending_ray[e][2];
        packed.tb[k] = pending_ray[e][3];
        cells.i[k] = pending_i[e];
        cells.j[k] = pending_j[e];
        cells.t0[k] = pending_t0[e];
      }
      const V4f later = terrain.IntersectSecondCells4(packed, cells);
      for (std::int32_t k = 0; k < 4 && p + k < pending; ++k) tile_t[pending_q[p + k]] = later[k];
    }
    // Texture, noise and output, four pixels at a time.
    const V4f gx0_f = {rays4.gx0, rays4.gx0, rays4.gx0, rays4.gx0};
    const V4f gy0_f = {rays4.gy0, rays4.gy0, rays4.gy0, rays4.gy0};
    for (std::int32_t v = v0; v <= v1; ++v) {
      const double yn = (v - cy) * inv_fy;
      const Eigen::Vector3d row = col_y * yn + col_z;
      const Eigen::Vector3d row_g = row * inv_cell;
      const auto yn_f = static_cast<float>(yn);
      const float stretch_y = yn_f * yn_f + 1.0f;
      for (std::int32_t u = u0; u <= u1; u += 4) {
        const std::int32_t q = (v - v0) * tw + (u - u0);
        const size_t k0 = static_cast<size_t>(v) * w + u;
        const V4f t = LoadLanes(&tile_t[q]);
        const V4i hit = t == t;  // NaN: no hit
        const V4f xn = (static_cast<float>(u - cx) + lanes) * inv_fx_f;
        const V4f dgx = col_gx * xn + static_cast<float>(row_g.x());
        const V4f dgy = col_gy * xn + static_cast<float>(row_g.y());
        // Ground size of a pixel: range t |(xn, yn, 1)| over fx. Misses sample the node under
        // the camera (a valid point); their result is dropped.
        const V4f footprint = t * SqrtLanes(xn * xn + stretch_y) * inv_fx_f;
        const V4f gx = hit != 0 ? gx0_f + t * dgx : zero;
        const V4f gy = hit != 0 ? gy0_f + t * dgy : zero;
        const V4f f = hit != 0 ? footprint : V4f{1.0f, 1.0f, 1.0f, 1.0f};
        const V4f radiance = appearance.Radiance4Grid(rays4.base_i, rays4.base_j, gx, gy, f);
        V4f dn = hit != 0 ? exposure_f * radiance : zero;
        if (add_noise) {
          const V4f sigma = SqrtLanes(read_var_f + (dn > zero ? dn : zero) * inv_e_per_dn_f);
          V4f g;
          for (int k = 0; k < 4; ++k) {
            g[k] = gaussian_table[Mix64(noise_key ^ (k0 + k)) & (kGaussianTableSize - 1)];
          }
          dn += sigma * g;
        }
        // Round half up after clamping (the value is non-negative there).
        dn = dn < zero ? zero : dn;
        dn = dn > 255.0f ? V4f{255.0f, 255.0f, 255.0f, 255.0f} : dn;
        const V4i level = __builtin_convertvector(dn + 0.5f, V4i);
        for (int k = 0; k < 4; ++k) pixels[k0 + k] = static_cast<std::uint8_t>(level[k]);
        if (depth_out != nullptr) {
          const V4f disparity = disparity_numerator_f / t;
          std::memcpy(&depth_out[k0], &t, sizeof(t));
          std::memcpy(&disparity_out[k0], &disparity, sizeof(disparity));
        }
      }
    }
  };

  for (std::int32_t v0 = 0; v0 < h; v0 += kTile) {
    const std::int32_t v1 = std::min(h, v0 + kTile) - 1;
    for (std::int32_t u0 = 0; u0 < w; u0 += kTile) {
      const std::int32_t u1 = std::min(w, u0 + kTile) - 1;
      const TileRange tile = tile_range(u0, v0, u1, v1);
      if (vector_tiles && tile.inside && (u1 - u0 + 1) % 4 == 0) {
        render_tile_vector(u0, v0, u1, v1, tile);
      } else {
        render_tile(u0, v0, u1, v1, tile);
      }
    }
  }
}

}  // namespace swf::sim
