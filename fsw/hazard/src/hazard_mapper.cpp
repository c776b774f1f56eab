// Hazard mapping (see hazard_mapper.hpp for the method).
#include "swf/hazard/hazard_mapper.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "swf/core/portable_math.hpp"

namespace swf::hazard {
namespace {

// count, x, y, z, xx, xy, yy, xz, yz, zz, sigma^2 (the plane fits), then the quadric's: xxx, xxy,
// xyy, yyy, xxxx, xxxy, xxyy, xyyy, yyyy, xxz, xyz, yyz.
constexpr int kSatChannels = 23;

// Fills channels kFirst to kFirst + kChannels - 1 of a summed-area table over an n x n grid whose
// entries lie kSatChannels doubles apart ((n + 1)^2 entries, the first row and column zero); the
// other channels keep what they held. cell_values(c, i, j, v) writes the values of cell c = (i,
// j) to v, or returns false for a cell that adds nothing.
template <int kFirst, int kChannels, typename CellValues>
void FillSummedAreaTable(int n, double* sat, CellValues&& cell_values) {
  static_assert(kFirst >= 0 && kFirst + kChannels <= kSatChannels);
  const std::size_t n1 = static_cast<std::size_t>(n) + 1;
  for (std::size_t i = 0; i < n1; ++i) std::fill_n(sat + i * kSatChannels + kFirst, kChannels, 0.0);
  for (int j = 0; j < n; ++j) {
    double row[kChannels] = {};
    double* out = sat + (static_cast<std::size_t>(j) + 1) * n1 * kSatChannels + kFirst;
    const double* above = sat + static_cast<std::size_t>(j) * n1 * kSatChannels + kFirst;
    for (int k = 0; k < kChannels; ++k) out[k] = 0.0;
    for (int i = 0; i < n; ++i) {
      double v[kChannels];
      if (cell_values(static_cast<std::size_t>(j) * n + i, i, j, v))
        for (int k = 0; k < kChannels; ++k) row[k] += v[k];
      double* o = out + (static_cast<std::size_t>(i) + 1) * kSatChannels;
      const double* a = above + (static_cast<std::size_t>(i) + 1) * kSatChannels;
      for (int k = 0; k < kChannels; ++k) o[k] = a[k] + row[k];
    }
  }
}
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kRadToDeg = 57.29577951308232;
constexpr std::uint16_t kMaxCount = 65535;

// A slope: dz / d(cell) along x and y and their variances.
struct Gradient {
  bool ok = false;
  double b = 0.0, c = 0.0;
  double var_b = 0.0, var_c = 0.0;
};

struct Plane {
  bool ok = false;
  double n = 0.0;
  Gradient gradient;  // var from the mean cell sigma^2 or the residuals
  double rss = 0.0;
};

// Least-squares plane through the window sums s (kSatChannels values). correlation_factor scales
// the stereo noise's share of the slope variance for cells whose errors are correlated
// (CorrelatedSlopeVarianceFactor; 1: independent cells).
Plane FitPlane(const std::array<double, kSatChannels>& s, double min_count,
               double correlation_factor) {
  Plane p;
  const double n = s[0];
  if (n < std::max(3.0, min_count)) return p;
  p.n = n;
  const double mx = s[1] / n;
  const double my = s[2] / n;
  const double mz = s[3] / n;
  const double cxx = s[4] / n - mx * mx;
  const double cxy = s[5] / n - mx * my;
  const double cyy = s[6] / n - my * my;
  const double cxz = s[7] / n - mx * mz;
  const double cyz = s[8] / n - my * mz;
  const double czz = s[9] / n - mz * mz;
  const double det = cxx * cyy - cxy * cxy;
  if (!(det > 1e-6)) return p;
  Gradient& g = p.gradient;
  g.b = (cyy * cxz - cxy * cyz) / det;
  g.c = (cxx * cyz - cxy * cxz) / det;
  const double mean_var = s[10] / n;
  p.rss = std::max(0.0, n * (czz - g.b * cxz - g.c * cyz));
  // Slope variance from the larger of the predicted noise (for correlated cells) and the fit's
  // own residuals. The residuals are mostly relief where they exceed the noise (a rock, a crest
  // in the window), which tilts the plane as a bias, not as a correlated noise: the factor is
  // the stereo error's only.
  const double noise = std::max(correlation_factor * mean_var, p.rss / (n - 3.0 + 1e-9));
  g.var_b = noise / n * (cyy / det);
  g.var_c = noise / n * (cxx / det);
  g.ok = p.ok = true;
  return p;
}

double IntPow(double x, int power) {
  double result = 1.0;
  for (int k = 0; k < power; ++k) result *= x;
  return result;
}

// The least-squares quadric z = a + b u + c v + d u^2 + e u v + f v^2 (u, v: cells from the centre
// (cx, cy) over r) through the window sums s, at its centre: a, and the variance of a per unit
// cell variance ((A^T A)^-1 at a: the centre's leverage).
struct Quadric {
  bool ok = false;
  double centre = 0.0;
  double leverage = 0.0;
  double mean_var = 0.0;
};

Quadric FitQuadric(const std::array<double, kSatChannels>& s, double cx, double cy, int r,
                   double min_count) {
  Quadric q;
  if (s[0] < std::max(6.0, min_count)) return q;
  // The sums of x^p y^q (p + q <= 4) and of x^p y^q z (p + q <= 2) by channel.
  constexpr int kNone = -1;
  constexpr int kMoment[5][5] = {{0, 2, 6, 14, 19},
                                 {1, 5, 13, 18, kNone},
                                 {4, 12, 17, kNone, kNone},
                                 {11, 16, kNone, kNone, kNone},
                                 {15, kNone, kNone, kNone, kNone}};
  constexpr int kMomentZ[3][3] = {{3, 8, 22}, {7, 21, kNone}, {20, kNone, kNone}};
  constexpr double kBinomial[5][5] = {
      {1, 0, 0, 0, 0}, {1, 1, 0, 0, 0}, {1, 2, 1, 0, 0}, {1, 3, 3, 1, 0}, {1, 4, 6, 4, 1}};
  // Moments about the centre, scaled by 1/r per power (u = (x - cx) / r): binomial shifts of the
  // grid-centred sums, each of the 15 (and 6 with z) once.
  double power_x[5];
  double power_y[5];
  double power_r[5];
  for (int k = 0; k < 5; ++k) {
    power_x[k] = IntPow(-cx, k);
    power_y[k] = IntPow(-cy, k);
    power_r[k] = IntPow(static_cast<double>(r), k);
  }
  const auto local = [&](int a, int b, const auto& channel) {
    double sum = 0.0;
    for (int p = 0; p <= a; ++p)
      for (int k = 0; k <= b; ++k)
        sum +=
            kBinomial[a][p] * kBinomial[b][k] * power_x[a - p] * power_y[b - k] * s[channel[p][k]];
    return sum / power_r[a + b];
  };
  double moment[5][5] = {};
  double moment_z[3][3] = {};
  for (int a = 0; a <= 4; ++a)
    for (int b = 0; a + b <= 4; ++b) {
      moment[a][b] = local(a, b, kMoment);
      if (a + b <= 2) moment_z[a][b] = local(a, b, kMomentZ);
    }
  constexpr int kBasis[6][2] = {{0, 0}, {1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}};
  Eigen::Matrix<double, 6, 6> normal;
  Eigen::Matrix<double, 6, 1> rhs;
  for (int k = 0; k < 6; ++k) {
    for (int l = 0; l < 6; ++l)
      normal(k, l) = moment[kBasis[k][0] + kBasis[l][0]][kBasis[k][1] + kBasis[l][1]];
    rhs(k) = moment_z[kBasis[k][0]][kBasis[k][1]];
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-9 * s[0])) return q;
  const Eigen::Matrix<double, 6, 1> theta = ldlt.solve(rhs);
  const Eigen::Matrix<double, 6, 1> leverage = ldlt.solve(Eigen::Matrix<double, 6, 1>::Unit(0));
  q.centre = theta(0);
  q.leverage = leverage(0);
  q.mean_var = s[10] / s[0];
  q.ok = std::isfinite(q.centre) && q.leverage > 0.0;
  return q;
}

// The pose-free variance of a fused cell's height (the relief sigma's stereo part) from its summed
// information and smallest single-frame variance: frames share rho of their error (fused variance
// rho min_k var_k + (1 - rho) / sum_k 1/var_k, exact for equicorrelated frames); landmarks only
// add information.
double FusedVariance(double info, double min_var, double rho) {
  const double shared = min_var > 0.0 ? rho : 0.0;
  return (1.0 - shared) / info + shared * min_var;
}

// The correlation of two cells' errors d cells apart (HazardMapperOptions::
// cell_error_autocorrelation at lags 1, 2, 4, 8, 16 cells; linear between them, 1 at 0, zero from
// 32).
double CellErrorCorrelation(const std::array<double, 5>& at_lags, double d) {
  if (!(d > 0.0)) return 1.0;
  double lag = 1.0;
  for (std::size_t k = 0; k < at_lags.size(); ++k, lag *= 2.0) {
    const double next = k + 1 < at_lags.size() ? at_lags[k + 1] : 0.0;
    if (d < 2.0 * lag) return at_lags[k] + (next - at_lags[k]) * (d - lag) / lag;
  }
  return 0.0;
}

// The variance of a least-squares plane's slope over a full (2r + 1)^2 window of cells whose
// errors are correlated, over the variance the fit states for independent cells: g^T C g / g^T g
// with g_i = x_i (the slope's weights up to a constant) and C_ij = CellErrorCorrelation(|p_i -
// p_j|). Summed by offset: sum_d rho(d) sum_{i, i + d in the window} x_i x_{i + d} (the same along
// y). At least 1.
double CorrelatedSlopeVarianceFactor(const std::array<double, 5>& at_lags, int r) {
  const int side = 2 * r + 1;
  double sum_xx = 0.0;
  for (int x = -r; x <= r; ++x) sum_xx += static_cast<double>(x) * x;
  if (!(sum_xx > 0.0)) return 1.0;
  double sum = 0.0;
  for (int dx = -2 * r; dx <= 2 * r; ++dx) {
    const int a = std::abs(dx);
    double pairs_x = 0.0;  // sum of x (x + a) over x with both in the window (either sign of dx)
    for (int x = -r; x + a <= r; ++x) pairs_x += static_cast<double>(x) * (x + a);
    for (int dy = -2 * r; dy <= 2 * r; ++dy) {
      const double rho = CellErrorCorrelation(at_lags, core::Hypot(dx, dy));
      sum += rho * pairs_x * (side - std::abs(dy));
    }
  }
  return std::max(1.0, sum / (sum_xx * side));
}

// The variance of the 1 m slope's central difference (the mean of a (2p + 1)^2 patch centred r
// cells along an axis, less the mean of the one -r cells along it) for cells whose errors are
// correlated, over its variance for independent cells: g^T C g / g^T g with g = +-1 over the two
// patches and C_ij = CellErrorCorrelation(|p_i - p_j|), summed over every pair of the patches'
// cells (2 (2p + 1)^2 cells: done once per analysis). At least 1.
double CorrelatedDifferenceVarianceFactor(const std::array<double, 5>& at_lags, int r, int p) {
  double sum = 0.0;
  int cells = 0;
  for (int sa = -1; sa <= 1; sa += 2)
    for (int ya = -p; ya <= p; ++ya)
      for (int xa = -p; xa <= p; ++xa) {
        ++cells;
        for (int sb = -1; sb <= 1; sb += 2)
          for (int yb = -p; yb <= p; ++yb)
            for (int xb = -p; xb <= p; ++xb) {
              const double d = core::Hypot(sa * r + xa - sb * r - xb, ya - yb);
              sum += sa * sb * CellErrorCorrelation(at_lags, d);
            }
      }
  return std::max(1.0, sum / cells);
}

// 1-sigma of the position's horizontal error along its worst direction (largest eigenvalue of the
// covariance's world x-y block).
double HorizontalSigma(const Eigen::Matrix<double, 6, 6>& cov) {
  const double a = cov(0, 0);
  const double b = 0.5 * (cov(0, 1) + cov(1, 0));
  const double c = cov(1, 1);
  const double mean = 0.5 * (a + c);
  const double half_diff = 0.5 * (a - c);
  return std::sqrt(std::max(0.0, mean + std::sqrt(half_diff * half_diff + b * b)));
}

// Cells each side of the centre of a square analysis window of +-radius_m (at least 1).
int HalfWindowCells(double radius_m, double cell_m) {
  return std::max(1, static_cast<int>(std::lround(radius_m / cell_m)));
}

// Integral of the half-spheroid profile height sqrt(1 - (x^2 + y^2) / R^2) over [0, x_m] x [0, y_m]
// (a quadrant's rectangle from the rock's centre): in y in closed form, in x by Simpson's rule (64
// intervals; the integrand is smooth except for a square-root edge at x = R, where the error stays
// below 1e-4 of the integral).
double SpheroidQuadrantIntegral(double radius_m, double x_m, double y_m) {
  constexpr int kIntervals = 64;
  const double x_max = std::min(x_m, radius_m);
  if (!(x_max > 0.0) || !(y_m > 0.0)) return 0.0;
  const auto column = [&](double x) {
    const double b2 = std::max(0.0, radius_m * radius_m - x * x);
    const double b = std::sqrt(b2);
    if (b <= 0.0) return 0.0;
    const double y = std::min(y_m, b);
    // integral_0^y sqrt(b^2 - t^2) dt, over R (the profile's unit height).
    const double s = std::sqrt(std::max(0.0, b2 - y * y));
    return 0.5 * (y * s + b2 * std::asin(std::min(1.0, y / b))) / radius_m;
  };
  const double step = x_max / kIntervals;
  double sum = column(0.0) + column(x_max);
  for (int k = 1; k < kIntervals; ++k) sum += (k % 2 == 1 ? 4.0 : 2.0) * column(k * step);
  return sum * step / 3.0;
}

// The first kChannels sums of a summed-area table (entries `stride` values apart, (n + 1)^2 of
// them) over the cells of the (2r + 1)^2 window around (ci, cj), clipped to the n x n grid.
template <int kChannels, typename T>
std::array<T, kChannels> WindowSum(const T* sat, int stride, int n, int ci, int cj, int r) {
  std::array<T, kChannels> s{};
  const int n1 = n + 1;
  const int i0 = std::max(0, ci - r);
  const int j0 = std::max(0, cj - r);
  const int i1 = std::min(n, ci + r + 1);
  const int j1 = std::min(n, cj + r + 1);
  const T* a = sat + (static_cast<std::size_t>(j1) * n1 + i1) * stride;
  const T* b = sat + (static_cast<std::size_t>(j0) * n1 + i1) * stride;
  const T* c = sat + (static_cast<std::size_t>(j1) * n1 + i0) * stride;
  const T* d = sat + (static_cast<std::size_t>(j0) * n1 + i0) * stride;
  for (int k = 0; k < kChannels; ++k) s[k] = a[k] - b[k] - c[k] + d[k];
  return s;
}

// Summed-area tables of the plane and quadric fits' moments, about the grid's centre (where the
// fourth powers stay small enough for the tables' differences) and the elevation z_ref.
void FillFitMoments(int n, const float* elevation, const float* sigma_rel, double z_ref,
                    double* sat) {
  const double grid_centre = 0.5 * (n - 1);
  FillSummedAreaTable<0, kSatChannels>(n, sat, [&](std::size_t c, int i, int j, double* v) {
    if (std::isnan(elevation[c])) return false;
    const double x = i - grid_centre;
    const double y = j - grid_centre;
    const double z = elevation[c] - z_ref;
    const double s = sigma_rel[c];
    const double xx = x * x;
    const double yy = y * y;
    const double moments[kSatChannels] = {
        1.0,        x,       y,          z,       xx,     x * y,     yy,     x * z,
        y * z,      z * z,   s * s,      xx * x,  xx * y, x * yy,    yy * y, xx * xx,
        xx * x * y, xx * yy, x * yy * y, yy * yy, xx * z, x * y * z, yy * z};
    std::copy(moments, moments + kSatChannels, v);
    return true;
  });
}

// The footprint evidence of the "rock possible" test (hazard_mapper.hpp, RockCriterion), once the
// fits are done: per cell with a relief, its count, relief, stereo sigma, that sigma's square
// and the reference quadric's sigma.
constexpr int kCount = 0, kRelief = 1, kStereo = 2, kStereo2 = 3, kFit = 4, kRockChannels = 5;
void FillRockEvidence(int n, const float* rock_m, const float* sigma_rel, const float* relief_sigma,
                      double* sat) {
  FillSummedAreaTable<0, kRockChannels>(n, sat, [&](std::size_t c, int, int, double* v) {
    if (std::isnan(rock_m[c])) return false;
    const double stereo = sigma_rel[c];
    const double total = relief_sigma[c];
    v[kCount] = 1.0;
    v[kRelief] = rock_m[c];
    v[kStereo] = stereo;
    v[kStereo2] = stereo * stereo;
    v[kFit] = std::sqrt(std::max(0.0, total * total - stereo * stereo));
    return true;
  });
}

// Can a rock of the threshold size stand with its centre in cell (ci, cj)? Where the whole box
// has a relief: its mean relief + k sigma against the threshold rock's box relief; else the
// cell alone against the threshold rock's cell relief (the test at one cell's scale).
bool RockPossible(const double* sat, int n, const RockCriterion& rocks, double k,
                  const float* rock_m, const float* relief_sigma, int ci, int cj) {
  const std::size_t c = static_cast<std::size_t>(cj) * n + ci;
  const int half_box = (rocks.FootprintCells() - 1) / 2;
  const double box_cells = static_cast<double>(rocks.FootprintCells()) * rocks.FootprintCells();
  if (ci - half_box >= 0 && cj - half_box >= 0 && ci + half_box < n && cj + half_box < n) {
    const std::array<double, kRockChannels> box =
        WindowSum<kRockChannels>(sat, kSatChannels, n, ci, cj, half_box);
    if (box[kCount] >= box_cells - 0.5) {
      const double mean = box[kRelief] / box_cells;
      const double sigma = rocks.FootprintSigma(box[kStereo], box[kStereo2], box[kFit]);
      return mean + k * sigma > rocks.FootprintRelief();
    }
  }
  return rock_m[c] + k * relief_sigma[c] > rocks.ThresholdRelief();
}

// The summed-area table of declared rocks ((n + 1)^2, row 0 and column 0 stay 0), from which the
// 1 m slope's patches leave out the cells near a declared rock (FillLocalSlopeMoments).
void CountDeclaredRocks(int n, const HazardClass* cls, std::int32_t* rock_sat) {
  const int n1 = n + 1;
  for (int j = 0; j < n; ++j) {
    std::int32_t row = 0;
    for (int i = 0; i < n; ++i) {
      row += cls[static_cast<std::size_t>(j) * n + i] == HazardClass::kRock ? 1 : 0;
      rock_sat[static_cast<std::size_t>(j + 1) * n1 + i + 1] =
          rock_sat[static_cast<std::size_t>(j) * n1 + i + 1] + row;
    }
  }
}

// The 1 m slope's patch sums (hazard_mapper.hpp, step 4) after the rock decisions, in the channels
// after the rock evidence's: per known cell farther than rock_cells (square) from every declared
// rock, its count, x, y, height above z_ref and stereo variance. A 1 m height difference across a
// rock is the rock's, a hazard already, and the truth's slopes are the rock-free surface's: the
// rock's cells and its flanks (the profile beyond its declared cells: Analyze) are left out
// of the patch means, not the whole slope test (until issue 16's every-2nd-frame campaigns the 1 m
// slope was not judged where its window held a declared rock; a false rock on a crater wall then
// let a site within 1.5 m of the wall's 10-25 deg cells: 1024 px campaign run 64).
constexpr int kLocalFirst = kRockChannels, kLocalChannels = 5;
void FillLocalSlopeMoments(int n, const float* elevation, const float* sigma_rel, double z_ref,
                           const std::int32_t* rock_sat, int rock_cells, double* sat) {
  const double grid_centre = 0.5 * (n - 1);
  FillSummedAreaTable<kLocalFirst, kLocalChannels>(
      n, sat, [&](std::size_t c, int i, int j, double* v) {
        if (std::isnan(elevation[c])) return false;
        if (WindowSum<1>(rock_sat, 1, n, i, j, rock_cells)[0] > 0) return false;
        const double s = sigma_rel[c];
        v[0] = 1.0;
        v[1] = i - grid_centre;
        v[2] = j - grid_centre;
        v[3] = elevation[c] - z_ref;
        v[4] = s * s;
        return true;
      });
}

// The summed-area table of the measured 1 m slopes ((n + 1)^2 entries of two channels, row 0 and
// column 0 staying 0): the cells whose 1 m slope was measured, and those of them where a slope
// above the threshold is possible (possible(deg, sigma_deg)).
template <typename Possible>
void CountMeasuredLocalSlopes(int n, const float* local_deg, const float* local_sigma_deg,
                              Possible&& possible, std::int32_t* sat) {
  const std::size_t n1 = static_cast<std::size_t>(n) + 1;
  for (int j = 0; j < n; ++j) {
    std::int32_t row[2] = {0, 0};
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      if (!std::isnan(local_deg[c])) {
        ++row[0];
        row[1] += possible(local_deg[c], local_sigma_deg[c]) ? 1 : 0;
      }
      std::int32_t* out = sat + 2 * ((static_cast<std::size_t>(j) + 1) * n1 + i + 1);
      const std::int32_t* above = sat + 2 * (static_cast<std::size_t>(j) * n1 + i + 1);
      out[0] = above[0] + row[0];
      out[1] = above[1] + row[1];
    }
  }
}

}  // namespace

