#include "swf/sim/terrain.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

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

}  // namespace

TerrainOptions TerrainPresetOptions(TerrainPreset preset, std::uint64_t seed) {
  TerrainOptions o;
  o.seed = seed;
  switch (preset) {
    case TerrainPreset::kSmoothPlains:
      o.relief_rms_m = 0.3;
      o.craters.density_at_1m = 0.004;
      o.craters.max_diameter_m = 10.0;
      o.rocks.k = 0.005;
      break;
    case TerrainPreset::kCraterField:
      o.relief_rms_m = 0.5;
      o.craters.density_at_1m = 0.08;
      o.craters.max_diameter_m = 40.0;
      o.rocks.k = 0.03;
      break;
    case TerrainPreset::kRockField:
      o.relief_rms_m = 0.3;
      o.craters.density_at_1m = 0.01;
      o.craters.max_diameter_m = 15.0;
      o.rocks.k = 0.15;  // rock-rich, between Viking Lander 1 (~0.07) and 2 (~0.18)
      break;
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
  if (std::strcmp(name, "plains") == 0) {
    *preset = TerrainPreset::kSmoothPlains;
  } else if (std::strcmp(name, "craters") == 0) {
    *preset = TerrainPreset::kCraterField;
  } else if (std::strcmp(name, "rocks") == 0) {
    *preset = TerrainPreset::kRockField;
  } else {
    return false;
  }
  return true;
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
      const auto i0 = std::max<std::int32_t>(
          0,
          static_cast<std::int32_t>(std::floor((c.center_m.x() - reach - origin_m_) / o.cell_m)));
      const auto i1 = std::min<std::int32_t>(
          size_ - 1,
          static_cast<std::int32_t>(std::ceil((c.center_m.x() + reach - origin_m_) / o.cell_m)));
      const auto j0 = std::max<std::int32_t>(
          0,
          static_cast<std::int32_t>(std::floor((c.center_m.y() - reach - origin_m_) / o.cell_m)));
      const auto j1 = std::min<std::int32_t>(
          size_ - 1,
          static_cast<std::int32_t>(std::ceil((c.center_m.y() + reach - origin_m_) / o.cell_m)));
      for (std::int32_t j = j0; j <= j1; ++j) {
        for (std::int32_t i = i0; i <= i1; ++i) {
          const double r = std::hypot(NodeX(i) - c.center_m.x(), NodeY(j) - c.center_m.y());
          h[static_cast<size_t>(j) * size_ + i] += CraterProfile(c, r);
        }
      }
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
      const auto i0 = std::max<std::int32_t>(
          0, static_cast<std::int32_t>(
                 std::floor((rock.center_m.x() - radius - origin_m_) / o.cell_m)));
      const auto i1 = std::min<std::int32_t>(
          size_ - 1, static_cast<std::int32_t>(
                         std::ceil((rock.center_m.x() + radius - origin_m_) / o.cell_m)));
      const auto j0 = std::max<std::int32_t>(
          0, static_cast<std::int32_t>(
                 std::floor((rock.center_m.y() - radius - origin_m_) / o.cell_m)));
      const auto j1 = std::min<std::int32_t>(
          size_ - 1, static_cast<std::int32_t>(
                         std::ceil((rock.center_m.y() + radius - origin_m_) / o.cell_m)));
      for (std::int32_t j = j0; j <= j1; ++j) {
        for (std::int32_t i = i0; i <= i1; ++i) {
          const double dx = NodeX(i) - rock.center_m.x();
          const double dy = NodeY(j) - rock.center_m.y();
          const double s2 = (dx * dx + dy * dy) / (radius * radius);
          if (s2 >= 1.0) continue;
          const auto top = static_cast<float>(rock.base_z_m + rock.height_m * std::sqrt(1.0 - s2));
          float& cell = heights_[static_cast<size_t>(j) * size_ + i];
          cell = std::max(cell, top);
        }
      }
    }
  }

  // Bounds for ray casting: per-block maxima over the block's nodes (borders shared).
  blocks_ = (size_ - 1 + kBlock - 1) / kBlock;
  block_max_.assign(static_cast<size_t>(blocks_) * blocks_, -std::numeric_limits<float>::max());
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
          float& m = block_max_[static_cast<size_t>(by) * blocks_ + bx];
          m = std::max(m, v);
        }
      }
    }
  }
  return core::Status::kOk;
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

