#include "swf/sim/terrain.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <numbers>

#include "lanes.hpp"
#include "swf/sim/rng.hpp"

namespace swf::sim {
namespace {

double LatticeValue(std::uint64_t key, std::int64_t ix, std::int64_t iy) {
  const std::uint64_t h =
      Mix64(key ^ Mix64(static_cast<std::uint64_t>(ix) * 0x9E3779B97F4A7C15ull ^
                        static_cast<std::uint64_t>(iy) * 0xC2B2AE3D27D4EB4Full));
  return static_cast<double>(h >> 11) * 0x1.0p-52 - 1.0;  // [-1, 1)
}

// Adds amplitude * value noise of the given wavelength (in cells) to the grid.
void AddValueNoiseOctave(std::int32_t size, double wavelength_cells, double amplitude,
                         std::uint64_t key, std::vector<double>* grid) {
  const auto lattice_n = static_cast<std::int32_t>(std::ceil(size / wavelength_cells)) + 2;
  std::vector<double> lattice(static_cast<size_t>(lattice_n) * lattice_n);
  for (std::int32_t b = 0; b < lattice_n; ++b) {
    for (std::int32_t a = 0; a < lattice_n; ++a)
      lattice[b * lattice_n + a] = LatticeValue(key, a, b);
  }
  const double inv = 1.0 / wavelength_cells;
  for (std::int32_t j = 0; j < size; ++j) {
    const double gy = j * inv;
    const auto b = static_cast<std::int32_t>(gy);
    double fy = gy - b;
    fy = fy * fy * (3.0 - 2.0 * fy);
    for (std::int32_t i = 0; i < size; ++i) {
      const double gx = i * inv;
      const auto a = static_cast<std::int32_t>(gx);
      double fx = gx - a;
      fx = fx * fx * (3.0 - 2.0 * fx);
      const double* row0 = &lattice[b * lattice_n + a];
      const double* row1 = row0 + lattice_n;
      const double top = row0[0] + fx * (row0[1] - row0[0]);
      const double bottom = row1[0] + fx * (row1[1] - row1[0]);
      (*grid)[static_cast<size_t>(j) * size + i] += amplitude * (top + fy * (bottom - top));
    }
  }
}

double CraterProfile(const Crater& c, double r) {
  const double radius = 0.5 * c.diameter_m;
  const double s = r / radius;
  if (s <= 1.0) return c.rim_height_m + c.depth_m * (s * s - 1.0);
  if (s >= 3.0) return 0.0;
  constexpr double kTail = 1.0 / 27.0;
  return c.rim_height_m * (1.0 / (s * s * s) - kTail) / (1.0 - kTail);
}

// Each preset: its name, relief, crater population and rock abundance.
struct PresetRow {
  TerrainPreset preset;
  const char* name;
  double relief_rms_m;
  double crater_density_at_1m;
  double crater_max_diameter_m;
  double rock_k;
};
constexpr PresetRow kPresets[] = {
    {TerrainPreset::kSmoothPlains, "plains", 0.3, 0.004, 10.0, 0.005},
    {TerrainPreset::kCraterField, "craters", 0.5, 0.08, 40.0, 0.03},
    // Rock-rich, between Viking Lander 1 (k ~0.07) and 2 (~0.18).
    {TerrainPreset::kRockField, "rocks", 0.3, 0.01, 15.0, 0.15},
};

}  // namespace

TerrainOptions TerrainPresetOptions(TerrainPreset preset, std::uint64_t seed) {
  TerrainOptions o;
  o.seed = seed;
  for (const PresetRow& row : kPresets) {
    if (row.preset != preset) continue;
    o.relief_rms_m = row.relief_rms_m;
    o.craters.density_at_1m = row.crater_density_at_1m;
    o.craters.max_diameter_m = row.crater_max_diameter_m;
    o.rocks.k = row.rock_k;
  }
  return o;
}

TerrainOptions ScaleTerrain(const TerrainOptions& options, double factor) {
  TerrainOptions o = options;
  o.cell_m *= factor;
  o.relief_rms_m *= factor;
  o.largest_wavelength_m *= factor;
  o.craters.min_diameter_m *= factor;
  o.craters.max_diameter_m *= factor;
  // N'(>D') = N(>D'/f) / f^2 = C f^(b-2) D'^-b.
  o.craters.density_at_1m *= std::pow(factor, o.craters.sfd_exponent - 2.0);
  o.rocks.size_scale *= factor;
  return o;
}

bool ParseTerrainPreset(const char* name, TerrainPreset* preset) {
  for (const PresetRow& row : kPresets) {
    if (std::strcmp(name, row.name) != 0) continue;
    *preset = row.preset;
    return true;
  }
  return false;
}

core::Status Terrain::Configure(const TerrainOptions& o) {
  const CraterOptions& co = o.craters;
  const RockOptions& ro = o.rocks;
  const bool ok = o.size >= 8 && o.size <= 16384 && o.cell_m > 0.0 && std::isfinite(o.cell_m) &&
                  std::isfinite(o.tilt_x) && std::isfinite(o.tilt_y) && o.relief_rms_m >= 0.0 &&
                  o.relief_hurst >= 0.0 && o.relief_hurst <= 2.0 && o.largest_wavelength_m > 0.0 &&
                  co.density_at_1m >= 0.0 && co.sfd_exponent > 0.0 && co.min_diameter_m > 0.0 &&
                  co.min_diameter_m <= co.max_diameter_m && co.depth_ratio >= 0.0 &&
                  co.rim_ratio >= 0.0 && co.min_freshness >= 0.0 && co.min_freshness <= 1.0 &&
                  ro.k >= 0.0 && ro.k < 1.0 && ro.min_diameter_m > 0.0 &&
                  ro.min_diameter_m <= ro.max_diameter_m && ro.height_ratio > 0.0 &&
                  ro.size_scale > 0.0;
  if (!ok) return core::Status::kInvalidArgument;
  options_ = o;
  size_ = o.size;
  origin_m_ = -0.5 * (size_ - 1) * o.cell_m;
  inv_cell_m_ = 1.0 / o.cell_m;
  const size_t n = static_cast<size_t>(size_) * size_;
  std::vector<double> h(n, 0.0);
  Rng rng(o.seed);

  // Multi-scale relief.
  if (o.relief_rms_m > 0.0) {
    std::vector<double> relief(n, 0.0);
    std::uint64_t octave_key = rng.Bits();
    for (double wavelength_m = o.largest_wavelength_m; wavelength_m >= 4.0 * o.cell_m;
         wavelength_m *= 0.5) {
      AddValueNoiseOctave(size_, wavelength_m / o.cell_m, std::pow(wavelength_m, o.relief_hurst),
                          octave_key, &relief);
      octave_key = Mix64(octave_key);
    }
    double mean = 0.0;
    for (double v : relief) mean += v;
    mean /= static_cast<double>(n);
    double var = 0.0;
    for (double v : relief) var += (v - mean) * (v - mean);
    const double rms = std::sqrt(var / static_cast<double>(n));
    const double scale = rms > 0.0 ? o.relief_rms_m / rms : 0.0;
    for (size_t k = 0; k < n; ++k) h[k] = (relief[k] - mean) * scale;
  }
  for (std::int32_t j = 0; j < size_; ++j) {
    for (std::int32_t i = 0; i < size_; ++i) {
      h[static_cast<size_t>(j) * size_ + i] += o.tilt_x * NodeX(i) + o.tilt_y * NodeY(j);
    }
  }

  const double extent_m = (size_ - 1) * o.cell_m;
  const double area_m2 = extent_m * extent_m;

  // Craters: truncated power-law SFD, sampled by inverting its CDF.
  craters_.clear();
  if (co.density_at_1m > 0.0) {
    const double b = co.sfd_exponent;
    const double lo = std::pow(co.min_diameter_m, -b);
    const double hi = std::pow(co.max_diameter_m, -b);
    const auto count = std::llround(area_m2 * co.density_at_1m * (lo - hi));
    craters_.reserve(static_cast<size_t>(count));
    for (std::int64_t c = 0; c < count; ++c) {
      Crater crater;
      crater.diameter_m = std::pow(lo - rng.Uniform() * (lo - hi), -1.0 / b);
      crater.center_m = {rng.Uniform(origin_m_, -origin_m_), rng.Uniform(origin_m_, -origin_m_)};
      const double freshness = rng.Uniform(co.min_freshness, 1.0);
      crater.depth_m = co.depth_ratio * crater.diameter_m * freshness;
      crater.rim_height_m = co.rim_ratio * crater.diameter_m * freshness;
      craters_.push_back(crater);
    }
    for (const Crater& c : craters_) {
      const double reach = 1.5 * c.diameter_m;
      ForEachNodeNear(c.center_m, reach, [&](std::int32_t i, std::int32_t j) {
        const double r = std::hypot(NodeX(i) - c.center_m.x(), NodeY(j) - c.center_m.y());
        h[static_cast<size_t>(j) * size_ + i] += CraterProfile(c, r);
      });
    }
  }
  base_heights_.assign(h.begin(), h.end());
  heights_ = base_heights_;

  // Rocks: Golombek-Rapp number density n(D) = 4 q k exp(-q D) / (pi D^2), tabulated CDF.
  rocks_.clear();
  if (ro.k > 0.0) {
    const double q = 1.79 + 0.152 / ro.k;
    constexpr int kBins = 4096;
    std::vector<double> cdf(kBins + 1, 0.0);
    const double d_lo = ro.min_diameter_m;
    const double step = (ro.max_diameter_m - d_lo) / kBins;
    auto density = [&](double d) {
      return 4.0 * q * ro.k * std::exp(-q * d) / (std::numbers::pi * d * d);
    };
    for (int b = 1; b <= kBins; ++b) {
      const double d0 = d_lo + (b - 1) * step;
      cdf[b] = cdf[b - 1] + 0.5 * step * (density(d0) + density(d0 + step));
    }
    // Areas scale with size_scale^2 while counts per model area are fixed.
    const double model_area_m2 = area_m2 / (ro.size_scale * ro.size_scale);
    const auto count = std::llround(model_area_m2 * cdf[kBins]);
    rocks_.reserve(static_cast<size_t>(count));
    for (std::int64_t r = 0; r < count; ++r) {
      const double target = rng.Uniform() * cdf[kBins];
      const auto it = std::upper_bound(cdf.begin(), cdf.end(), target);
      const auto b = std::clamp<std::int64_t>(it - cdf.begin(), 1, kBins);
      const double frac = (target - cdf[b - 1]) / std::max(1e-300, cdf[b] - cdf[b - 1]);
      Rock rock;
      rock.diameter_m = (d_lo + (b - 1 + frac) * step) * ro.size_scale;
      rock.height_m = ro.height_ratio * rock.diameter_m;
      rock.center_m = {rng.Uniform(origin_m_, -origin_m_), rng.Uniform(origin_m_, -origin_m_)};
      rock.base_z_m = GridHeight((rock.center_m.x() - origin_m_) / o.cell_m,
                                 (rock.center_m.y() - origin_m_) / o.cell_m);
      rocks_.push_back(rock);
    }
    for (const Rock& rock : rocks_) {
      const double radius = 0.5 * rock.diameter_m;
      ForEachNodeNear(rock.center_m, radius, [&](std::int32_t i, std::int32_t j) {
        const double dx = NodeX(i) - rock.center_m.x();
        const double dy = NodeY(j) - rock.center_m.y();
        const double s2 = (dx * dx + dy * dy) / (radius * radius);
        if (s2 >= 1.0) return;
        const auto top = static_cast<float>(rock.base_z_m + rock.height_m * std::sqrt(1.0 - s2));
        float& cell = heights_[static_cast<size_t>(j) * size_ + i];
        cell = std::max(cell, top);
      });
    }
  }

  // Bounds for ray casting: per-block minima and maxima over the block's nodes (borders shared).
  blocks_ = (size_ - 1 + kBlock - 1) / kBlock;
  block_max_.assign(static_cast<size_t>(blocks_) * blocks_, -std::numeric_limits<float>::max());
  block_min_.assign(static_cast<size_t>(blocks_) * blocks_, std::numeric_limits<float>::max());
  min_height_m_ = std::numeric_limits<double>::max();
  max_height_m_ = -std::numeric_limits<double>::max();
  for (std::int32_t j = 0; j < size_; ++j) {
    for (std::int32_t i = 0; i < size_; ++i) {
      const float v = heights_[static_cast<size_t>(j) * size_ + i];
      min_height_m_ = std::min(min_height_m_, static_cast<double>(v));
      max_height_m_ = std::max(max_height_m_, static_cast<double>(v));
      const std::int32_t bx_lo = std::max(0, (i - 1) / kBlock);
      const std::int32_t bx_hi = std::min(blocks_ - 1, i / kBlock);
      const std::int32_t by_lo = std::max(0, (j - 1) / kBlock);
      const std::int32_t by_hi = std::min(blocks_ - 1, j / kBlock);
      for (std::int32_t by = by_lo; by <= by_hi; ++by) {
        for (std::int32_t bx = bx_lo; bx <= bx_hi; ++bx) {
          const size_t b = static_cast<size_t>(by) * blocks_ + bx;
          block_max_[b] = std::max(block_max_[b], v);
          block_min_[b] = std::min(block_min_[b], v);
        }
      }
    }
  }
  supers_ = (blocks_ + kSuper - 1) / kSuper;
  super_max_.assign(static_cast<size_t>(supers_) * supers_, -std::numeric_limits<float>::max());
  super_min_.assign(static_cast<size_t>(supers_) * supers_, std::numeric_limits<float>::max());
  for (std::int32_t by = 0; by < blocks_; ++by) {
    for (std::int32_t bx = 0; bx < blocks_; ++bx) {
      const size_t s = static_cast<size_t>(by / kSuper) * supers_ + bx / kSuper;
      const size_t b = static_cast<size_t>(by) * blocks_ + bx;
      super_max_[s] = std::max(super_max_[s], block_max_[b]);
      super_min_[s] = std::min(super_min_[s], block_min_[b]);
    }
  }
  return core::Status::kOk;
}

std::int32_t Terrain::FirstNodeFrom(double coordinate_m) const {
  return std::max<std::int32_t>(
      0, static_cast<std::int32_t>(std::floor((coordinate_m - origin_m_) / options_.cell_m)));
}

std::int32_t Terrain::LastNodeTo(double coordinate_m) const {
  return std::min<std::int32_t>(
      size_ - 1,
      static_cast<std::int32_t>(std::ceil((coordinate_m - origin_m_) / options_.cell_m)));
}

double Terrain::GridHeight(double gx, double gy) const {
  const double max_g = size_ - 1;
  gx = std::clamp(gx, 0.0, max_g);
  gy = std::clamp(gy, 0.0, max_g);
  const std::int32_t i = std::min(static_cast<std::int32_t>(gx), size_ - 2);
  const std::int32_t j = std::min(static_cast<std::int32_t>(gy), size_ - 2);
  const double fx = gx - i;
  const double fy = gy - j;
  const float* p = &heights_[static_cast<size_t>(j) * size_ + i];
  const double h00 = p[0];
  const double h10 = p[1];
  const double h01 = p[size_];
  const double h11 = p[size_ + 1];
  const double top = h00 + fx * (h10 - h00);
  const double bottom = h01 + fx * (h11 - h01);
  return top + fy * (bottom - top);
}

double Terrain::HeightAt(double x_m, double y_m) const {
  return GridHeight((x_m - origin_m_) / options_.cell_m, (y_m - origin_m_) / options_.cell_m);
}

namespace {

// Per-ray constants of the Amanatides-Woo walks: border crossing parameters per grid unit.
struct WalkRay {
  double gx0, gy0, inv_dgx, inv_dgy;
  std::int32_t step_i, step_j, ahead_i, ahead_j;  // ahead: 1 when the next border is above
};

// Walk over one level of the max pyramid: the cell (i, j) of `cells` grid units per side the ray
// is in, and the parameters where it crosses the next x and y borders.
struct LevelWalk {
  std::int32_t i = 0;
  std::int32_t j = 0;
  std::int32_t n = 0;
  double next_x = 0.0;
  double next_y = 0.0;
  double delta_x = 0.0;
  double delta_y = 0.0;
  std::int32_t step_i = 0;
  std::int32_t step_j = 0;

