// Surface: what the measurement generator and the renderer need from the ground, a height field
// z = h(x, y) in the world frame (trajectory.hpp) that rays can be intersected with. The terrain
// (terrain.hpp) implements it; PlaneWaveSurface is an analytic one for tests and measurement-level
// scenarios that do not need rendered terrain.
#pragma once

#include <Eigen/Core>

namespace swf::sim {

class Surface {
 public:
  virtual ~Surface() = default;
  virtual double HeightAt(double x_m, double y_m) const = 0;
  // First intersection of origin + t * direction with the surface for t > 0 (direction need not be
  // unit length). Returns false when the ray misses (leaves the surface's domain first).
  virtual bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                         double* t) const = 0;
};

// h(x, y) = base + amplitude * sin(2 pi x / wavelength) * sin(2 pi y / wavelength), unbounded.
class PlaneWaveSurface final : public Surface {
 public:
  PlaneWaveSurface(double base_m, double amplitude_m, double wavelength_m)
      : base_m_(base_m), amplitude_m_(amplitude_m), wavelength_m_(wavelength_m) {}
  double HeightAt(double x_m, double y_m) const override;
  bool Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                 double* t) const override;

 private:
  double base_m_;
  double amplitude_m_;
  double wavelength_m_;
};

}  // namespace swf::sim