RockCriterion::RockCriterion(const RockCriterionOptions& options, double cell_m)
    : options_(options), cell_m_(cell_m) {
  // The quadric's weights of the cells for its value at the centre of a whole window of m x m
  // cells: w_i = alpha + beta (x_i^2 + y_i^2) (cells; by symmetry), from sum w = 1 and sum w x^2
  // = 0: alpha m^2 + 2 beta m S2 = 1, alpha m S2 + beta (m S4 + S2^2) = 0 (S2, S4 the sums of
  // x^2, x^4 over one side).
  const int half = HalfWindowCells(options.window_radius_m, cell_m);
  const double m = 2 * half + 1;
  double s2 = 0.0;
  double s4 = 0.0;
  for (int x = -half; x <= half; ++x) {
    s2 += static_cast<double>(x) * x;
    s4 += static_cast<double>(x) * x * x * x;
  }
  const double ratio = -m * s2 / (m * s4 + s2 * s2);  // beta / alpha
  lift_alpha_ = 1.0 / (m * m + 2.0 * m * s2 * ratio);
  lift_beta_ = ratio * lift_alpha_;
  const double h = options.max_height_m;
  const double d = h / options.height_to_diameter;
  threshold_relief_m_ = Relief(h, d);
  resolved_sigma_m_ = threshold_relief_m_ / (options.false_alarm_sigmas + options.detection_sigmas);
  // The footprint box: the odd side m (up to the rock's diameter plus a cell) that maximizes the
  // threshold rock's box relief over the box mean's sigma, r_m m / sqrt(1 + (m^2 - 1) rho).
  const double rho = options.relief_error_correlation;
  const int max_side = 2 * static_cast<int>(std::ceil(0.5 * d / cell_m)) + 1;
  double best = -1.0;
  for (int m = 1; m <= max_side; m += 2) {
    const double r = BoxRelief(h, d, m);
    const double snr = r * m / std::sqrt(1.0 + (m * m - 1.0) * rho);
    if (snr > best) {
      best = snr;
      footprint_cells_ = m;
      footprint_relief_m_ = r;
    }
  }
}