  // gx, gy: the grid position just after the start (nudged past a border the ray sits on).
  LevelWalk(const WalkRay& r, double gx, double gy, std::int32_t cells, std::int32_t count)
      : n(count), step_i(r.step_i), step_j(r.step_j) {
    const double inv_cells = 1.0 / cells;
    // Truncation is floor here: positions below 0 are only rounding and clamp to 0.
    i = std::clamp(static_cast<std::int32_t>(gx * inv_cells), 0, n - 1);
    j = std::clamp(static_cast<std::int32_t>(gy * inv_cells), 0, n - 1);
    // inv_dg* is +-inf for a ray parallel to an axis: the border is never crossed.
    next_x = step_i == 0 ? r.inv_dgx : ((i + r.ahead_i) * cells - r.gx0) * r.inv_dgx;
    next_y = step_j == 0 ? r.inv_dgy : ((j + r.ahead_j) * cells - r.gy0) * r.inv_dgy;
    delta_x = cells * std::abs(r.inv_dgx);
    delta_y = cells * std::abs(r.inv_dgy);
  }
  double Exit() const { return std::min(next_x, next_y); }
  // Steps into the next cell; false when that leaves the grid.
  bool Advance() {
    if (next_x < next_y) {
      i += step_i;
      next_x += delta_x;
      return i >= 0 && i < n;
    }
    j += step_j;
    next_y += delta_y;
    return j >= 0 && j < n;
  }
};

}  // namespace

inline bool Terrain::IntersectCell(const GridRay& ray, std::int32_t i, std::int32_t j, double t0,
                                   double t1, double* t) const {
  const float* p = &heights_[static_cast<size_t>(j) * size_ + i];
  const double h00 = p[0];
  const double h10 = p[1];
  const double h01 = p[size_];
  const double h11 = p[size_ + 1];
  // The ray is lowest at t1 (dz < 0); a bilinear patch is highest at a corner.
  if (ray.oz + t1 * ray.dz > std::max(std::max(h00, h10), std::max(h01, h11))) return false;
  // With tau = t - t0 and local coordinates fx = fx0 + dgx tau, fy = fy0 + dgy tau the gap
  // z(tau) - h(tau) = g0 + g1 tau + g2 tau^2.
  const double fx0 = ray.gx0 + t0 * ray.dgx - i;
  const double fy0 = ray.gy0 + t0 * ray.dgy - j;
  const double e10 = h10 - h00;
  const double e01 = h01 - h00;
  const double e11 = h00 - h10 - h01 + h11;
  const double g0 = (ray.oz + t0 * ray.dz) - (h00 + e10 * fx0 + e01 * fy0 + e11 * fx0 * fy0);
  if (g0 <= 0.0) {  // already at or below the surface where the ray enters this cell
    *t = t0;
    return true;
  }
  const double g1 =
      ray.dz - (e10 * ray.dgx + e01 * ray.dgy + e11 * (fx0 * ray.dgy + ray.dgx * fy0));
  const double g2 = -e11 * ray.dgx * ray.dgy;
  const double span = t1 - t0;
  const double limit = span + 1e-12 * (span + std::abs(t0));
  double tau = -1.0;
  if (g2 == 0.0) {
    if (g1 < 0.0) tau = -g0 / g1;
  } else {
    // Positive at both ends: a root needs the vertex inside the span (a dip).
    const double g_end = g0 + span * (g1 + span * g2);
    if (g_end > 0.0 && !(g2 > 0.0 && g1 < 0.0 && -g1 < 2.0 * g2 * span)) return false;
    const double disc = g1 * g1 - 4.0 * g2 * g0;
    if (disc < 0.0) return false;
    // Numerically stable pair of roots; g0 > 0 makes q != 0.
    // One division: r1 = q / g2 = q^2 / (q g2), r2 = g0 / q = g0 g2 / (q g2).
    const double q = -0.5 * (g1 + std::copysign(std::sqrt(disc), g1));
    const double inv_qg2 = 1.0 / (q * g2);
    const double r1 = q * q * inv_qg2;
    const double r2 = g0 * g2 * inv_qg2;
    const double lo = std::min(r1, r2);
    const double hi = std::max(r1, r2);
    tau = lo >= 0.0 ? lo : hi;
  }
  if (!(tau >= 0.0 && tau <= limit)) return false;
  *t = t0 + std::min(tau, span);
  return true;
}

void Terrain::HeightRangeInBox(double x0_m, double y0_m, double x1_m, double y1_m, double* lo_m,
                               double* hi_m) const {
  *lo_m = min_height_m_;
  *hi_m = max_height_m_;
  if (size_ == 0) return;
  const double to_block = 1.0 / (kBlock * options_.cell_m);
  auto index = [&](double v_m) {
    const double g = std::clamp((v_m - origin_m_) * to_block, 0.0, blocks_ - 1.0);
    return static_cast<std::int32_t>(g);
  };
  const std::int32_t bx0 = index(std::min(x0_m, x1_m));
  const std::int32_t bx1 = index(std::max(x0_m, x1_m));
  const std::int32_t by0 = index(std::min(y0_m, y1_m));
  const std::int32_t by1 = index(std::max(y0_m, y1_m));
  float top = -std::numeric_limits<float>::max();
  float bottom = std::numeric_limits<float>::max();
  if ((bx1 - bx0 + 1) * (by1 - by0 + 1) > 4 * kSuper * kSuper) {  // large box: super blocks
    for (std::int32_t sy = by0 / kSuper; sy <= by1 / kSuper; ++sy) {
      for (std::int32_t sx = bx0 / kSuper; sx <= bx1 / kSuper; ++sx) {
        top = std::max(top, super_max_[static_cast<size_t>(sy) * supers_ + sx]);
        bottom = std::min(bottom, super_min_[static_cast<size_t>(sy) * supers_ + sx]);
      }
    }
  } else {
    for (std::int32_t by = by0; by <= by1; ++by) {
      for (std::int32_t bx = bx0; bx <= bx1; ++bx) {
        top = std::max(top, block_max_[static_cast<size_t>(by) * blocks_ + bx]);
        bottom = std::min(bottom, block_min_[static_cast<size_t>(by) * blocks_ + bx]);
      }
    }
  }
  *lo_m = bottom;
  *hi_m = top;
}

bool Terrain::Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* t) const {
  return IntersectBetween(o, d, max_height_m_, min_height_m_, t);
}

