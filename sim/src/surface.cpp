#include "swf/sim/surface.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace swf::sim {

double PlaneWaveSurface::HeightAt(double x_m, double y_m) const {
  const double k = 2.0 * std::numbers::pi / wavelength_m_;
  return base_m_ + amplitude_m_ * std::sin(k * x_m) * std::sin(k * y_m);
}

bool PlaneWaveSurface::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                 double* t) const {
  const double top = base_m_ + std::abs(amplitude_m_);
  const double bottom = base_m_ - std::abs(amplitude_m_);
  if (!(direction.z() < 0.0)) return false;  // only downward rays meet an unbounded height field
  const double t_top = std::max(0.0, (origin.z() - top) / -direction.z());
  const double t_bottom = (origin.z() - bottom) / -direction.z();
  if (t_bottom <= 0.0) return false;
  auto gap = [&](double s) {
    const Eigen::Vector3d p = origin + s * direction;
    return p.z() - HeightAt(p.x(), p.y());
  };
  // March with steps short against the wavelength, then bisect the first sign change.
  const double horizontal = std::hypot(direction.x(), direction.y());
  const double max_step = horizontal > 0.0 ? wavelength_m_ / (32.0 * horizontal) : t_bottom;
  const int steps = std::clamp(static_cast<int>(std::ceil((t_bottom - t_top) / max_step)), 1, 4096);
  double lo = t_top;
  double hi = t_top;
  bool found = false;
  for (int i = 1; i <= steps; ++i) {
    const double s = t_top + (t_bottom - t_top) * i / steps;
    if (gap(s) <= 0.0) {
      hi = s;
      found = true;
      break;
    }
    lo = s;
  }
  if (!found) return false;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (gap(mid) > 0.0 ? lo : hi) = mid;
  }
  *t = 0.5 * (lo + hi);
  return true;
}

}  // namespace swf::sim