double RockCriterion::Relief(double height_m, double diameter_m) const {
  return BoxRelief(height_m, diameter_m, 1);
}

double RockCriterion::BoxRelief(double height_m, double diameter_m, int side_cells) const {
  const double radius = 0.5 * diameter_m;
  if (!(height_m > 0.0) || !(radius > 0.0) || side_cells < 1) return 0.0;
  // The box's centre cell has a corner at the rock's centre: the box spans [-a, b] on both axes.
  const double a = 0.5 * (side_cells - 1) * cell_m_;
  const double b = 0.5 * (side_cells + 1) * cell_m_;
  const double integral =
      SpheroidQuadrantIntegral(radius, b, b) + SpheroidQuadrantIntegral(radius, a, b) +
      SpheroidQuadrantIntegral(radius, b, a) + SpheroidQuadrantIntegral(radius, a, a);
  const double side_m = side_cells * cell_m_;
  const double box_mean = height_m * integral / (side_m * side_m);
  // The rock lifts each box cell's reference quadric by sum_i w_i (its cells' mean heights) =
  // (alpha V + beta integral |p - d|^2 h dA / c^2) / c^2 (d the cell's centre from the rock's):
  // V = 2/3 pi R^2 H, integral |p|^2 h dA = 4/15 pi H R^4, the cross term vanishes, and the mean
  // |d|^2 over the box's cells is 2 c^2 mean_k (k + 1/2)^2.
  constexpr double kPi = 3.141592653589793;
  const double volume = 2.0 / 3.0 * kPi * radius * radius * height_m;
  const double second_moment = 4.0 / 15.0 * kPi * height_m * radius * radius * radius * radius;
  double mean_offset2 = 0.0;
  const int half = (side_cells - 1) / 2;
  for (int k = -half; k <= half; ++k) mean_offset2 += (k + 0.5) * (k + 0.5) / side_cells;
  mean_offset2 *= 2.0 * cell_m_ * cell_m_;
  const double c2 = cell_m_ * cell_m_;
  const double lift =
      (lift_alpha_ * volume + lift_beta_ * (second_moment + volume * mean_offset2) / c2) / c2;
  return std::max(0.0, box_mean - lift);
}

double RockCriterion::DecisionRelief(double sigma_m) const {
  if (!(sigma_m <= resolved_sigma_m_)) return std::numeric_limits<double>::infinity();
  return threshold_relief_m_ - options_.detection_sigmas * sigma_m;
}

bool RockCriterion::Resolvable(double height_m, double diameter_m, double sigma_m) const {
  if (!(height_m >= options_.max_height_m)) return false;
  return Relief(height_m, diameter_m) - options_.detection_sigmas * sigma_m >=
         DecisionRelief(sigma_m);
}

double RockCriterion::FootprintSigma(double sum_sigma_m, double sum_sigma2_m2,
                                     double sum_plane_sigma_m) const {
  const double n = static_cast<double>(footprint_cells_) * footprint_cells_;
  const double rho = options_.relief_error_correlation;
  const double stereo = ((1.0 - rho) * sum_sigma2_m2 + rho * sum_sigma_m * sum_sigma_m) / (n * n);
  const double plane = sum_plane_sigma_m / n;
  return std::sqrt(std::max(0.0, stereo) + plane * plane);
}

RockCriterionOptions RockCriterionOf(const HazardMapperOptions& options) {
  RockCriterionOptions r;
  r.max_height_m = options.max_rock_height_m;
  r.window_radius_m = options.rock_window_radius_m;
  r.relief_error_correlation = options.relief_error_correlation;
  return r;
}

