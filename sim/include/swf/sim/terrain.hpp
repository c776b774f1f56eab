// Terrain: the simulated landing area as a height field with exact ground truth.
//
// Grid: size x size nodes, spacing cell_m, centred on the world origin: node (i, j) sits at
//   x = (i - (size-1)/2) cell_m,  y = (j - (size-1)/2) cell_m,   heights[j * size + i]
// and h(x, y) between nodes is bilinear. Layers, each deterministic from the seed:
//   1. tilt: the plane tilt_x * x + tilt_y * y (exact-slope tests);
//   2. multi-scale relief: fractional-Brownian value noise, octaves of wavelength
//      largest_wavelength_m / 2^o down to 4 cells, amplitude ~ wavelength^hurst, scaled to
//      relief_rms_m;
//   3. craters: cumulative size-frequency distribution N(>D) = density_at_1m * D^-sfd_exponent per
//      m^2 (D in metres) between min and max diameter (exponent 2: the lunar equilibrium slope of
//      small craters, Gault 1970), at uniform positions. Profile (r from the centre, R = D/2,
//      depth d = depth_ratio D f, rim height h = rim_ratio D f, freshness f uniform in
//      [min_freshness, 1]; Pike 1977 gives d/D ~ 0.2, h/D ~ 0.04 for fresh simple craters):
//         r <= R:       dz = h + d ((r/R)^2 - 1)            (parabolic bowl)
//         R < r < 3R:   dz = h ((R/r)^3 - 1/27) / (1 - 1/27)  (ejecta blanket, 0 at 3R)
//   4. rocks: the Golombek & Rapp (1997) model: the cumulative fractional area covered by rocks of
//      diameter >= D is F_k(D) = k exp(-q(k) D), q(k) = 1.79 + 0.152 / k. The number density
//      follows from n(D) pi D^2 / 4 = -dF/dD. Rocks between min and max diameter are drawn at
//      uniform positions (expected count, rounded), shaped as half-ellipsoid domes of height
//      height_ratio * D (Golombek et al. 2003: ~0.5) resting on the surface below them.
// The crater and rock lists are the exact truth; the height field is rasterized from them.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/sim/surface.hpp"

namespace swf::sim {

struct CraterOptions {
  double density_at_1m = 0.0;  // N(>1 m) per m^2; 0 disables craters
  double sfd_exponent = 2.0;
  double min_diameter_m = 1.0;
  double max_diameter_m = 40.0;
  double depth_ratio = 0.2;
  double rim_ratio = 0.04;
  double min_freshness = 0.3;
};

struct RockOptions {
  double k = 0.0;  // Golombek-Rapp cumulative fractional area; 0 disables rocks
  double min_diameter_m = 0.3;
  double max_diameter_m = 2.5;
  double height_ratio = 0.5;
  // Lab-scale models: the drawn rock (diameters above are model units, metres at scale 1) is
  // scaled by this factor, keeping the fractional area covered.
  double size_scale = 1.0;
};

struct TerrainOptions {
  std::int32_t size = 2048;  // nodes per side
  double cell_m = 0.1;
  double tilt_x = 0.0;  // dz/dx of a plane under everything
  double tilt_y = 0.0;
  double relief_rms_m = 0.5;
  double relief_hurst = 0.8;
  double largest_wavelength_m = 200.0;
  CraterOptions craters;
  RockOptions rocks;
  std::uint64_t seed = 1;
};

enum class TerrainPreset : std::uint8_t { kSmoothPlains, kCraterField, kRockField };

// Presets at the paper's EDL scale (cell 0.1 m, 204.8 m square). For the lab rig, scale cell_m
// and every length by 0.1 (ScaleTerrain).
TerrainOptions TerrainPresetOptions(TerrainPreset preset, std::uint64_t seed = 1);
TerrainOptions ScaleTerrain(const TerrainOptions& options, double factor);
// "plains" | "craters" | "rocks"; false for an unknown name.
bool ParseTerrainPreset(const char* name, TerrainPreset* preset);

struct Crater {
  Eigen::Vector2d center_m{0.0, 0.0};
  double diameter_m = 0.0;
  double depth_m = 0.0;
  double rim_height_m = 0.0;
};

struct Rock {
  Eigen::Vector2d center_m{0.0, 0.0};
  double diameter_m = 0.0;
  double height_m = 0.0;  // above the surface the rock rests on
  double base_z_m = 0.0;  // that surface's height at the rock centre
};

class Terrain final : public Surface {
 public:
  // kInvalidArgument for size outside [8, 16384], non-positive cell or lengths, bad SFD or rock
  // parameters (k >= 1, min diameter > max, ...).
  core::Status Configure(const TerrainOptions& options);