bool Terrain::IntersectBetween(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double top_m,
                               double bottom_m, double* t) const {
  if (size_ == 0 || !(d.z() < 0.0)) return false;
  // Pad the height range so a perfectly flat terrain still has a non-empty interval. Divisions
  // are few (three per ray): reciprocals of the direction are reused below.
  const double pad_m = 1e-3 * options_.cell_m;
  top_m = std::min(top_m, max_height_m_);
  bottom_m = std::max(bottom_m, min_height_m_);
  const double inv_descent = -1.0 / d.z();
  double ta = std::max(0.0, (o.z() - top_m - pad_m) * inv_descent);
  double tb = (o.z() - bottom_m + pad_m) * inv_descent;
  const double inv_dx = d.x() != 0.0 ? 1.0 / d.x() : 0.0;
  const double inv_dy = d.y() != 0.0 ? 1.0 / d.y() : 0.0;
  const double lo = origin_m_;
  const double hi = -origin_m_;
  for (int axis = 0; axis < 2; ++axis) {
    if (d[axis] != 0.0) {
      const double inv = axis == 0 ? inv_dx : inv_dy;
      double t0 = (lo - o[axis]) * inv;
      double t1 = (hi - o[axis]) * inv;
      if (t0 > t1) std::swap(t0, t1);
      ta = std::max(ta, t0);
      tb = std::min(tb, t1);
    } else if (o[axis] < lo || o[axis] > hi) {
      return false;
    }
  }
  if (!(ta < tb)) return false;
  const double inv_cell = inv_cell_m_;
  GridRay ray{};
  ray.gx0 = (o.x() - origin_m_) * inv_cell;
  ray.gy0 = (o.y() - origin_m_) * inv_cell;
  ray.dgx = d.x() * inv_cell;
  ray.dgy = d.y() * inv_cell;
  ray.oz = o.z();
  ray.dz = d.z();
  return IntersectSpan(ray, ta, tb, t);
}