core::Status HazardMapper::Configure(const HazardMapperOptions& o) {
  configured_ = false;
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(o.camera.fx) || !positive(o.camera.fy) || !positive(o.camera.baseline_m) ||
      !std::isfinite(o.camera.cx) || !std::isfinite(o.camera.cy) || o.image_width < 32 ||
      o.image_height < 32 || (o.downsample != 1 && o.downsample != 2 && o.downsample != 4) ||
      o.grid_cells < 16 || o.grid_cells > 2048 || !positive(o.min_cell_m) ||
      !positive(o.max_cell_m) || o.min_cell_m > o.max_cell_m || !positive(o.pixels_per_cell) ||
      !positive(o.disparity_sigma_px) || o.max_independent_pixels < 1 ||
      !(o.pixels_per_independent >= 1.0) ||
      !(o.frame_error_correlation >= 0.0 && o.frame_error_correlation < 1.0) ||
      !(o.outlier_gate_sigmas >= 0.0) || !std::isfinite(o.outlier_gate_sigmas) ||
      o.outlier_replace_after < 1 || o.outlier_replace_after > 255 ||
      !(o.relief_error_correlation >= 0.0 && o.relief_error_correlation <= 1.0) ||
      !std::all_of(o.cell_error_autocorrelation.begin(), o.cell_error_autocorrelation.end(),
                   [](double r) { return r >= 0.0 && r <= 1.0; }) ||
      !positive(o.max_slope_deg) || !positive(o.max_rock_height_m) ||
      !positive(o.footprint_radius_m) || !positive(o.rock_window_radius_m) ||
      !positive(o.local_slope_baseline_m) || !positive(o.local_slope_patch_m) ||
      !(o.local_slope_patch_m < o.local_slope_baseline_m) || !(o.site_margin_sigmas >= 0.0) ||
      !(o.confidence_k >= 0.0) || !(o.min_known_fraction >= 0.0 && o.min_known_fraction <= 1.0) ||
      !positive(o.clearance_cap_m) || !(o.target_weight >= 0.0) || !(o.site_hysteresis >= 0.0) ||
      o.max_landmarks < 0 || o.min_calibration_landmarks < 3 || !std::isfinite(o.ground_z_hint_m) ||
      !o.target_world_m.allFinite() || !(o.min_confidence >= 0.0f && o.min_confidence <= 1.0f)) {
    return core::Status::kInvalidArgument;
  }
  options_ = o;
  work_w_ = o.image_width;
  work_h_ = o.image_height;
  for (int d = o.downsample; d > 1; d /= 2) {
    work_w_ = (work_w_ + 1) / 2;
    work_h_ = (work_h_ + 1) / 2;
  }
  SgmOptions so;
  so.max_width = work_w_;
  so.max_height = work_h_;
  so.max_disparities = o.max_disparities;
  so.paths = o.sgm_paths;
  so.p1 = o.sgm_p1;
  so.p2 = o.sgm_p2;
  so.uniqueness = o.uniqueness;
  if (core::Status s = sgm_.Configure(so); s != core::Status::kOk) return s;
  const std::size_t half = static_cast<std::size_t>((o.image_width + 1) / 2) *
                           static_cast<std::size_t>((o.image_height + 1) / 2);
  left_small_.assign(half, 0);
  right_small_.assign(half, 0);
  tmp_small_.assign(half, 0);
  n_ = o.grid_cells;
  const std::size_t cells = static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_);
  info_.assign(cells, 0.0);
  info_z_.assign(cells, 0.0);
  min_var_.assign(cells, 0.0);
  count_.assign(cells, 0);
  rejections_.assign(cells, 0);
  f_rejections_.assign(cells, 0);
  datum_diff_.assign(cells, 0.0);
  f_w_.assign(cells, 0.0);
  f_wz_.assign(cells, 0.0);
  f_min_var_.assign(cells, 0.0);
  f_n_.assign(cells, 0);
  const std::size_t nl = static_cast<std::size_t>(std::max(o.max_landmarks, 1));
  calib_abs_.assign(nl, 0.0);
  calib_var_.assign(nl, 0.0);
  calib_model_.assign(nl, 0.0);
  active_.assign(nl, ActiveLandmark{});
  incoming_.assign(nl, ActiveLandmark{});
  lm_info_.assign(cells, 0.0);
  lm_info_z_.assign(cells, 0.0);
  elevation_.assign(cells, kNaN);
  sigma_.assign(cells, kNaN);
  sigma_rel_.assign(cells, kNaN);
  class_.assign(cells, HazardClass::kUnknown);
  slope_deg_.assign(cells, kNaN);
  slope_sigma_deg_.assign(cells, kNaN);
  local_slope_deg_.assign(cells, kNaN);
  local_slope_sigma_deg_.assign(cells, kNaN);
  rock_m_.assign(cells, kNaN);
  relief_sigma_.assign(cells, kNaN);
  rough_m_.assign(cells, kNaN);
  clearance_m_.assign(cells, 0.0f);
  sat_.assign(static_cast<std::size_t>(n_ + 1) * static_cast<std::size_t>(n_ + 1) * kSatChannels,
              0.0);
  rock_sat_.assign(static_cast<std::size_t>(n_ + 1) * static_cast<std::size_t>(n_ + 1), 0);
  local_sat_.assign(2 * static_cast<std::size_t>(n_ + 1) * static_cast<std::size_t>(n_ + 1), 0);
  dt_f_.assign(cells, 0.0f);
  dt_d_.assign(static_cast<std::size_t>(n_), 0.0f);
  dt_z_.assign(static_cast<std::size_t>(n_) + 1, 0.0f);
  dt_v_.assign(static_cast<std::size_t>(n_), 0);
  configured_ = true;
  Reset();
  return core::Status::kOk;
}

void HazardMapper::Reset() {
  started_ = false;
  std::fill(info_.begin(), info_.end(), 0.0);
  std::fill(info_z_.begin(), info_z_.end(), 0.0);
  std::fill(min_var_.begin(), min_var_.end(), 0.0);
  std::fill(count_.begin(), count_.end(), 0);
  std::fill(rejections_.begin(), rejections_.end(), 0);
  num_active_ = 0;
  std::fill(elevation_.begin(), elevation_.end(), kNaN);
  std::fill(sigma_.begin(), sigma_.end(), kNaN);
  std::fill(sigma_rel_.begin(), sigma_rel_.end(), kNaN);
  std::fill(class_.begin(), class_.end(), HazardClass::kUnknown);
  std::fill(slope_deg_.begin(), slope_deg_.end(), kNaN);
  std::fill(local_slope_deg_.begin(), local_slope_deg_.end(), kNaN);
  std::fill(rock_m_.begin(), rock_m_.end(), kNaN);
  std::fill(relief_sigma_.begin(), relief_sigma_.end(), kNaN);
  std::fill(rough_m_.begin(), rough_m_.end(), kNaN);
  std::fill(clearance_m_.begin(), clearance_m_.end(), 0.0f);
  site_ = SafeSite{};
  stats_ = HazardStats{};
  cell_m_ = options_.max_cell_m;
  target_ = options_.target_world_m;
  corner_x_ = target_.x() - 0.5 * n_ * cell_m_;
  corner_y_ = target_.y() - 0.5 * n_ * cell_m_;
}

bool HazardMapper::CellOf(double x_m, double y_m, int* i, int* j) const {
  const double fx = (x_m - corner_x_) / cell_m_;
  const double fy = (y_m - corner_y_) / cell_m_;
  if (!(fx >= 0.0 && fy >= 0.0 && fx < n_ && fy < n_)) return false;
  *i = static_cast<int>(fx);
  *j = static_cast<int>(fy);
  return true;
}

void HazardMapper::Reduce(const frontend::GrayView& src, std::vector<std::uint8_t>* dst) const {
  if (options_.downsample == 1) return;
  if (options_.downsample == 2) {
    HalveImage(src, dst->data());
    return;
  }
  std::uint8_t* tmp = const_cast<std::uint8_t*>(tmp_small_.data());
  HalveImage(src, tmp);
  const int w2 = (src.width + 1) / 2;
  const int h2 = (src.height + 1) / 2;
  HalveImage(frontend::GrayView{tmp, w2, h2, w2}, dst->data());
}

void HazardMapper::ChooseRange(const HazardFrame& frame, int* min_d, int* num_d) {
  const double ds = options_.downsample;
  const double fxw = options_.camera.fx / ds;
  const double fb = fxw * options_.camera.baseline_m;
  const Eigen::Matrix3d& world_R_camera = frame.world_T_camera.R;
  const Eigen::Vector3d& t = frame.world_T_camera.t;
  double z_lo = std::numeric_limits<double>::infinity();
  double z_hi = 0.0;
  int in_view = 0;
  const int nl = std::min(frame.num_landmarks, options_.max_landmarks);
  for (int k = 0; k < nl; ++k) {
    const Eigen::Vector3d& p = frame.landmarks[k].position_world_m;
    if (!p.allFinite()) continue;
    const Eigen::Vector3d pc = world_R_camera.transpose() * (p - t);
    if (!(pc.z() > 0.1)) continue;
    const double u = options_.camera.cx + options_.camera.fx * pc.x() / pc.z();
    const double v = options_.camera.cy + options_.camera.fy * pc.y() / pc.z();
    if (u < 0.0 || v < 0.0 || u > options_.image_width - 1 || v > options_.image_height - 1) {
      continue;
    }
    z_lo = std::min(z_lo, pc.z());
    z_hi = std::max(z_hi, pc.z());
    ++in_view;
  }
  if (in_view >= 3) {
    predicted_depth_m_ = std::sqrt(z_lo * z_hi);
    z_lo *= 0.8;
    z_hi *= 1.25;
  } else {
    double ground = options_.ground_z_hint_m;
    double sum = 0.0;
    int known = 0;
    if (started_) {
      for (std::size_t c = 0; c < elevation_.size(); c += 7) {
        if (!std::isnan(elevation_[c])) {
          sum += elevation_[c];
          ++known;
        }
      }
      if (known > 0) ground = sum / known;
    }
    const double axis_z = -world_R_camera(2, 2);  // cosine of the optical axis with straight down
    const double depth = (t.z() - ground) / std::max(axis_z, 0.2);
    predicted_depth_m_ = std::max(depth, 0.5);
    z_lo = std::max(0.5, depth * 0.6);
    z_hi = std::max(z_lo + 0.5, depth * 1.6);
  }
  int lo = static_cast<int>(std::floor(fb / z_hi)) - 2;
  int hi = static_cast<int>(std::ceil(fb / z_lo)) + 2;
  lo = std::max(lo, 0);
  int num = hi - lo + 1;
  if (num > options_.max_disparities) {
    ++stats_.range_clamped;
    const int mid = (lo + hi) / 2;
    num = options_.max_disparities;
    lo = std::max(0, mid - num / 2);
  }
  num = std::max(num, 16);
  num = std::min(num, options_.max_disparities);
  if (lo + num >= work_w_) lo = std::max(0, work_w_ - 1 - num);
  *min_d = lo;
  *num_d = num;
}

// The fused state into the per-frame scratch, from which MaybeRefine and FollowLander rewrite it.
void HazardMapper::CopyStateToScratch() {
  std::copy(info_.begin(), info_.end(), f_w_.begin());
  std::copy(info_z_.begin(), info_z_.end(), f_wz_.begin());
  std::copy(min_var_.begin(), min_var_.end(), f_min_var_.begin());
  std::copy(count_.begin(), count_.end(), f_n_.begin());
  std::copy(rejections_.begin(), rejections_.end(), f_rejections_.begin());
}

