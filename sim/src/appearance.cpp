#include "swf/sim/appearance.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <numbers>

#include "lanes.hpp"
#include "swf/sim/image_io.hpp"
#include "swf/sim/rng.hpp"

namespace swf::sim {
namespace {

// Octave groups of four: group g holds octaves 4g .. 4g + 3.
constexpr float kGroupRatio[2] = {1.0f, 1.0f / 16.0f};
constexpr float kGroupScale[2] = {1.0f, 16.0f};

double HashValue(std::uint64_t key, std::int64_t ix, std::int64_t iy) {
  const std::uint64_t h = Mix64(key ^ (static_cast<std::uint64_t>(ix) * 0x9E3779B97F4A7C15ull) ^
                                (static_cast<std::uint64_t>(iy) * 0xC2B2AE3D27D4EB4Full));
  return static_cast<double>(h >> 11) * 0x1.0p-52 - 1.0;
}

// Bilinear sample of a row-major w x h float grid at 0 <= x <= w - 1, 0 <= y <= h - 1.
double SampleBilinear(const std::vector<float>& grid, std::int32_t w, std::int32_t h, double x,
                      double y) {
  const std::int32_t i = std::min(static_cast<std::int32_t>(x), w - 2);
  const std::int32_t j = std::min(static_cast<std::int32_t>(y), h - 2);
  const double fx = x - i;
  const double fy = y - j;
  const float* p = &grid[static_cast<size_t>(j) * w + i];
  const double top = p[0] + fx * (p[1] - p[0]);
  const double bottom = p[w] + fx * (p[w + 1] - p[w]);
  return top + fy * (bottom - top);
}

// Bilinear sample of an image at continuous pixel coordinates, mirror-repeated.
double SampleMirrored(const std::vector<float>& img, std::int32_t w, std::int32_t h, double x,
                      double y) {
  auto mirror = [](double v, std::int32_t n) {
    const double period = 2.0 * (n - 1);
    double m = std::fmod(v, period);
    if (m < 0.0) m += period;
    return m > n - 1 ? period - m : m;
  };
  return SampleBilinear(img, w, h, mirror(x, w), mirror(y, h));
}

}  // namespace

AppearanceOptions DefaultImagery(const std::string& shared_dir) {
  AppearanceOptions o;
  o.intensity_image_path = shared_dir + "/data/terrain/kaguya_south_pole_intensity.pgm";
  o.mask_image_path = shared_dir + "/data/terrain/kaguya_south_pole_mask.pgm";
  o.global_albedo_path = shared_dir + "/data/terrain/moon_4k.jpg";
  return o;
}

core::Status Appearance::Configure(const Terrain& terrain, const AppearanceOptions& options) {
  const core::Status status = Build(terrain, options);
  if (status != core::Status::kOk) {
    // A half-built appearance must not look usable: Size() == 0 makes Render refuse it.
    size_ = 0;
    albedo_.clear();
    shaded_.clear();
    lit_.clear();
  }
  return status;
}

core::Status Appearance::Build(const Terrain& terrain, const AppearanceOptions& options) {
  if (!(options.sun_elevation_deg > 0.0 && options.sun_elevation_deg <= 90.0) ||
      !(options.ambient >= 0.0 && options.ambient <= 1.0) || !(options.global_weight >= 0.0) ||
      !(options.detail_strength >= 0.0) || !(options.image_pixel_m > 0.0) ||
      !std::isfinite(options.sun_azimuth_deg) || terrain.Size() < 2) {
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  size_ = terrain.Size();
  origin_m_ = terrain.NodeX(0);
  cell_m_ = terrain.CellM();
  inv_cell_m_ = 1.0 / cell_m_;
  const size_t n = static_cast<size_t>(size_) * size_;
  Rng rng(options.seed);
  const std::uint64_t detail_key = rng.Bits();
  // One extra wrapped row and column: the four corners of a lattice cell are at i, i + 1,
  // i + kLatticeStride and i + kLatticeStride + 1 without masking.
  lattice_.resize(static_cast<size_t>(kLatticeStride * kLatticeStride));
  for (std::int64_t b = 0; b < kLatticeStride; ++b) {
    for (std::int64_t a = 0; a < kLatticeStride; ++a) {
      lattice_[static_cast<size_t>(b * kLatticeStride + a)] =
          static_cast<float>(HashValue(detail_key, a & (kLatticeSize - 1), b & (kLatticeSize - 1)));
    }
  }
  for (int o = 0; o < kDetailOctaves; ++o) {
    const std::uint64_t h = Mix64(detail_key ^ Mix64(static_cast<std::uint64_t>(o) + 1));
    octave_offset_x_[o / 4][o % 4] = static_cast<std::int32_t>(h & (kLatticeSize - 1));
    octave_offset_y_[o / 4][o % 4] = static_cast<std::int32_t>((h >> 32) & (kLatticeSize - 1));
    octave_amplitude_[o / 4][o % 4] =
        static_cast<float>(options.detail_strength * std::pow(std::numbers::sqrt2 * 0.5, o));
  }
  albedo_.assign(n, 1.0f);

  // Kaguya: pick the 384 px window with the most valid, lit pixels; normalize to mean 1.
  if (!options.intensity_image_path.empty()) {
    GrayImage intensity;
    GrayImage mask;
    if (const core::Status s = ReadGrayImage(options.intensity_image_path, &intensity);
        s != core::Status::kOk) {
      return s;
    }
    const bool has_mask = !options.mask_image_path.empty();
    if (has_mask) {
      if (const core::Status s = ReadGrayImage(options.mask_image_path, &mask);
          s != core::Status::kOk) {
        return s;
      }
      if (mask.width != intensity.width || mask.height != intensity.height) {
        return core::Status::kCorruptData;
      }
    }
    constexpr std::int32_t kLitDn = 20;
    const std::int32_t win = std::min({384, intensity.width, intensity.height});
    if (win < 16) return core::Status::kCorruptData;
    auto good = [&](std::int32_t x, std::int32_t y) {
      return intensity.At(x, y) >= kLitDn && (!has_mask || mask.At(x, y) > 0);
    };
    std::int64_t best = -1;
    std::int32_t best_x = 0;
    std::int32_t best_y = 0;
    for (std::int32_t y0 = 0; y0 + win <= intensity.height; y0 += 32) {
      for (std::int32_t x0 = 0; x0 + win <= intensity.width; x0 += 32) {
        std::int64_t count = 0;
        for (std::int32_t y = y0; y < y0 + win; y += 4) {
          for (std::int32_t x = x0; x < x0 + win; x += 4) count += good(x, y) ? 1 : 0;
        }
        if (count > best) {
          best = count;
          best_x = x0;
          best_y = y0;
        }
      }
    }
    std::vector<float> window(static_cast<size_t>(win) * win);
    double sum = 0.0;
    std::int64_t lit = 0;
    for (std::int32_t y = 0; y < win; ++y) {
      for (std::int32_t x = 0; x < win; ++x) {
        if (good(best_x + x, best_y + y)) {
          sum += intensity.At(best_x + x, best_y + y);
          ++lit;
        }
      }
    }
    const double mean = lit > 0 ? sum / static_cast<double>(lit) : 1.0;
    for (std::int32_t y = 0; y < win; ++y) {
      for (std::int32_t x = 0; x < win; ++x) {
        const double v = good(best_x + x, best_y + y) ? intensity.At(best_x + x, best_y + y) / mean
                                                      : 0.5;  // real shadow / no data: dim
        window[static_cast<size_t>(y) * win + x] = static_cast<float>(std::clamp(v, 0.3, 2.5));
      }
    }
    const double offset_x = rng.Uniform(0.0, 2.0 * win);
    const double offset_y = rng.Uniform(0.0, 2.0 * win);
    const double per_cell = cell_m_ / options.image_pixel_m;
    for (std::int32_t j = 0; j < size_; ++j) {
      for (std::int32_t i = 0; i < size_; ++i) {
        albedo_[static_cast<size_t>(j) * size_ + i] = static_cast<float>(SampleMirrored(
            window, win, win, offset_x + i * per_cell, offset_y + (size_ - 1 - j) * per_cell));
      }
    }
  }

  // Global albedo: a 256 px crop between +-45 deg latitude stretched over the terrain.
  if (!options.global_albedo_path.empty() && options.global_weight > 0.0) {
    GrayImage global;
    if (const core::Status s = ReadGrayImage(options.global_albedo_path, &global);
        s != core::Status::kOk) {
      return s;
    }
    constexpr std::int32_t kCrop = 256;
    if (global.width < 2 * kCrop || global.height < 2 * kCrop) return core::Status::kCorruptData;
    const auto x0 = static_cast<std::int32_t>(rng.UniformInt(0, global.width - kCrop - 1));
    const auto y0 = static_cast<std::int32_t>(
        rng.UniformInt(global.height / 4, 3 * global.height / 4 - kCrop - 1));
    std::vector<float> crop(static_cast<size_t>(kCrop) * kCrop);
    double sum = 0.0;
    for (std::int32_t y = 0; y < kCrop; ++y) {
      for (std::int32_t x = 0; x < kCrop; ++x) {
        crop[static_cast<size_t>(y) * kCrop + x] = global.At(x0 + x, y0 + y);
        sum += global.At(x0 + x, y0 + y);
      }
    }
    const double mean = std::max(1.0, sum / (kCrop * kCrop));
    const double scale = (kCrop - 1.0) / (size_ - 1.0);
    for (std::int32_t j = 0; j < size_; ++j) {
      for (std::int32_t i = 0; i < size_; ++i) {
        const double g = SampleMirrored(crop, kCrop, kCrop, i * scale, (size_ - 1 - j) * scale);
        float& a = albedo_[static_cast<size_t>(j) * size_ + i];
        a = static_cast<float>(a * std::max(0.2, 1.0 + options.global_weight * (g / mean - 1.0)));
      }
    }
  }

  // Cast shadows: sweep from the sun side carrying the horizon height.
  const double az = options.sun_azimuth_deg * std::numbers::pi / 180.0;
  const double el = options.sun_elevation_deg * std::numbers::pi / 180.0;
  const Eigen::Vector3d sun(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const std::vector<float>& h = terrain.Heights();
  lit_.assign(n, 1);
  if (options.sun_elevation_deg < 90.0) {
    // Walk along the dominant horizontal axis of the sun direction ("major"), one node per step.
    const bool x_major = std::abs(sun.x()) >= std::abs(sun.y());
    const double major = x_major ? sun.x() : sun.y();
    const double minor = x_major ? sun.y() : sun.x();
    const int step = major > 0.0 ? 1 : -1;         // towards the sun along the major axis
    const double slope = minor / std::abs(major);  // minor-axis offset per major step
    const double drop = cell_m_ * std::sqrt(1.0 + slope * slope) * std::tan(el);
    auto index = [&](std::int32_t a, std::int32_t b) {  // a along major, b along minor
      return x_major ? static_cast<size_t>(b) * size_ + a : static_cast<size_t>(a) * size_ + b;
    };
    std::vector<double> horizon(n, -std::numeric_limits<double>::infinity());
    const std::int32_t first = step > 0 ? size_ - 1 : 0;
    for (std::int32_t b = 0; b < size_; ++b) horizon[index(first, b)] = h[index(first, b)];
    for (std::int32_t a = first - step; a >= 0 && a < size_; a -= step) {
      const std::int32_t up = a + step;
      for (std::int32_t b = 0; b < size_; ++b) {
        const double pb = b + slope;
        double upstream = -std::numeric_limits<double>::infinity();
        if (pb >= 0.0 && pb <= size_ - 1) {
          const std::int32_t b0 = std::min(static_cast<std::int32_t>(pb), size_ - 2);
          const double f = pb - b0;
          upstream = (1.0 - f) * horizon[index(up, b0)] + f * horizon[index(up, b0 + 1)];
        }
        const double here = h[index(a, b)];
        const double carried = upstream - drop;
        lit_[index(a, b)] = here >= carried ? 1 : 0;
        horizon[index(a, b)] = std::max(here, carried);
      }
    }
  }

  shaded_.assign(n, 0.0f);
  const double inv_2cell = 0.5 / cell_m_;
  for (std::int32_t j = 0; j < size_; ++j) {
    for (std::int32_t i = 0; i < size_; ++i) {
      const std::int32_t il = std::max(0, i - 1);
      const std::int32_t ir = std::min(size_ - 1, i + 1);
      const std::int32_t jd = std::max(0, j - 1);
      const std::int32_t ju = std::min(size_ - 1, j + 1);
      const double hx =
          (h[static_cast<size_t>(j) * size_ + ir] - h[static_cast<size_t>(j) * size_ + il]) *
          inv_2cell * 2.0 / (ir - il);
      const double hy =
          (h[static_cast<size_t>(ju) * size_ + i] - h[static_cast<size_t>(jd) * size_ + i]) *
          inv_2cell * 2.0 / (ju - jd);
      const Eigen::Vector3d normal = Eigen::Vector3d(-hx, -hy, 1.0).normalized();
      const size_t k = static_cast<size_t>(j) * size_ + i;
      const double direct = lit_[k] * std::max(0.0, normal.dot(sun)) / std::sin(el);
      shaded_[k] =
          static_cast<float>(albedo_[k] * (options.ambient + (1.0 - options.ambient) * direct));
    }
  }
  return core::Status::kOk;
}

inline Appearance::V4f Appearance::OctaveDetail4(V4f lane_ratio, V4f sx, V4f sy, V4i cell_x,
                                                 V4i cell_y, V4f amplitude) const {
  V4f w = (lane_ratio - 1.5f) * (1.0f / 1.5f);
  w = w < 0.0f ? 0.0f : w;  // lane-wise select
  w = w > 1.0f ? 1.0f : w;
  w = w * w * (3.0f - 2.0f * w);
  const V4i kx = __builtin_convertvector(sx, V4i);  // truncation = floor (non-negative)
  const V4i ky = __builtin_convertvector(sy, V4i);
  V4f rx = sx - __builtin_convertvector(kx, V4f);
  V4f ry = sy - __builtin_convertvector(ky, V4f);
  rx = rx * rx * (3.0f - 2.0f * rx);
  ry = ry * ry * (3.0f - 2.0f * ry);
  const V4i mask = {kLatticeSize - 1, kLatticeSize - 1, kLatticeSize - 1, kLatticeSize - 1};
  const V4i a0 = (cell_x + kx) & mask;
  const V4i b0 = (cell_y + ky) & mask;
  const V4i i00 = b0 * kLatticeStride + a0;
  const lanes::CellCorners4 v = lanes::GatherCellCorners4(lattice_.data(), i00, kLatticeStride);
  const V4f upper = v.v00 + rx * (v.v10 - v.v00);
  const V4f lower = v.v01 + rx * (v.v11 - v.v01);
  return w * amplitude * (upper + ry * (lower - upper));
}

double Appearance::Radiance(double x_m, double y_m, double footprint_m) const {
  const double inv_cell = inv_cell_m_;
  const double gx = std::clamp((x_m - origin_m_) * inv_cell, 0.0, size_ - 1.0);
  const double gy = std::clamp((y_m - origin_m_) * inv_cell, 0.0, size_ - 1.0);
  const double base = SampleBilinear(shaded_, size_, size_, gx, gy);

  // Octave o has wavelength cell / 2^o: its lattice coordinate is (di + f) 2^o, split exactly into
  // di 2^o + floor(f 2^o) and the fraction of f 2^o (single precision suffices for the fraction
  // within one cell: 2^-24 of a cell before the scaling by at most 2^7). The detail lattice sits
  // half a cell off the height-field nodes (no common kink lines). An octave whose wavelength spans
  // < 1.5 px has weight 0; with more than two octaves of weight, four at a time in 4-lane vectors
  // (SSE2 / NEON).
  const float ratio = static_cast<float>(cell_m_) / static_cast<float>(footprint_m);  // px/wl
  if (ratio < 1.5f) return base;
  const double hx = gx + 0.5;
  const double hy = gy + 0.5;
  const auto di = static_cast<std::int32_t>(hx);
  const auto dj = static_cast<std::int32_t>(hy);
  const auto cfx = static_cast<float>(hx - di);
  const auto cfy = static_cast<float>(hy - dj);
  const float* lattice = lattice_.data();
  if (ratio < 6.0f) {  // at most octaves 0 and 1 have weight: scalar
    constexpr std::int32_t kMask = kLatticeSize - 1;
    float detail = 0.0f;
    float octave_ratio = ratio;
    for (int o = 0; o < 2 && octave_ratio >= 1.5f; ++o, octave_ratio *= 0.5f) {
      float w = std::min(1.0f, (octave_ratio - 1.5f) * (1.0f / 1.5f));
      w = w * w * (3.0f - 2.0f * w);
      const float sx = cfx * static_cast<float>(1 << o);
      const float sy = cfy * static_cast<float>(1 << o);
      const auto kx = static_cast<std::int32_t>(sx);
      const auto ky = static_cast<std::int32_t>(sy);
      float rx = sx - static_cast<float>(kx);
      float ry = sy - static_cast<float>(ky);
      rx = rx * rx * (3.0f - 2.0f * rx);
      ry = ry * ry * (3.0f - 2.0f * ry);
      const float* p =
          lattice + ((((dj << o) + ky + octave_offset_y_[0][o]) & kMask) * kLatticeStride +
                     (((di << o) + kx + octave_offset_x_[0][o]) & kMask));
      const float upper = p[0] + rx * (p[1] - p[0]);
      const float lower = p[kLatticeStride] + rx * (p[kLatticeStride + 1] - p[kLatticeStride]);
      detail += w * octave_amplitude_[0][o] * (upper + ry * (lower - upper));
    }
    return base * std::max(0.05, 1.0 + static_cast<double>(detail));
  }
  V4f detail = {0.0f, 0.0f, 0.0f, 0.0f};
  for (int g = 0; g < kDetailOctaves / 4; ++g) {
    const float group_ratio = ratio * kGroupRatio[g];
    if (group_ratio < 1.5f) break;
    const V4f lane_ratio = group_ratio * V4f{1.0f, 0.5f, 0.25f, 0.125f};
    const V4f scale = kGroupScale[g] * V4f{1.0f, 2.0f, 4.0f, 8.0f};  // powers of two: exact
    const std::int32_t shift = 4 * g;
    const V4i cell_x = (V4i{di, di * 2, di * 4, di * 8} << shift) + octave_offset_x_[g];
    const V4i cell_y = (V4i{dj, dj * 2, dj * 4, dj * 8} << shift) + octave_offset_y_[g];
    detail +=
        OctaveDetail4(lane_ratio, cfx * scale, cfy * scale, cell_x, cell_y, octave_amplitude_[g]);
  }
  const float sum = (detail[0] + detail[1]) + (detail[2] + detail[3]);
  return base * std::max(0.05, 1.0 + static_cast<double>(sum));
}

void Appearance::Radiance4(const double* x_m, const double* y_m, const double* footprint_m,
                           double* radiance) const {
  // Per point as Radiance: grid position and the split lattice coordinates (cell index, fraction
  // in the cell) in double, four lanes at once (two SSE2 / NEON registers per vector), then the
  // bilinear shading and the octaves in single precision.
  using V4d [[gnu::vector_size(32)]] = double;
  V4d x;
  V4d y;
  std::memcpy(&x, x_m, sizeof(x));
  std::memcpy(&y, y_m, sizeof(y));
  const V4d lo = {0.0, 0.0, 0.0, 0.0};
  const double top_g = size_ - 1.0;
  const V4d hi = {top_g, top_g, top_g, top_g};
  V4d gx = (x - origin_m_) * inv_cell_m_;
  V4d gy = (y - origin_m_) * inv_cell_m_;
  gx = gx < lo ? lo : (hi < gx ? hi : gx);  // std::clamp
  gy = gy < lo ? lo : (hi < gy ? hi : gy);
  const std::int32_t last = size_ - 2;
  const V4i last4 = {last, last, last, last};
  V4i i = __builtin_convertvector(gx, V4i);
  V4i j = __builtin_convertvector(gy, V4i);
  i = i < last4 ? i : last4;
  j = j < last4 ? j : last4;
  const V4f fx = __builtin_convertvector(gx - __builtin_convertvector(i, V4d), V4f);
  const V4f fy = __builtin_convertvector(gy - __builtin_convertvector(j, V4d), V4f);
  alignas(16) float s00[4];
  alignas(16) float s10[4];
  alignas(16) float s01[4];
  alignas(16) float s11[4];
  for (int k = 0; k < 4; ++k) {
    const float* p = &shaded_[static_cast<size_t>(j[k]) * size_ + i[k]];
    s00[k] = p[0];
    s10[k] = p[1];
    s01[k] = p[size_];
    s11[k] = p[size_ + 1];
  }
  V4f a00;
  V4f a10;
  V4f a01;
  V4f a11;
  std::memcpy(&a00, s00, sizeof(a00));
  std::memcpy(&a10, s10, sizeof(a10));
  std::memcpy(&a01, s01, sizeof(a01));
  std::memcpy(&a11, s11, sizeof(a11));
  const V4f top = a00 + fx * (a10 - a00);
  const V4f bottom = a01 + fx * (a11 - a01);
  const V4f base = top + fy * (bottom - top);
  const V4d hx = gx + 0.5;
  const V4d hy = gy + 0.5;
  const V4i di = __builtin_convertvector(hx, V4i);
  const V4i dj = __builtin_convertvector(hy, V4i);
  const V4f cfx = __builtin_convertvector(hx - __builtin_convertvector(di, V4d), V4f);
  const V4f cfy = __builtin_convertvector(hy - __builtin_convertvector(dj, V4d), V4f);
  V4d footprint;
  std::memcpy(&footprint, footprint_m, sizeof(footprint));
  const V4f detail = Detail4(di, dj, cfx, cfy,
                             static_cast<float>(cell_m_) / __builtin_convertvector(footprint, V4f));
  V4f factor = 1.0f + detail;
  factor = factor < 0.05f ? 0.05f : factor;
  const V4d out = __builtin_convertvector(base * factor, V4d);
  std::memcpy(radiance, &out, sizeof(out));
}

inline Appearance::V4f Appearance::Detail4(V4i di, V4i dj, V4f cfx, V4f cfy, V4f lane_ratio) const {
  V4f detail = {0.0f, 0.0f, 0.0f, 0.0f};
  float scale = 1.0f;  // 2^o: exact
  for (int o = 0; o < kDetailOctaves; ++o, lane_ratio *= 0.5f, scale *= 2.0f) {
    // An octave whose wavelength spans < 1.5 px in every lane has weight 0, as have the finer.
    if (!(lane_ratio[0] >= 1.5f || lane_ratio[1] >= 1.5f || lane_ratio[2] >= 1.5f ||
          lane_ratio[3] >= 1.5f)) {
      break;
    }
    const float amplitude = octave_amplitude_[o / 4][o % 4];
    detail += OctaveDetail4(lane_ratio, cfx * scale, cfy * scale,
                            (di << o) + octave_offset_x_[o / 4][o % 4],
                            (dj << o) + octave_offset_y_[o / 4][o % 4],
                            V4f{amplitude, amplitude, amplitude, amplitude});
  }
  return detail;
}

Appearance::V4f Appearance::Radiance4Grid(std::int32_t base_i, std::int32_t base_j, V4f gx, V4f gy,
                                          V4f footprint_m) const {
  // As Radiance4 with the grid split done in float: floor of a relative position and its fraction
  // (exact: the integer part of a float is subtracted without rounding).
  auto floor_i = [](V4f x) {
    const V4i i = __builtin_convertvector(x, V4i);
    return i + (__builtin_convertvector(i, V4f) > x);  // -1 where truncation rounded up
  };
  // Clamped to the grid as Radiance does (position to [0, size - 1], cell index to size - 2), in
  // float before the floor (float max / min are single instructions, 32-bit integer ones are not
  // on SSE2); the bounds are integers, so the floor of the clamped value is the clamped floor.
  const auto lo_x = static_cast<float>(-base_i);
  const auto lo_y = static_cast<float>(-base_j);
  const auto hi_x = static_cast<float>(size_ - 1 - base_i);
  const auto hi_y = static_cast<float>(size_ - 1 - base_j);
  gx = gx > lo_x ? gx : V4f{lo_x, lo_x, lo_x, lo_x};  // a NaN lane gets the lower bound
  gy = gy > lo_y ? gy : V4f{lo_y, lo_y, lo_y, lo_y};
  gx = gx < hi_x ? gx : V4f{hi_x, hi_x, hi_x, hi_x};
  gy = gy < hi_y ? gy : V4f{hi_y, hi_y, hi_y, hi_y};
  const float last_x = hi_x - 1.0f;
  const float last_y = hi_y - 1.0f;
  const V4i ki = floor_i(gx < last_x ? gx : V4f{last_x, last_x, last_x, last_x});
  const V4i kj = floor_i(gy < last_y ? gy : V4f{last_y, last_y, last_y, last_y});
  const V4f fx = gx - __builtin_convertvector(ki, V4f);
  const V4f fy = gy - __builtin_convertvector(kj, V4f);
  const std::int32_t stride = size_;
  const float* const base_node =
      shaded_.data() + static_cast<std::ptrdiff_t>(base_j) * stride + base_i;
  const V4i node = kj * stride + ki;  // offsets from the base node (at most 2^28 nodes)
  const lanes::CellCorners4 a = lanes::GatherCellCorners4(base_node, node, stride);
  const V4f top = a.v00 + fx * (a.v10 - a.v00);
  const V4f bottom = a.v01 + fx * (a.v11 - a.v01);
  const V4f base = top + fy * (bottom - top);
  // The detail lattice sits half a cell off the nodes.
  const V4f hx = gx + 0.5f;
  const V4f hy = gy + 0.5f;
  const V4i dx = floor_i(hx);
  const V4i dy = floor_i(hy);
  const V4f cfx = hx - __builtin_convertvector(dx, V4f);
  const V4f cfy = hy - __builtin_convertvector(dy, V4f);
  const V4f detail =
      Detail4(dx + base_i, dy + base_j, cfx, cfy, static_cast<float>(cell_m_) / footprint_m);
  V4f factor = 1.0f + detail;
  factor = factor < 0.05f ? 0.05f : factor;
  return base * factor;
}

}  // namespace swf::sim