  double HeightAt(double x_m, double y_m) const override;
  // Exact first hit of the ray with the bilinear surface: the ray descends a two-level max-height
  // pyramid (2 x 2 cell blocks, 64 x 64 cell super blocks), skipping every block it passes above;
  // in each remaining cell the height along the ray is a quadratic in t (bilinear patch), whose
  // smallest root in the cell is solved in closed form (no iteration, no tolerance).
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                 double* t) const override;
  // The same first hit for a ray whose path between the heights top_m and bottom_m only crosses
  // ground with heights in [bottom_m, top_m] (e.g. the range HeightRangeInBox gives for a box
  // holding that path): the walk covers only that stretch of the ray, at cell level when it is
  // short, instead of the whole range from the global maximum down to the global minimum. With
  // top_m >= MaxHeightM() and bottom_m <= MinHeightM() this is Intersect.
  bool IntersectBetween(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                        double top_m, double bottom_m, double* t) const;
  // A ray in grid units: grid x = gx0 + t dgx, y = gy0 + t dgy, height z = oz + t dz.
  struct GridRay {
    double gx0, gy0, dgx, dgy, oz, dz;
  };
  // The first hit of a descending ray (dz < 0) with t in [ta, tb], ta < tb, for a segment that
  // lies inside the grid (IntersectBetween after its clipping; a renderer that clipped whole
  // tiles calls it directly).
  bool IntersectSpan(const GridRay& ray, double ta, double tb, double* t) const;
  // Four rays from one origin (pixels of a tile row) at once, in single precision in the lanes of
  // 4-lane vectors (GCC vector extensions: SSE2 / NEON): IntersectSpan for each where the segment
  // [ta, tb] touches one cell or two neighbours, with the same closed-form root per cell; *walk
  // marks the rays whose segment needs the pyramid walk (left to IntersectSpan). Grid positions
  // are relative to the node (base_i, base_j) so that they stay small: a float then resolves
  // ~1e-5 cell over +-200 cells. *t is the hit parameter, NaN where there is none.
  using V4f [[gnu::vector_size(16)]] = float;
  using V4i [[gnu::vector_size(16)]] = std::int32_t;
  struct GridRays4 {
    std::int32_t base_i, base_j;
    float gx0, gy0, oz;  // origin: grid position relative to the base node, height
    V4f dgx, dgy, dz, ta, tb;
  };
  void IntersectSpan4(const GridRays4& rays, V4f* t, V4i* walk) const;
  // IntersectSpan4 in two steps, so that a caller can gather the second cells of many rays into
  // full vectors (most groups of four have only one or two rays that cross into a neighbour and
  // miss the first cell): the first step solves the first cell of every ray and marks in
  // second->pending the rays left to solve in the neighbour second->(i, j) from second->t0 to tb;
  // IntersectSecondCells4 solves those (for lanes packed from any GridRays4 of the same origin).
  struct SecondCells4 {
    V4i pending;
    V4i i, j;  // relative to the base node, like GridRays4
    V4f t0;
  };
  void IntersectSpan4(const GridRays4& rays, V4f* t, V4i* walk, SecondCells4* second) const;
  V4f IntersectSecondCells4(const GridRays4& rays, const SecondCells4& second) const;
  // Bounds of the surface height over the box [x0, x1] x [y0, y1] (metres, clamped to the
  // terrain): the minimum and maximum of the max/min-pyramid blocks the box overlaps.
  void HeightRangeInBox(double x0_m, double y0_m, double x1_m, double y1_m, double* lo_m,
                        double* hi_m) const;