void HazardMapper::MaybeRefine(double altitude_m) {
  const double fxw = options_.camera.fx / options_.downsample;
  const double desired = options_.pixels_per_cell * altitude_m / fxw;
  double cell = options_.min_cell_m;
  while (cell * 2.0 <= desired && cell * 2.0 <= options_.max_cell_m * 1.000001) cell *= 2.0;
  if (started_ && cell >= cell_m_ * 0.999) return;
  if (!started_) {
    cell_m_ = cell;
    corner_x_ = target_.x() - 0.5 * n_ * cell_m_;
    corner_y_ = target_.y() - 0.5 * n_ * cell_m_;
    return;
  }
  // Resample the fused state onto the finer grid (same centre: the target's, or the lander's
  // nadir when the grid follows it).
  const double centre_x = corner_x_ + 0.5 * n_ * cell_m_;
  const double centre_y = corner_y_ + 0.5 * n_ * cell_m_;
  CopyStateToScratch();
  const double old_cell = cell_m_;
  const double old_cx = corner_x_;
  const double old_cy = corner_y_;
  const double ratio = old_cell / cell;
  const double scale = 1.0 / (ratio * ratio);
  cell_m_ = cell;
  corner_x_ = centre_x - 0.5 * n_ * cell_m_;
  corner_y_ = centre_y - 0.5 * n_ * cell_m_;
  for (int j = 0; j < n_; ++j) {
    const double y = corner_y_ + (j + 0.5) * cell_m_;
    const int oj = static_cast<int>(std::floor((y - old_cy) / old_cell));
    for (int i = 0; i < n_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      const double x = corner_x_ + (i + 0.5) * cell_m_;
      const int oi = static_cast<int>(std::floor((x - old_cx) / old_cell));
      if (oi < 0 || oj < 0 || oi >= n_ || oj >= n_) {
        info_[c] = info_z_[c] = min_var_[c] = 0.0;
        count_[c] = 0;
        rejections_[c] = 0;
        continue;
      }
      const std::size_t o = static_cast<std::size_t>(oj) * n_ + oi;
      info_[c] = f_w_[o] * scale;
      info_z_[c] = f_wz_[o] * scale;
      min_var_[c] = f_min_var_[o] / scale;
      count_[c] = static_cast<std::uint16_t>(f_n_[o]);
      rejections_[c] = f_rejections_[o];
    }
  }
  site_.valid = site_.valid && CellOf(site_.position_world_m.x(), site_.position_world_m.y(),
                                      &dt_v_[0], &dt_v_[0]);
}

// Recentres the grid on the nadir by whole cells (the lattice, and so every kept cell's state,
// is unchanged): cell (i, j) takes the state of old cell (i + di, j + dj); cells from outside the
// old grid start empty.
void HazardMapper::FollowLander(const Eigen::Vector2d& nadir_world_m) {
  const double half = 0.5 * n_ * cell_m_;
  const double shift_x = std::round((nadir_world_m.x() - (corner_x_ + half)) / cell_m_);
  const double shift_y = std::round((nadir_world_m.y() - (corner_y_ + half)) / cell_m_);
  // A shift of a whole grid or more empties it (clamped before the integer conversion).
  const long di = static_cast<long>(std::clamp(shift_x, -1.0 * n_, 1.0 * n_));
  const long dj = static_cast<long>(std::clamp(shift_y, -1.0 * n_, 1.0 * n_));
  stats_.grid_shift_cells[0] = static_cast<int>(di);
  stats_.grid_shift_cells[1] = static_cast<int>(dj);
  if (di == 0 && dj == 0) return;
  CopyStateToScratch();
  const std::uint64_t known_before = static_cast<std::uint64_t>(
      std::count_if(info_.begin(), info_.end(), [](double w) { return w > 0.0; }));
  std::uint64_t kept = 0;
  for (int j = 0; j < n_; ++j) {
    const long oj = j + dj;
    for (int i = 0; i < n_; ++i) {
      const long oi = i + di;
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      if (oi < 0 || oj < 0 || oi >= n_ || oj >= n_) {
        info_[c] = info_z_[c] = min_var_[c] = 0.0;
        count_[c] = 0;
        rejections_[c] = 0;
        continue;
      }
      const std::size_t o = static_cast<std::size_t>(oj) * n_ + static_cast<std::size_t>(oi);
      info_[c] = f_w_[o];
      info_z_[c] = f_wz_[o];
      min_var_[c] = f_min_var_[o];
      count_[c] = static_cast<std::uint16_t>(f_n_[o]);
      rejections_[c] = f_rejections_[o];
      kept += f_w_[o] > 0.0 ? 1 : 0;
    }
  }
  stats_.cells_dropped += known_before - kept;
  corner_x_ += shift_x * cell_m_;
  corner_y_ += shift_y * cell_m_;
}

void HazardMapper::CalibrateDisparitySigma(const HazardFrame& frame) {
  disparity_scale_ = 1.0;
  stats_.calibration_landmarks = 0;
  stats_.disparity_scale = 1.0;
  if (!options_.calibrate_disparity_sigma) return;
  const double ds = options_.downsample;
  const double fxw = options_.camera.fx / ds;
  const double fb = fxw * options_.camera.baseline_m;
  const Eigen::Matrix3d& world_R_camera = frame.world_T_camera.R;
  const Eigen::Vector3d& t = frame.world_T_camera.t;
  const int nl = std::min(frame.num_landmarks, options_.max_landmarks);
  int m = 0;
  for (int k = 0; k < nl; ++k) {
    const HazardLandmark& l = frame.landmarks[k];
    if (!l.position_world_m.allFinite() || !l.covariance.allFinite()) continue;
    const Eigen::Vector3d pc = world_R_camera.transpose() * (l.position_world_m - t);
    if (!(pc.z() > 0.1)) continue;
    const int u = static_cast<int>(
        std::lround((options_.camera.cx + options_.camera.fx * pc.x() / pc.z()) / ds));
    const int v = static_cast<int>(
        std::lround((options_.camera.cy + options_.camera.fy * pc.y() / pc.z()) / ds));
    if (u < 0 || v < 0 || u >= sgm_.Width() || v >= sgm_.Height()) continue;
    const float d = sgm_.DisparityAt(u, v);
    const float q = sgm_.ConfidenceAt(u, v);
    if (!(d > 0.5f) || q < options_.min_confidence) continue;
    const double dl = fb / pc.z();
    // Depth variance of the landmark (camera z), mapped to disparity: sigma_d = d sigma_z / z.
    const Eigen::Vector3d ez = world_R_camera.col(2);
    const double var_z = std::max(0.0, ez.dot(l.covariance * ez));
    calib_abs_[m] = std::fabs(d - dl);
    calib_var_[m] = var_z * (dl / pc.z()) * (dl / pc.z());
    calib_model_[m] = options_.disparity_sigma_px * (2.0 - q);
    ++m;
  }
  stats_.calibration_landmarks = m;
  if (m < options_.min_calibration_landmarks) return;
  const auto median = [m](std::vector<double>* v) {
    auto mid = v->begin() + m / 2;
    std::nth_element(v->begin(), mid, v->begin() + m);
    return *mid;
  };
  const double spread = 1.4826 * median(&calib_abs_);
  const double own = median(&calib_var_);
  const double model = median(&calib_model_);
  const double measured = std::sqrt(std::max(0.0, spread * spread - own));
  disparity_scale_ = std::max(1.0, measured / std::max(model, 1e-6));
  stats_.disparity_scale = disparity_scale_;
}