bool Terrain::IntersectSpan(const GridRay& ray, double ta, double tb, double* t) const {
  // Short stretches (local height bounds): the cells the segment [ta, tb] touches are read off its
  // end points; one cell, or two neighbours split where the ray crosses their border, need no walk.
  {
    const std::int32_t last = size_ - 2;
    const std::int32_t ia = std::clamp(static_cast<std::int32_t>(ray.gx0 + ta * ray.dgx), 0, last);
    const std::int32_t ib = std::clamp(static_cast<std::int32_t>(ray.gx0 + tb * ray.dgx), 0, last);
    const std::int32_t ja = std::clamp(static_cast<std::int32_t>(ray.gy0 + ta * ray.dgy), 0, last);
    const std::int32_t jb = std::clamp(static_cast<std::int32_t>(ray.gy0 + tb * ray.dgy), 0, last);
    if (ia == ib && ja == jb) return IntersectCell(ray, ia, ja, ta, tb, t);
    if (ja == jb && (ib - ia == 1 || ia - ib == 1)) {
      const double tm = std::clamp((std::max(ia, ib) - ray.gx0) * (1.0 / ray.dgx), ta, tb);
      return IntersectCell(ray, ia, ja, ta, tm, t) || IntersectCell(ray, ib, ja, tm, tb, t);
    }
    if (ia == ib && (jb - ja == 1 || ja - jb == 1)) {
      const double tm = std::clamp((std::max(ja, jb) - ray.gy0) * (1.0 / ray.dgy), ta, tb);
      return IntersectCell(ray, ia, ja, ta, tm, t) || IntersectCell(ray, ia, jb, tm, tb, t);
    }
  }
  return WalkSpan(ray, ta, tb, t);
}