bool Terrain::FineMarch(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_begin,
                        double t_end, double* t) const {
  const double inv_cell = 1.0 / options_.cell_m;
  auto gap = [&](double s) {
    return (o.z() + s * d.z()) - GridHeight((o.x() + s * d.x() - origin_m_) * inv_cell,
                                            (o.y() + s * d.y() - origin_m_) * inv_cell);
  };
  const double horizontal = std::hypot(d.x(), d.y());
  // Half a cell horizontally per step: a bilinear patch is crossed at most twice per step.
  const double dt = horizontal > 0.0 ? 0.5 * options_.cell_m / horizontal : t_end - t_begin;
  double a = t_begin;
  double fa = gap(a);
  if (fa <= 0.0) {
    *t = a;
    return true;
  }
  while (a < t_end) {
    const double b_try = std::min(a + dt, t_end);
    const double fb_try = gap(b_try);
    if (fb_try > 0.0) {
      a = b_try;
      fa = fb_try;
      continue;
    }
    // Illinois regula falsi on [a, b] with gap(a) > 0 >= gap(b).
    double b = b_try;
    double fb = fb_try;
    double c = b;
    int side = 0;
    for (int it = 0; it < 40; ++it) {
      c = (a * fb - b * fa) / (fb - fa);
      const double fc = gap(c);
      if (std::abs(fc) < 1e-10 || b - a < 1e-12) break;
      if (fc > 0.0) {
        a = c;
        fa = fc;
        if (side == 1) fb *= 0.5;
        side = 1;
      } else {
        b = c;
        fb = fc;
        if (side == -1) fa *= 0.5;
        side = -1;
      }
    }
    *t = c;
    return true;
  }
  return false;
}

bool Terrain::Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* t) const {
  if (size_ == 0 || !(d.z() < 0.0)) return false;
  // Pad the height range so a perfectly flat terrain still has a non-empty interval.
  const double pad_m = 1e-3 * options_.cell_m;
  double ta = std::max(0.0, (o.z() - max_height_m_ - pad_m) / -d.z());
  double tb = (o.z() - min_height_m_ + pad_m) / -d.z();
  const double lo = origin_m_;
  const double hi = -origin_m_;
  for (int axis = 0; axis < 2; ++axis) {
    if (d[axis] != 0.0) {
      double t0 = (lo - o[axis]) / d[axis];
      double t1 = (hi - o[axis]) / d[axis];
      if (t0 > t1) std::swap(t0, t1);
      ta = std::max(ta, t0);
      tb = std::min(tb, t1);
    } else if (o[axis] < lo || o[axis] > hi) {
      return false;
    }
  }
  if (!(ta < tb)) return false;
  const double inv_cell = 1.0 / options_.cell_m;
  const double block_m = kBlock * options_.cell_m;
  const double horizontal = std::hypot(d.x(), d.y());
  const double nudge = horizontal > 0.0 ? 1e-6 * options_.cell_m / horizontal : 0.0;
  double s = ta;
  while (s < tb) {
    const double px = o.x() + (s + nudge) * d.x();
    const double py = o.y() + (s + nudge) * d.y();
    const std::int32_t bx =
        std::clamp(static_cast<std::int32_t>((px - origin_m_) * inv_cell) / kBlock, 0, blocks_ - 1);
    const std::int32_t by =
        std::clamp(static_cast<std::int32_t>((py - origin_m_) * inv_cell) / kBlock, 0, blocks_ - 1);
    double s_exit = tb;
    if (d.x() > 0.0) s_exit = std::min(s_exit, (origin_m_ + (bx + 1) * block_m - o.x()) / d.x());
    if (d.x() < 0.0) s_exit = std::min(s_exit, (origin_m_ + bx * block_m - o.x()) / d.x());
    if (d.y() > 0.0) s_exit = std::min(s_exit, (origin_m_ + (by + 1) * block_m - o.y()) / d.y());
    if (d.y() < 0.0) s_exit = std::min(s_exit, (origin_m_ + by * block_m - o.y()) / d.y());
    s_exit = std::max(s_exit, s + 2.0 * nudge);
    if (s_exit > tb) s_exit = tb;
    const double block_top = block_max_[static_cast<size_t>(by) * blocks_ + bx];
    if (o.z() + s_exit * d.z() <= block_top) {
      const double s_in = std::max(s, (o.z() - block_top) / -d.z());
      if (FineMarch(o, d, s_in, s_exit, t)) return true;
    }
    if (s_exit <= s) break;  // no progress possible (degenerate ray)
    s = s_exit;
  }
  return false;
}

}  // namespace swf::sim