void HazardMapper::FuseStereo(const HazardFrame& frame) {
  const std::size_t cells = info_.size();
  std::fill(f_w_.begin(), f_w_.end(), 0.0);
  std::fill(f_wz_.begin(), f_wz_.end(), 0.0);
  std::fill(f_n_.begin(), f_n_.end(), 0);
  const double ds = options_.downsample;
  const double fxw = options_.camera.fx / ds;
  const double fyw = options_.camera.fy / ds;
  const double cxw = options_.camera.cx / ds;
  const double cyw = options_.camera.cy / ds;
  const double fb = fxw * options_.camera.baseline_m;
  const Eigen::Matrix3d& world_R_camera = frame.world_T_camera.R;
  const Eigen::Vector3d& t = frame.world_T_camera.t;
  const int w = sgm_.Width();
  const int h = sgm_.Height();
  int valid = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float d = sgm_.DisparityAt(u, v);
      const float q = sgm_.ConfidenceAt(u, v);
      if (!(d > 0.5f) || q < options_.min_confidence) continue;
      const double z = fb / d;
      const Eigen::Vector3d ray((u - cxw) / fxw, (v - cyw) / fyw, 1.0);
      const Eigen::Vector3d pc = z * ray;
      const Eigen::Vector3d pw = world_R_camera * pc + t;
      int i = 0;
      int j = 0;
      if (!CellOf(pw.x(), pw.y(), &i, &j)) continue;
      const double sigma_d = disparity_scale_ * options_.disparity_sigma_px * (2.0 - q);
      const double sigma_z = z * z * sigma_d / fb;
      const double vertical = std::fabs(world_R_camera.row(2).dot(ray));
      const double sigma_e = std::max(vertical * sigma_z, 1e-4);
      const double wgt = 1.0 / (sigma_e * sigma_e);
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      f_w_[c] += wgt;
      f_wz_[c] += wgt * pw.z();
      ++f_n_[c];
      ++valid;
    }
  }
  stats_.valid_pixels = valid;
  // The frame's cells: elevation and stereo variance (pose-free: the pose error is common to the
  // whole frame and is taken out below).
  for (std::size_t c = 0; c < cells; ++c) {
    const int n = f_n_[c];
    if (n == 0) continue;
    const double n_ind = std::clamp(n / options_.pixels_per_independent, 1.0,
                                    static_cast<double>(options_.max_independent_pixels));
    f_wz_[c] /= f_w_[c];
    f_w_[c] = (1.0 / f_w_[c]) * static_cast<double>(n) / std::min<double>(n, n_ind);
  }
  // The frame's pose error is one error shared by all its cells (mostly vertical: the position's
  // vertical error; the attitude's tilt over a map is millimetres). Frames fused with different
  // weights per cell would turn their different pose errors into relief that no stereo sigma
  // accounts for, so the map is moved onto this frame's datum before fusing: the offset is the
  // inverse-variance mean of (frame - map) over the cells both hold. The map then carries the
  // newest pose's vertical error (Analyze adds it to the elevation sigma), and its relief only
  // the stereo's. Cells outside the outlier gate (below) are left out of the offset: their
  // differences are gross errors, not the datum.
  const double gate2 = options_.outlier_gate_sigmas * options_.outlier_gate_sigmas;
  const auto outside_gate = [&](std::size_t c, double offset) {
    if (!(gate2 > 0.0)) return false;
    const double e = f_wz_[c] - (info_z_[c] / info_[c] + offset);
    return e * e > gate2 * (f_w_[c] +
                            FusedVariance(info_[c], min_var_[c], options_.frame_error_correlation));
  };
  const auto datum_offset = [&](bool gated, double guess) {
    double sum_w = 0.0;
    double sum_wd = 0.0;
    for (std::size_t c = 0; c < cells; ++c) {
      if (f_n_[c] == 0 || !(info_[c] > 0.0)) continue;
      if (gated && outside_gate(c, guess)) continue;
      const double w = 1.0 / (f_w_[c] + 1.0 / info_[c]);
      sum_w += w;
      sum_wd += w * (f_wz_[c] - info_z_[c] / info_[c]);
    }
    return sum_w > 0.0 ? sum_wd / sum_w : 0.0;
  };
  // The gate needs the datum and the datum the gate: the median of (frame - map) first (robust to
  // the outliers, whose small sigmas would pull a weighted mean), then the inverse-variance mean
  // over the cells within the gate around it (with no outlier: the mean over all shared cells).
  double median = 0.0;
  if (gate2 > 0.0) {
    int shared = 0;
    for (std::size_t c = 0; c < cells; ++c) {
      if (f_n_[c] == 0 || !(info_[c] > 0.0)) continue;
      datum_diff_[shared++] = f_wz_[c] - info_z_[c] / info_[c];
    }
    if (shared > 0) {
      const auto mid = datum_diff_.begin() + shared / 2;
      std::nth_element(datum_diff_.begin(), mid, datum_diff_.begin() + shared);
      median = *mid;
    }
  }
  const double offset = datum_offset(gate2 > 0.0, median);
  stats_.datum_shift_m = offset;
  int fused = 0;
  int rejected = 0;
  int replaced = 0;
  for (std::size_t c = 0; c < cells; ++c) {
    info_z_[c] += offset * info_[c];
    const int n = f_n_[c];
    if (n == 0) continue;
    const double var = f_w_[c];
    // Gross outliers (HazardMapperOptions::outlier_gate_sigmas): the frame's cell disagrees with
    // the fused one beyond what both sigmas allow. Once: the frame's cell is the outlier and is
    // not fused. outlier_replace_after frames in a row: the fused cell is, and is replaced.
    if (info_[c] > 0.0 && outside_gate(c, 0.0)) {
      if (++rejections_[c] < options_.outlier_replace_after) {
        ++rejected;
        continue;
      }
      info_[c] = info_z_[c] = min_var_[c] = 0.0;
      count_[c] = 0;
      ++replaced;
    }
    rejections_[c] = 0;
    info_[c] += 1.0 / var;
    info_z_[c] += f_wz_[c] / var;
    min_var_[c] = min_var_[c] > 0.0 ? std::min(min_var_[c], var) : var;
    if (count_[c] < kMaxCount) ++count_[c];
    ++fused;
  }
  stats_.fused_cells = fused;
  stats_.outlier_cells = rejected;
  stats_.replaced_cells = replaced;
  stats_.outliers_rejected += static_cast<std::uint64_t>(rejected);
  stats_.cells_replaced += static_cast<std::uint64_t>(replaced);
}

void HazardMapper::CommitLandmark(double x_m, double y_m, double z_m, double var_m2) {
  int i = 0;
  int j = 0;
  if (!CellOf(x_m, y_m, &i, &j)) return;  // left the grid with its cell
  const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
  info_[c] += 1.0 / var_m2;
  info_z_[c] += z_m / var_m2;
  if (count_[c] < kMaxCount) ++count_[c];
}

// Each landmark enters once (hazard_mapper.hpp, step 3): anonymous ones now; identified ones are
// held at their newest estimate, and the held ones this frame no longer publishes are fused with
// their last estimate, moved onto this frame's datum (datum_shift_m, as the map was).
void HazardMapper::FuseLandmarks(const HazardFrame& frame, double datum_shift_m) {
  int used = 0;
  int incoming = 0;
  for (int k = 0; k < frame.num_landmarks; ++k) {
    if (k >= options_.max_landmarks) {
      stats_.landmarks_rejected += static_cast<std::uint32_t>(frame.num_landmarks - k);
      break;
    }
    const HazardLandmark& l = frame.landmarks[k];
    const double var = l.covariance(2, 2);
    int i = 0;
    int j = 0;
    if (!l.position_world_m.allFinite() || !(var > 0.0) || !std::isfinite(var) ||
        !CellOf(l.position_world_m.x(), l.position_world_m.y(), &i, &j)) {
      ++stats_.landmarks_rejected;
      continue;
    }
    const Eigen::Vector3d& p = l.position_world_m;
    if (l.id < 0) {
      CommitLandmark(p.x(), p.y(), p.z(), var);
      ++used;
      continue;
    }
    incoming_[incoming++] = ActiveLandmark{l.id, k, p.x(), p.y(), p.z(), var};
  }
  const auto by_id = [](const ActiveLandmark& a, const ActiveLandmark& b) {
    return a.id < b.id || (a.id == b.id && a.order < b.order);
  };
  std::sort(incoming_.begin(), incoming_.begin() + incoming, by_id);
  // A repeated id keeps its last entry (the frame's newest).
  int unique = 0;
  for (int k = 0; k < incoming; ++k) {
    if (k + 1 < incoming && incoming_[k + 1].id == incoming_[k].id) {
      ++stats_.landmarks_rejected;
      continue;
    }
    incoming_[unique++] = incoming_[k];
  }
  // A frame without an identified landmark carries no landmark map (the SWF could not publish
  // one): the held landmarks are kept, moved with the map onto this frame's datum. A landmark
  // the SWF published again would otherwise enter twice.
  if (unique == 0) {
    for (int k = 0; k < num_active_; ++k) active_[k].z += datum_shift_m;
    stats_.landmarks_active = num_active_;
    stats_.landmarks_used = used + num_active_;
    return;
  }
  // Held landmarks missing from this frame's map: fused for good.
  int a = 0;
  for (int b = 0; a < num_active_; ++a) {
    const ActiveLandmark& held = active_[a];
    while (b < unique && incoming_[b].id < held.id) ++b;
    if (b < unique && incoming_[b].id == held.id) continue;
    CommitLandmark(held.x, held.y, held.z + datum_shift_m, held.var);
    ++stats_.landmarks_committed;
  }
  std::swap(active_, incoming_);
  num_active_ = unique;
  stats_.landmarks_active = unique;
  stats_.landmarks_used = used + unique;
}

// The held landmarks' information per cell, for Analyze (rebuilt from world positions: the grid
// may have scrolled or been refined since they were published).
void HazardMapper::OverlayActiveLandmarks() {
  std::fill(lm_info_.begin(), lm_info_.end(), 0.0);
  std::fill(lm_info_z_.begin(), lm_info_z_.end(), 0.0);
  for (int k = 0; k < num_active_; ++k) {
    const ActiveLandmark& l = active_[k];
    int i = 0;
    int j = 0;
    if (!CellOf(l.x, l.y, &i, &j)) continue;
    const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
    lm_info_[c] += 1.0 / l.var;
    lm_info_z_[c] += l.z / l.var;
  }
}

// Fuses the frame into the cells: elevation, its pose-free sigma and its sigma with the
// newest pose's datum error, for every cell with information; returns the known cells' mean
// elevation (the fits' origin).
double HazardMapper::FuseCells(const HazardFrame& frame) {
  const std::size_t cells = info_.size();
  double sum = 0.0;
  int known = 0;
  const Eigen::Matrix3d& world_R_camera = frame.world_T_camera.R;
  const Eigen::Vector3d& t = frame.world_T_camera.t;
  const Eigen::Vector3d up_in_camera = world_R_camera.row(2).transpose();
  const Eigen::Matrix<double, 6, 6>& pose_cov = frame.pose_covariance;
  OverlayActiveLandmarks();
  for (std::size_t c = 0; c < cells; ++c) {
    const double info = info_[c] + lm_info_[c];
    if (info > 0.0) {
      elevation_[c] = static_cast<float>((info_z_[c] + lm_info_z_[c]) / info);
      const double var_rel = FusedVariance(info, min_var_[c], options_.frame_error_correlation);
      sigma_rel_[c] = static_cast<float>(std::sqrt(var_rel));
      // The datum: the newest pose's vertical error at this cell (pose update [rho, phi], p_w = R
      // Exp(phi) p_c + t + rho: dz = rho_z + (p_c x R^T e_z) . phi).
      const int ci = static_cast<int>(c % static_cast<std::size_t>(n_));
      const int cj = static_cast<int>(c / static_cast<std::size_t>(n_));
      const Eigen::Vector3d p_w(corner_x_ + (ci + 0.5) * cell_m_, corner_y_ + (cj + 0.5) * cell_m_,
                                elevation_[c]);
      const Eigen::Vector3d a = (world_R_camera.transpose() * (p_w - t)).cross(up_in_camera);
      const double var_datum =
          std::max(0.0, pose_cov(2, 2) + 2.0 * a.dot(pose_cov.block<3, 1>(3, 2)) +
                            a.dot(pose_cov.block<3, 3>(3, 3) * a));
      sigma_[c] = static_cast<float>(std::sqrt(var_rel + var_datum));
      sum += elevation_[c];
      ++known;
    } else {
      elevation_[c] = sigma_[c] = sigma_rel_[c] = kNaN;
    }
  }
  stats_.known_cells = known;
  return known > 0 ? sum / known : 0.0;
}