namespace {

using V4f = Terrain::V4f;
using lanes::SqrtLanes;

}  // namespace

inline Terrain::V4f Terrain::IntersectCell4(const GridRays4& rays, V4i i, V4i j, V4f t0,
                                            V4f t1) const {
  // The gap z - h along the ray as in IntersectCell, with heights relative to the cell's first
  // node (node heights are floats: their differences are nearly exact).
  // The four node heights of each lane's cell, then the differences for all four lanes at once
  // (the same float subtractions as one lane at a time).
  const float* const heights = heights_.data();
  const std::int32_t stride = size_;
  // Offsets from the base node in one vector multiply-add (the grid has at most 2^28 nodes).
  const float* const base_node =
      heights + static_cast<std::ptrdiff_t>(rays.base_j) * stride + rays.base_i;
  const V4i node = j * stride + i;
  const lanes::CellCorners4 h = lanes::GatherCellCorners4(base_node, node, stride);
  const V4f base = h.v00;
  const V4f e10 = h.v10 - base;
  const V4f e01 = h.v01 - base;
  const V4f d11 = h.v11 - base;
  const V4f e11 = d11 - e10 - e01;
  const V4f fx = rays.gx0 + t0 * rays.dgx - __builtin_convertvector(i, V4f);
  const V4f fy = rays.gy0 + t0 * rays.dgy - __builtin_convertvector(j, V4f);
  const V4f s = t1 - t0;
  const V4f zero = {0.0f, 0.0f, 0.0f, 0.0f};
  // The ray is lowest at t1 (dz < 0); a bilinear patch is highest at a corner.
  const V4f top_a = e10 > zero ? e10 : zero;
  const V4f top_b = e01 > d11 ? e01 : d11;
  const V4i above = (rays.oz + t1 * rays.dz - base) > (top_a > top_b ? top_a : top_b);
  const V4f g0 = (rays.oz + t0 * rays.dz - base) - (e10 * fx + e01 * fy + e11 * fx * fy);
  const V4i entered_below = g0 <= 0.0f;
  const V4f g1 =
      rays.dz - (e10 * rays.dgx + e01 * rays.dgy + e11 * (fx * rays.dgy + rays.dgx * fy));
  const V4f g2 = -e11 * rays.dgx * rays.dgy;
  // Positive at both ends: a root needs the vertex inside the span (a dip).
  const V4f g_end = g0 + s * (g1 + s * g2);
  const V4i dip = (g2 > 0.0f) & (g1 < 0.0f) & (-g1 < 2.0f * g2 * s);
  const V4f disc = g1 * g1 - 4.0f * g2 * g0;
  const V4i quadratic = ~((g_end > 0.0f) & ~dip) & (disc >= 0.0f);
  // Numerically stable pair of roots (g0 > 0 makes q != 0); one division for both cases: q g2
  // (quadratic) or g1 (linear, root -g0 / g1).
  constexpr std::int32_t kSign = std::numeric_limits<std::int32_t>::min();
  const V4i sign = {kSign, kSign, kSign, kSign};
  const V4f root = SqrtLanes(disc > zero ? disc : zero);
  const V4f q = -0.5f * (g1 + reinterpret_cast<V4f>(reinterpret_cast<V4i>(root) |
                                                    (reinterpret_cast<V4i>(g1) & sign)));
  const V4i linear = g2 == 0.0f;
  const V4f inv = 1.0f / (linear != 0 ? g1 : q * g2);
  const V4f r1 = q * q * inv;
  const V4f r2 = g0 * g2 * inv;
  const V4f lo = r2 < r1 ? r2 : r1;
  const V4f hi = r1 < r2 ? r2 : r1;
  const V4f minus_one = {-1.0f, -1.0f, -1.0f, -1.0f};
  const V4f tau_quadratic = quadratic != 0 ? (lo >= 0.0f ? lo : hi) : minus_one;
  const V4f tau_linear = g1 < 0.0f ? -g0 * inv : minus_one;
  const V4f tau = linear != 0 ? tau_linear : tau_quadratic;
  // Rounding may put a root at the exit a little past it: accepted, clamped to the exit.
  const V4i in_span = (tau >= 0.0f) & (tau <= s + 1e-4f * s);
  const V4i found = ~above & (entered_below | in_span);
  const V4f nan = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::quiet_NaN(),
                   std::numeric_limits<float>::quiet_NaN(),
                   std::numeric_limits<float>::quiet_NaN()};
  const V4f offset = entered_below != 0 ? zero : (s < tau ? s : tau);
  return found != 0 ? t0 + offset : nan;
}

