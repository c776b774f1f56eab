// Appearance: what the ground looks like, as a radiance factor per world point (1 = flat,
// fully lit ground of mean albedo; the renderer turns it into digital numbers).
//
//   radiance(x, y) = albedo(x, y) * shading(x, y) * (1 + detail(x, y, footprint))
// - albedo (per height-field node) from real orbital imagery: a mostly-lit window of the Kaguya
//   (SELENE) south-pole orthoimage, normalized to mean 1 and mirror-tiled at image_pixel_m per
//   pixel, modulated by a seeded crop of the USGS/Clementine global albedo map spread over the
//   whole terrain (weight global_weight). Without images, albedo is 1.
// - shading (per node, Lambert with an ambient term, normalized so flat lit ground is 1):
//       ambient + (1 - ambient) * lit * max(0, n . s) / sin(elevation)
//   with n the height-field normal and lit the cast-shadow test: a sweep toward the sun carries
//   the horizon height node to node (dropping cell * tan(elevation) per cell travelled) and a
//   node is lit when it reaches above it.
// - detail: procedural value-noise octaves of wavelength cell / 2^o below the grid, amplitude
//   detail_strength * 2^(-o/2), each faded in only where its wavelength spans >= 3 pixels and
//   out below 1.5 (band-limiting by the pixel footprint: the texture anti-aliasing), so there is
//   trackable texture from 100 m down to a few metres without aliasing. The lattice values come
//   from one seeded 512 x 512 table (smoothstep-interpolated), read by each octave at its own
//   seeded offset: octave o repeats every 512 wavelengths (51.2 m for the first at 0.1 m cells,
//   wider than the 100 m view), and a lookup costs a few loads instead of four hashes. The lattice
//   nodes sit half a cell off the height-field nodes; octaves are evaluated in single precision,
//   four per 4-lane vector (GCC vector extensions: SSE2 / NEON).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/sim/terrain.hpp"

namespace swf::sim {

struct AppearanceOptions {
  std::string intensity_image_path;  // e.g. ../shared/data/terrain/kaguya_south_pole_intensity.pgm
  std::string mask_image_path;       // its validity mask (optional)
  std::string global_albedo_path;    // e.g. ../shared/data/terrain/moon_4k.jpg (optional)
  double image_pixel_m = 0.2;        // ground size of one orbital-image pixel
  double global_weight = 0.35;
  double sun_azimuth_deg = 135.0;  // from +x towards +y
  double sun_elevation_deg = 30.0;
  double ambient = 0.05;
  double detail_strength = 0.3;
  std::uint64_t seed = 1;
};

// Paths of the shared terrain imagery under shared_dir (the project's ../shared).
AppearanceOptions DefaultImagery(const std::string& shared_dir);

class Appearance {
 public:
  // kInvalidArgument for a sun elevation outside (0, 90] deg, ambient outside [0, 1], negative
  // weights; kIoError / kCorruptData when a named image cannot be read.
  core::Status Configure(const Terrain& terrain, const AppearanceOptions& options);

  // Radiance factor at a world point; footprint_m is the ground size of one pixel there.
  double Radiance(double x_m, double y_m, double footprint_m) const;
  // Radiance at four points at once: the same texture, its octaves evaluated one point per lane
  // of 4-lane vectors (an octave costs a few vector operations for all four).
  void Radiance4(const double* x_m, const double* y_m, const double* footprint_m,
                 double* radiance) const;

  // Radiance4 for four points given in grid units relative to the node (base_i, base_j)
  // (x = OriginM() + (base_i + gx) CellM(), likewise y), all in single precision: relative
  // positions stay small, so a float resolves ~1e-5 cell over +-250 cells. The points must lie
  // inside the grid (no clamping of the position, only of the indices, for memory safety).
  using V4f [[gnu::vector_size(16)]] = float;
  using V4i [[gnu::vector_size(16)]] = std::int32_t;
  V4f Radiance4Grid(std::int32_t base_i, std::int32_t base_j, V4f gx, V4f gy,
                    V4f footprint_m) const;

  double OriginM() const { return origin_m_; }
  double CellM() const { return cell_m_; }
  // Per-node grids (row-major like Terrain::Heights()).
  const std::vector<float>& Albedo() const { return albedo_; }
  const std::vector<float>& Shaded() const { return shaded_; }
  const std::vector<std::uint8_t>& Lit() const { return lit_; }
  std::int32_t Size() const { return size_; }

 private:
  core::Status Build(const Terrain& terrain, const AppearanceOptions& options);
  // detail(x, y) for four points: lattice cell (di, dj) and in-cell fraction (cfx, cfy) of the
  // first octave, pixels per first-octave wavelength lane_ratio.
  V4f Detail4(V4i di, V4i dj, V4f cfx, V4f cfy, V4f lane_ratio) const;
  // One detail octave in four lanes (the lanes are points in Detail4, octaves in Radiance):
  // weight (0 below 1.5 px per wavelength, smoothstep to 1 at 3 px) x amplitude x the
  // smoothstep-bilinear lattice value at lattice cell (cell_x, cell_y) + floor(s), fraction
  // s - floor(s), for the in-cell position s = (sx, sy) >= 0 in the octave's wavelengths.
  V4f OctaveDetail4(V4f lane_ratio, V4f sx, V4f sy, V4i cell_x, V4i cell_y, V4f amplitude) const;

  static constexpr int kDetailOctaves = 8;
  static constexpr std::int32_t kLatticeSize = 512;  // power of two
  static constexpr std::int32_t kLatticeStride = kLatticeSize + 1;

  AppearanceOptions options_;
  std::int32_t size_ = 0;
  double origin_m_ = 0.0;
  double cell_m_ = 1.0;
  double inv_cell_m_ = 1.0;
  std::vector<float> albedo_;
  std::vector<float> shaded_;
  std::vector<std::uint8_t> lit_;
  std::vector<float> lattice_;  // kLatticeSize^2 values in [-1, 1), row stride kLatticeStride
  // Per octave o, stored as [o / 4][o % 4] (four-lane groups): lattice offsets and amplitude
  // detail_strength 2^(-o/2).
  V4i octave_offset_x_[kDetailOctaves / 4] = {};
  V4i octave_offset_y_[kDetailOctaves / 4] = {};
  V4f octave_amplitude_[kDetailOctaves / 4] = {};
};

}  // namespace swf::sim