void HazardMapper::Analyze(const HazardFrame& frame) {
  const double z_ref = FuseCells(frame);
  const double grid_centre = 0.5 * (n_ - 1);
  FillFitMoments(n_, elevation_.data(), sigma_rel_.data(), z_ref, sat_.data());
  const auto window = [&](int ci, int cj, int r) {
    return WindowSum<kSatChannels>(sat_.data(), kSatChannels, n_, ci, cj, r);
  };
  const int rf = HalfWindowCells(options_.footprint_radius_m, cell_m_);
  const int rl = HalfWindowCells(0.5 * options_.local_slope_baseline_m, cell_m_);
  const int pl = std::max(
      0, static_cast<int>(std::lround(0.5 * (options_.local_slope_patch_m / cell_m_ - 1.0))));
  const int rr = HalfWindowCells(options_.rock_window_radius_m, cell_m_);
  const double min_f = options_.min_known_fraction * (2 * rf + 1) * (2 * rf + 1);
  const double min_l = 2 * pl + 1;  // cells of a 1 m slope patch: at least one row's worth
  const double min_r = options_.min_known_fraction * (2 * rr + 1) * (2 * rr + 1);
  const Eigen::Matrix<double, 6, 6>& cov = frame.pose_covariance;
  // Tilt of the map from attitude error: rotations about the horizontal world axes.
  const Eigen::Matrix3d rot_cov =
      frame.world_T_camera.R * cov.block<3, 3>(3, 3) * frame.world_T_camera.R.transpose();
  const double var_tilt = std::max(0.0, rot_cov(0, 0)) + std::max(0.0, rot_cov(1, 1));
  const double k = options_.confidence_k;
  const RockCriterion rocks(RockCriterionOf(options_), cell_m_);
  // The slopes' stereo noise for cells whose errors are correlated over their windows
  // (HazardMapperOptions::cell_error_autocorrelation).
  const double footprint_factor =
      CorrelatedSlopeVarianceFactor(options_.cell_error_autocorrelation, rf);
  const double local_factor =
      CorrelatedDifferenceVarianceFactor(options_.cell_error_autocorrelation, rl, pl);
  // A gradient's slope and its sigma (its own and the map's tilt from attitude error), degrees.
  const auto slope_of = [&](const Gradient& d, double* sigma_deg) {
    const double g = core::Hypot(d.b, d.c) / cell_m_;
    const double var_g = (d.var_b + d.var_c) / (cell_m_ * cell_m_) + var_tilt;
    *sigma_deg = std::sqrt(var_g) / (1.0 + g * g) * kRadToDeg;
    return std::atan(g) * kRadToDeg;
  };
  // The 1 m slope (HazardMapperOptions::local_slope_patch_m): the patch means rl cells either
  // side along x and along y, over the distance of the patches' centroids along that axis (2 rl
  // where both are whole; less where the known area ends inside a patch: a patch counts from one
  // row of known cells, so the slope reaches to within rl - pl + 1 cells of the known area's
  // edge). The variance of a difference of two means of k+ and k- cells of mean variance v+, v-
  // is v+ / k+ + v- / k-, times local_factor for their correlation (that of whole patches: a
  // partial patch's cells are fewer and as close, so it overstates rather than understates).
  // Known: both ends of both axes hold a patch of known cells (the moments' table). Measured:
  // from the patches without the declared rocks' cells (FillLocalSlopeMoments); where an end's
  // cells are all near a rock the slope is not measured (a shorter baseline there, tried, read a
  // crater wall beside a false rock at its flatter end: 2 deg for a true 10 deg).
  const auto local_patches_known = [&](int ci, int cj) {
    const auto known = [&](int a, int b) {
      return a >= 0 && b >= 0 && a < n_ && b < n_ && window(a, b, pl)[0] >= min_l;
    };
    return known(ci + rl, cj) && known(ci - rl, cj) && known(ci, cj + rl) && known(ci, cj - rl);
  };
  const auto local_gradient = [&](int ci, int cj) {
    Gradient d;
    const auto patch = [&](int a, int b) {
      return WindowSum<kLocalChannels>(sat_.data() + kLocalFirst, kSatChannels, n_, a, b, pl);
    };
    const auto difference = [&](int di, int dj, int axis, double* value, double* var) {
      const std::array<double, kLocalChannels> hi = patch(ci + di, cj + dj);
      const std::array<double, kLocalChannels> lo = patch(ci - di, cj - dj);
      if (hi[0] < min_l || lo[0] < min_l) return false;
      const double baseline = hi[axis] / hi[0] - lo[axis] / lo[0];
      *value = (hi[3] / hi[0] - lo[3] / lo[0]) / baseline;
      *var = (hi[4] / (hi[0] * hi[0]) + lo[4] / (lo[0] * lo[0])) * local_factor /
             (baseline * baseline);
      return true;
    };
    d.ok = difference(rl, 0, 1, &d.b, &d.var_b) && difference(0, rl, 2, &d.c, &d.var_c);
    return d;
  };
  // A slope is a hazard where it exceeds the threshold by k sigma and the map resolves it (sigma
  // below a third of the threshold); it cannot be excluded where value + k sigma exceeds it.
  const auto slope_declared = [&](double deg, double sigma_deg) {
    return deg - k * sigma_deg > options_.max_slope_deg &&
           sigma_deg * 3.0 <= options_.max_slope_deg;
  };
  const auto slope_possible = [&](double deg, double sigma_deg) {
    return deg + k * sigma_deg > options_.max_slope_deg;
  };
  int safe = 0;
  int rock = 0;
  int slope = 0;
  int uncertain = 0;
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      slope_deg_[c] = slope_sigma_deg_[c] = rock_m_[c] = relief_sigma_[c] = rough_m_[c] = kNaN;
      local_slope_deg_[c] = local_slope_sigma_deg_[c] = kNaN;
      class_[c] = HazardClass::kUnknown;
      if (std::isnan(elevation_[c])) continue;
      const Plane pf = FitPlane(window(i, j, rf), min_f, footprint_factor);
      const Quadric pr = FitQuadric(window(i, j, rr), i - grid_centre, j - grid_centre, rr, min_r);
      if (!pf.ok || !pr.ok || !local_patches_known(i, j)) continue;
      double slope_sigma_deg = 0.0;
      const double slope_deg = slope_of(pf.gradient, &slope_sigma_deg);
      const double h = (elevation_[c] - z_ref) - pr.centre;
      const double sr = sigma_rel_[c];
      const double sigma_h = std::sqrt(sr * sr + pr.mean_var * pr.leverage);
      slope_deg_[c] = static_cast<float>(slope_deg);
      slope_sigma_deg_[c] = static_cast<float>(slope_sigma_deg);
      rock_m_[c] = static_cast<float>(h);
      relief_sigma_[c] = static_cast<float>(sigma_h);
      rough_m_[c] = static_cast<float>(std::sqrt(pf.rss / pf.n));
      // A rock where the rock criterion's test decides it.
      if (h > rocks.DecisionRelief(sigma_h)) {
        class_[c] = HazardClass::kRock;
        ++rock;
      }
    }
  }
  FillRockEvidence(n_, rock_m_.data(), sigma_rel_.data(), relief_sigma_.data(), sat_.data());
  CountDeclaredRocks(n_, class_.data(), rock_sat_.data());
  // A declared rock's flank: beyond the cells where its relief exceeds the decision relief (at
  // most r_h, the threshold rock's relief on a sharp map), the rock model's profile still stands
  // out to its radius R; for the threshold rock that is R (1 - sqrt(1 - (r_h / h)^2)) (0.18 m at
  // 5 cm cells), less for taller rocks of the model's shape (a larger part of them is declared).
  const RockCriterionOptions criterion = RockCriterionOf(options_);
  const double rock_radius_m = 0.5 * criterion.max_height_m / criterion.height_to_diameter;
  const double declared_fraction = rocks.ThresholdRelief() / criterion.max_height_m;
  const int rock_flank_cells = static_cast<int>(std::ceil(
      rock_radius_m *
      (1.0 - std::sqrt(std::max(0.0, 1.0 - declared_fraction * declared_fraction))) / cell_m_));
  FillLocalSlopeMoments(n_, elevation_.data(), sigma_rel_.data(), z_ref, rock_sat_.data(),
                        rock_flank_cells, sat_.data());
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      if (std::isnan(slope_deg_[c])) continue;
      const Gradient gl = local_gradient(i, j);
      if (!gl.ok) continue;
      double local_sigma_deg = 0.0;
      local_slope_deg_[c] = static_cast<float>(slope_of(gl, &local_sigma_deg));
      local_slope_sigma_deg_[c] = static_cast<float>(local_sigma_deg);
    }
  }
  // Where a rock covers a patch the 1 m slope is not measured, and the ground beside the rock is
  // judged by the ground around it: a slope above the threshold is possible there when it is at a
  // measured cell within rl (the baseline's half; the chords of those cells overlap the hidden
  // one by at least half), or when no cell there is measured. Until the every-2nd-frame campaigns
  // such a cell was not judged at all; taking it as kUncertain instead cost 8 of the 51 rock-field
  // runs of the 512 px every-2nd-frame campaign their site (a 1 m rock leaves a ring of flat
  // ground 0.3-0.7 m from it unmeasured).
  CountMeasuredLocalSlopes(n_, local_slope_deg_.data(), local_slope_sigma_deg_.data(),
                           slope_possible, local_sat_.data());
  // A slope (footprint or 1 m scale) where the map resolves it; elsewhere an exceedance of either
  // threshold is kUncertain.
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      if (class_[c] == HazardClass::kRock || std::isnan(slope_deg_[c])) continue;
      const double slope_deg = slope_deg_[c];
      const double slope_sigma_deg = slope_sigma_deg_[c];
      const double local_deg = local_slope_deg_[c];
      const double local_sigma_deg = local_slope_sigma_deg_[c];
      bool local_declared = false;
      bool local_possible = false;
      if (!std::isnan(local_deg)) {
        local_declared = slope_declared(local_deg, local_sigma_deg);
        local_possible = slope_possible(local_deg, local_sigma_deg);
      } else {
        const std::array<std::int32_t, 2> around = WindowSum<2>(local_sat_.data(), 2, n_, i, j, rl);
        local_possible = around[0] == 0 || around[1] > 0;
      }
      // Where the map resolves the threshold rock, the rock criterion has decided the cell (kRock
      // or not, at its false-alarm and detection rates); a rock is undecided only where it does
      // not, and possible there when the footprint's evidence leaves a threshold rock possible.
      const bool undecided_rock =
          relief_sigma_[c] > rocks.ResolvedSigma() &&
          RockPossible(sat_.data(), n_, rocks, k, rock_m_.data(), relief_sigma_.data(), i, j);
      if (slope_declared(slope_deg, slope_sigma_deg) || local_declared) {
        class_[c] = HazardClass::kSlope;
        ++slope;
      } else if (undecided_rock || slope_possible(slope_deg, slope_sigma_deg) || local_possible) {
        class_[c] = HazardClass::kUncertain;
        ++uncertain;
      } else {
        class_[c] = HazardClass::kSafe;
        ++safe;
      }
    }
  }
  stats_.safe_cells = safe;
  stats_.rock_cells = rock;
  stats_.slope_cells = slope;
  stats_.uncertain_cells = uncertain;
}