void Terrain::IntersectSpan4(const GridRays4& rays, V4f* t, V4i* walk, SecondCells4* second) const {
  // As IntersectSpan: the cells the segment touches, read off its end points (floor of the
  // relative positions, clamped so that the global cell stays inside the grid).
  auto floor_i = [](V4f x) {
    const V4i i = __builtin_convertvector(x, V4i);
    return i + (__builtin_convertvector(i, V4f) > x);  // -1 where truncation rounded up
  };
  // Clamped in float before the floor (float max / min are one instruction each on SSE2 and
  // NEON, 32-bit integer ones are not on SSE2): floor is monotonic and the bounds are integers,
  // so this is the clamped floor. A NaN position gets the lower bound (max and min return their
  // second operand when unordered), never an index outside the grid.
  auto clamped_floor = [&](V4f x, std::int32_t base) {
    const auto lo = static_cast<float>(-base);
    const auto hi = static_cast<float>(size_ - 2 - base);
    x = x > lo ? x : V4f{lo, lo, lo, lo};
    x = x < hi ? x : V4f{hi, hi, hi, hi};
    return floor_i(x);
  };
  const V4i ia = clamped_floor(rays.gx0 + rays.ta * rays.dgx, rays.base_i);
  const V4i ib = clamped_floor(rays.gx0 + rays.tb * rays.dgx, rays.base_i);
  const V4i ja = clamped_floor(rays.gy0 + rays.ta * rays.dgy, rays.base_j);
  const V4i jb = clamped_floor(rays.gy0 + rays.tb * rays.dgy, rays.base_j);
  const V4i di = ib - ia;
  const V4i dj = jb - ja;
  const V4i one = (di == 0) & (dj == 0);
  const V4i two_x = (dj == 0) & ((di == 1) | (di == -1));
  const V4i two_y = (di == 0) & ((dj == 1) | (dj == -1));
  const V4i two = two_x | two_y;
  *walk = ~(one | two);
  // Two neighbours: split where the ray crosses their border.
  const V4i border_i = ia > ib ? ia : ib;
  const V4i border_j = ja > jb ? ja : jb;
  const V4f cross = two_x != 0 ? (__builtin_convertvector(border_i, V4f) - rays.gx0) / rays.dgx
                               : (__builtin_convertvector(border_j, V4f) - rays.gy0) / rays.dgy;
  const V4f clamped = cross < rays.ta ? rays.ta : (rays.tb < cross ? rays.tb : cross);
  const V4f mid = two != 0 ? clamped : rays.tb;
  const V4f hit = IntersectCell4(rays, ia, ja, rays.ta, mid);
  *t = hit;
  second->pending = two & (hit != hit);  // NaN: no hit in the first cell
  second->i = ib;
  second->j = jb;
  second->t0 = mid;
}