  std::int32_t Size() const { return size_; }
  double CellM() const { return options_.cell_m; }
  double NodeX(std::int32_t i) const { return origin_m_ + i * options_.cell_m; }
  double NodeY(std::int32_t j) const { return origin_m_ + j * options_.cell_m; }
  double HalfExtentM() const { return -origin_m_; }
  // Node heights, row-major (j * size + i): the full surface and the surface without rocks.
  const std::vector<float>& Heights() const { return heights_; }
  const std::vector<float>& BaseHeights() const { return base_heights_; }
  double MinHeightM() const { return min_height_m_; }
  double MaxHeightM() const { return max_height_m_; }
  const std::vector<Crater>& Craters() const { return craters_; }
  const std::vector<Rock>& Rocks() const { return rocks_; }
  const TerrainOptions& Options() const { return options_; }

 private:
  double NodeHeight(std::int32_t i, std::int32_t j) const { return heights_[j * size_ + i]; }
  // visit(i, j) for every node of the square within reach_m of center_m on either axis,
  // clamped to the grid (rows j ascending, then i): the nodes a crater or a rock of that reach
  // can raise or lower.
  template <typename Visit>
  void ForEachNodeNear(const Eigen::Vector2d& center_m, double reach_m, Visit visit) const {
    const std::int32_t i0 = FirstNodeFrom(center_m.x() - reach_m);
    const std::int32_t i1 = LastNodeTo(center_m.x() + reach_m);
    const std::int32_t j0 = FirstNodeFrom(center_m.y() - reach_m);
    const std::int32_t j1 = LastNodeTo(center_m.y() + reach_m);
    for (std::int32_t j = j0; j <= j1; ++j) {
      for (std::int32_t i = i0; i <= i1; ++i) visit(i, j);
    }
  }
  // The node index at or below a coordinate / at or above it, clamped to the grid (either axis:
  // the grid is square).
  std::int32_t FirstNodeFrom(double coordinate_m) const;
  std::int32_t LastNodeTo(double coordinate_m) const;
  // Bilinear height in grid coordinates (gx, gy), clamped to the grid.
  double GridHeight(double gx, double gy) const;
  // First root of the ray against the bilinear patch of cell (i, j) for t in [t0, t1].
  // IntersectSpan over more than two cells: the max pyramid walk (kept out of line so that the
  // short cases stay small).
  [[gnu::noinline]] bool WalkSpan(const GridRay& ray, double ta, double tb, double* t) const;
  [[gnu::always_inline]] bool IntersectCell(const GridRay& ray, std::int32_t i, std::int32_t j,
                                            double t0, double t1, double* t) const;
  // IntersectCell for four rays: cells (base + (i, j)) (already clamped to the grid), spans
  // [t0, t1]; the hit parameter where ray k meets the patch, NaN elsewhere.
  V4f IntersectCell4(const GridRays4& rays, V4i i, V4i j, V4f t0, V4f t1) const;

  static constexpr std::int32_t kBlock = 2;   // cells per side of a min/max-height block
  static constexpr std::int32_t kSuper = 32;  // blocks per side of a min/max-height super block

  TerrainOptions options_;
  std::int32_t size_ = 0;
  double origin_m_ = 0.0;
  double inv_cell_m_ = 1.0;
  std::vector<float> heights_;
  std::vector<float> base_heights_;
  std::int32_t blocks_ = 0;
  std::vector<float> block_max_;
  std::vector<float> block_min_;
  std::int32_t supers_ = 0;
  std::vector<float> super_max_;
  std::vector<float> super_min_;
  double min_height_m_ = 0.0;
  double max_height_m_ = 0.0;
  std::vector<Crater> craters_;
  std::vector<Rock> rocks_;
};

}  // namespace swf::sim