// Exact squared Euclidean distance transform (Felzenszwalb & Huttenlocher 2012), rows then
// columns, into clearance_m_.
void HazardMapper::DistanceTransform() {
  const float inf = 1e20f;
  const std::size_t cells = class_.size();
  for (std::size_t c = 0; c < cells; ++c) {
    dt_f_[c] = class_[c] == HazardClass::kSafe ? inf : 0.0f;
  }
  const auto pass = [&](float* base, int step) {
    // 1-D transform of n_ values base[0], base[step], ...
    int k = 0;
    dt_v_[0] = 0;
    dt_z_[0] = -inf;
    dt_z_[1] = inf;
    for (int q = 1; q < n_; ++q) {
      const float fq = base[q * step];
      float s = 0.0f;
      while (true) {
        const int vk = dt_v_[k];
        const float fv = base[vk * step];
        s = ((fq + static_cast<float>(q * q)) - (fv + static_cast<float>(vk * vk))) /
            static_cast<float>(2 * q - 2 * vk);
        if (s <= dt_z_[k] && k > 0) {
          --k;
          continue;
        }
        break;
      }
      if (s <= dt_z_[k]) {  // k == 0 and the new parabola dominates everywhere
        dt_v_[0] = q;
        dt_z_[0] = -inf;
        dt_z_[1] = inf;
        continue;
      }
      ++k;
      dt_v_[k] = q;
      dt_z_[k] = s;
      dt_z_[k + 1] = inf;
    }
    k = 0;
    for (int q = 0; q < n_; ++q) {
      while (dt_z_[k + 1] < static_cast<float>(q)) ++k;
      const float dq = static_cast<float>(q - dt_v_[k]);
      dt_d_[q] = dq * dq + base[dt_v_[k] * step];
    }
    for (int q = 0; q < n_; ++q) base[q * step] = dt_d_[q];
  };
  for (int j = 0; j < n_; ++j) pass(dt_f_.data() + static_cast<std::size_t>(j) * n_, 1);
  for (int i = 0; i < n_; ++i) pass(dt_f_.data() + i, n_);
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      const double border =
          std::min(std::min(i + 0.5, j + 0.5), std::min(n_ - i - 0.5, n_ - j - 0.5));
      const double hazard = dt_f_[c] >= inf * 0.5f ? border : std::sqrt(dt_f_[c]) - 0.5;
      clearance_m_[c] = static_cast<float>(std::max(0.0, std::min(border, hazard)) * cell_m_);
    }
  }
}

void HazardMapper::SelectSite() {
  DistanceTransform();
  const double radius = options_.footprint_radius_m + site_margin_m_;
  const double half_extent = 0.5 * n_ * cell_m_;
  const auto score_of = [&](std::size_t c, int i, int j) {
    const double x = corner_x_ + (i + 0.5) * cell_m_;
    const double y = corner_y_ + (j + 0.5) * cell_m_;
    const double dist = core::Hypot(x - target_.x(), y - target_.y());
    const double clear = std::min<double>(clearance_m_[c], options_.clearance_cap_m);
    const double conf = 1.0 - std::min(1.0, sigma_rel_[c] / options_.max_rock_height_m);
    const double near = 1.0 - std::min(1.0, dist / half_extent);
    return (clear / options_.clearance_cap_m + 0.5 * conf + options_.target_weight * near) /
           (1.5 + options_.target_weight);
  };
  double best = -std::numeric_limits<double>::infinity();
  int best_i = -1;
  int best_j = -1;
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n_ + i;
      if (class_[c] != HazardClass::kSafe || clearance_m_[c] < radius) continue;
      const double s = score_of(c, i, j);
      if (s > best) {
        best = s;
        best_i = i;
        best_j = j;
      }
    }
  }
  if (best_i < 0) {
    site_ = SafeSite{};
    return;
  }
  int pi = 0;
  int pj = 0;
  if (site_.valid && CellOf(site_.position_world_m.x(), site_.position_world_m.y(), &pi, &pj)) {
    const std::size_t c = static_cast<std::size_t>(pj) * n_ + pi;
    if (class_[c] == HazardClass::kSafe && clearance_m_[c] >= radius) {
      const double s = score_of(c, pi, pj);
      if (s >= best - options_.site_hysteresis) {
        best = s;
        best_i = pi;
        best_j = pj;
      }
    }
  }
  const std::size_t c = static_cast<std::size_t>(best_j) * n_ + best_i;
  const Eigen::Vector2d pos(corner_x_ + (best_i + 0.5) * cell_m_,
                            corner_y_ + (best_j + 0.5) * cell_m_);
  const bool same = site_.valid && (pos - site_.position_world_m).norm() < 0.5 * cell_m_ + 1e-9;
  site_.stable_updates = same ? site_.stable_updates + 1 : 0;
  site_.valid = true;
  site_.position_world_m = pos;
  site_.elevation_m = elevation_[c];
  site_.score = best;
  site_.clearance_m = clearance_m_[c];
  site_.slope_deg = slope_deg_[c];
  site_.sigma_m = sigma_[c];
  site_.margin_m = site_margin_m_;
}

core::Status HazardMapper::Update(const HazardFrame& frame) {
  if (!configured_) return core::Status::kNotConfigured;
  const frontend::GrayView& l = frame.left;
  const frontend::GrayView& r = frame.right;
  if (!l.Valid() || !r.Valid() || l.width != options_.image_width ||
      l.height != options_.image_height || r.width != l.width || r.height != l.height ||
      !frame.world_T_camera.R.allFinite() || !frame.world_T_camera.t.allFinite() ||
      !frame.pose_covariance.allFinite() || frame.num_landmarks < 0 ||
      (frame.num_landmarks > 0 && frame.landmarks == nullptr)) {
    return core::Status::kInvalidArgument;
  }
  frontend::GrayView wl = l;
  frontend::GrayView wr = r;
  if (options_.downsample > 1) {
    Reduce(l, &left_small_);
    Reduce(r, &right_small_);
    wl = frontend::GrayView{left_small_.data(), work_w_, work_h_, work_w_};
    wr = frontend::GrayView{right_small_.data(), work_w_, work_h_, work_w_};
  }
  int min_d = 0;
  int num_d = 0;
  ChooseRange(frame, &min_d, &num_d);
  stats_.min_disparity = min_d;
  stats_.num_disparities = num_d;
  if (core::Status s = sgm_.Compute(wl, wr, min_d, num_d); s != core::Status::kOk) return s;
  const double range_m = predicted_depth_m_;
  if (!started_) {
    if (options_.target_from_first_pose) {
      const Eigen::Vector3d axis = frame.world_T_camera.R.col(2);
      const Eigen::Vector3d ground = frame.world_T_camera.t + range_m * axis;
      target_ = ground.head<2>();
    } else {
      target_ = options_.target_world_m;
    }
  }
  MaybeRefine(range_m);
  started_ = true;
  if (options_.grid_follows_lander) {
    const Eigen::Vector3d nadir = frame.world_T_camera.t + range_m * frame.world_T_camera.R.col(2);
    FollowLander(nadir.head<2>());
  }
  CalibrateDisparitySigma(frame);
  FuseStereo(frame);
  FuseLandmarks(frame, stats_.datum_shift_m);
  Analyze(frame);
  site_margin_m_ = options_.site_margin_sigmas * HorizontalSigma(frame.pose_covariance);
  SelectSite();
  ++stats_.updates;
  return core::Status::kOk;
}

}  // namespace swf::hazard