void Terrain::IntersectSpan4(const GridRays4& rays, V4f* t, V4i* walk) const {
  SecondCells4 second{};
  IntersectSpan4(rays, t, walk, &second);
  const V4i pending = second.pending;
  if (pending[0] | pending[1] | pending[2] | pending[3]) {
    const V4f later = IntersectSecondCells4(rays, second);
    *t = pending != 0 ? later : *t;
  }
}

Terrain::V4f Terrain::IntersectSecondCells4(const GridRays4& rays,
                                            const SecondCells4& second) const {
  return IntersectCell4(rays, second.i, second.j, second.t0, rays.tb);
}

bool Terrain::WalkSpan(const GridRay& ray, double ta, double tb, double* t) const {
  const double inv_descent = -1.0 / ray.dz;
  const double fastest = std::max(std::abs(ray.dgx), std::abs(ray.dgy));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  WalkRay walk_ray{};
  walk_ray.gx0 = ray.gx0;
  walk_ray.gy0 = ray.gy0;
  walk_ray.inv_dgx = ray.dgx != 0.0 ? 1.0 / ray.dgx : kInf;
  walk_ray.inv_dgy = ray.dgy != 0.0 ? 1.0 / ray.dgy : kInf;
  walk_ray.step_i = ray.dgx > 0.0 ? 1 : (ray.dgx < 0.0 ? -1 : 0);
  walk_ray.step_j = ray.dgy > 0.0 ? 1 : (ray.dgy < 0.0 ? -1 : 0);
  walk_ray.ahead_i = ray.dgx > 0.0 ? 1 : 0;
  walk_ray.ahead_j = ray.dgy > 0.0 ? 1 : 0;
  // ~1e-7 cell along the faster axis: steps past a border the ray sits on.
  const double nudge =
      fastest > 0.0 ? 1e-7 * std::min(std::abs(walk_ray.inv_dgx), std::abs(walk_ray.inv_dgy)) : 0.0;
  auto walk = [&](double s, std::int32_t cells, std::int32_t count) {
    return LevelWalk(walk_ray, ray.gx0 + (s + nudge) * ray.dgx, ray.gy0 + (s + nudge) * ray.dgy,
                     cells, count);
  };
  // Super blocks, then blocks, then cells: a level is entered only where the ray comes down to its
  // maximum height (the ray is lowest where it leaves a cell, as dz < 0). A ray starting low
  // (within one block height of the ground, the usual case below a local top_m) skips the super
  // level.
  auto walk_blocks = [&](double s0, double s1) {
    double sb = s0;
    LevelWalk block = walk(sb, kBlock, blocks_);
    for (;;) {
      const double block_exit = std::min(block.Exit(), s1);
      const double block_top = block_max_[static_cast<size_t>(block.j) * blocks_ + block.i];
      if (ray.oz + block_exit * ray.dz <= block_top) {
        double sc = std::max(sb, (ray.oz - block_top) * inv_descent);
        LevelWalk cell = walk(sc, 1, size_ - 1);
        for (;;) {
          const double cell_exit = std::min(cell.Exit(), block_exit);
          if (IntersectCell(ray, cell.i, cell.j, sc, cell_exit, t)) return true;
          if (cell_exit >= block_exit || !cell.Advance()) break;
          sc = cell_exit;
        }
      }
      if (block_exit >= s1 || !block.Advance()) return false;
      sb = block_exit;
    }
  };
  const double horizontal_cells = (tb - ta) * fastest;
  if (horizontal_cells < kBlock) {  // a short walk (local height bounds): cells only
    double sc = ta;
    LevelWalk cell = walk(sc, 1, size_ - 1);
    for (;;) {
      const double cell_exit = std::min(cell.Exit(), tb);
      if (IntersectCell(ray, cell.i, cell.j, sc, cell_exit, t)) return true;
      if (cell_exit >= tb || !cell.Advance()) return false;
      sc = cell_exit;
    }
  }
  if (horizontal_cells < 2.0 * kBlock) return walk_blocks(ta, tb);
  LevelWalk super = walk(ta, kBlock * kSuper, supers_);
  double s = ta;
  for (;;) {
    const double super_exit = std::min(super.Exit(), tb);
    const double super_top = super_max_[static_cast<size_t>(super.j) * supers_ + super.i];
    if (ray.oz + super_exit * ray.dz <= super_top) {
      if (walk_blocks(std::max(s, (ray.oz - super_top) * inv_descent), super_exit)) return true;
    }
    if (super_exit >= tb || !super.Advance()) break;
    s = super_exit;
  }
  return false;
}

}  // namespace swf::sim
