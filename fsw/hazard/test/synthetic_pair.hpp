// Synthetic rectified stereo pairs for the hazard tests: a nadir camera over a textured plane
// z = tilt_x * x (plus an optional ripple along x, an optional wall along x and flat-topped square
// rocks), rendered by ray casting (exact for the plane and the boxes, iterated to convergence for
// the ripple and the wall).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "swf/estimator/geometry.hpp"

namespace swf::hazard::testing {

struct Box {
  double x = 0.0, y = 0.0, half = 0.3, height = 0.5;
};

struct Scene {
  double tilt_x = 0.0;
  // A ripple along x, z += ripple_amplitude_m sin(2 pi x / ripple_wavelength_m): metre-scale
  // slopes that a plane over a whole wavelength does not see.
  double ripple_amplitude_m = 0.0;
  double ripple_wavelength_m = 3.0;
  // A wall along x: from x = wall_start_m the ground rises at wall_slope (dz / dx) until it is
  // wall_height_m higher, then stays flat (a crater's inner wall beside its floor, and its rim).
  double wall_start_m = 0.0;
  double wall_slope = 0.0;
  double wall_height_m = 0.0;
  std::vector<Box> boxes;
  double texture_cell_m = 0.04;

  static double Hash(std::int64_t i, std::int64_t j) {
    std::uint64_t h = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^
                      static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    return static_cast<double>(h & 0xFFFF) / 65535.0;
  }
  double Texture(double x, double y) const {
    const double gx = x / texture_cell_m;
    const double gy = y / texture_cell_m;
    const auto i = static_cast<std::int64_t>(std::floor(gx));
    const auto j = static_cast<std::int64_t>(std::floor(gy));
    const double ax = gx - static_cast<double>(i);
    const double ay = gy - static_cast<double>(j);
    const double a = Hash(i, j) * (1 - ax) + Hash(i + 1, j) * ax;
    const double b = Hash(i, j + 1) * (1 - ax) + Hash(i + 1, j + 1) * ax;
    return a * (1 - ay) + b * ay;
  }
  double GroundZ(double x) const {
    const double wall =
        wall_slope > 0.0 ? std::clamp(wall_slope * (x - wall_start_m), 0.0, wall_height_m) : 0.0;
    return tilt_x * x + ripple_amplitude_m * std::sin(2.0 * M_PI * x / ripple_wavelength_m) + wall;
  }
  // True height at (x, y).
  double HeightAt(double x, double y) const {
    double z = GroundZ(x);
    for (const Box& b : boxes) {
      if (std::fabs(x - b.x) <= b.half && std::fabs(y - b.y) <= b.half) {
        z = GroundZ(b.x) + b.height;
      }
    }
    return z;
  }
  // Intersects origin + s * dir (dir.z < 0) with the scene; returns the hit point.
  Eigen::Vector3d Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& dir) const {
    // Box tops first (nearest), then the ground.
    double best_s = 1e30;
    for (const Box& b : boxes) {
      const double top = GroundZ(b.x) + b.height;
      const double s = (top - o.z()) / dir.z();
      const Eigen::Vector3d p = o + s * dir;
      if (s > 0 && std::fabs(p.x() - b.x) <= b.half && std::fabs(p.y() - b.y) <= b.half) {
        best_s = std::min(best_s, s);
      }
    }
    double s_plane = (o.z() - tilt_x * o.x()) / (tilt_x * dir.x() - dir.z());
    // The ripple and the wall by fixed-point iteration on the ray's height: a contraction for
    // near-nadir rays (|dz/dx| |dir.x / dir.z| well below 1).
    const bool curved = ripple_amplitude_m != 0.0 || wall_height_m != 0.0;
    for (int k = 0; k < 40 && curved; ++k) {
      s_plane = (o.z() - GroundZ(o.x() + s_plane * dir.x())) / -dir.z();
    }
    if (s_plane < best_s) {
      const Eigen::Vector3d p = o + s_plane * dir;
      // A ground hit under a box footprint is a side wall: the wall's texture (height-coded).
      bool under = false;
      for (const Box& b : boxes) {
        under = under || (std::fabs(p.x() - b.x) <= b.half && std::fabs(p.y() - b.y) <= b.half);
      }
      if (!under) return p;
    }
    return o + std::min(best_s, s_plane) * dir;
  }
};

struct Pair {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> left;
  std::vector<std::uint8_t> right;
};

// world_R_camera for a nadir camera: camera x = world x, camera y = -world y, camera z = -world z.
inline Eigen::Matrix3d Nadir() {
  Eigen::Matrix3d r;
  r << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  return r;
}

inline void Render(const Scene& scene, const estimator::StereoCamera<double>& cam, int w, int h,
                   const estimator::Pose<double>& world_T_camera, Pair* pair) {
  pair->width = w;
  pair->height = h;
  pair->left.assign(static_cast<std::size_t>(w) * h, 0);
  pair->right.assign(static_cast<std::size_t>(w) * h, 0);
  for (int c = 0; c < 2; ++c) {
    const Eigen::Vector3d origin =
        world_T_camera.Apply(Eigen::Vector3d(c == 0 ? 0.0 : cam.baseline_m, 0.0, 0.0));
    std::vector<std::uint8_t>& img = c == 0 ? pair->left : pair->right;
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const Eigen::Vector3d dir =
            world_T_camera.R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
        const Eigen::Vector3d p = scene.Cast(origin, dir);
        const double t = scene.Texture(p.x(), p.y() + 3.0 * p.z());
        img[static_cast<std::size_t>(v) * w + u] = static_cast<std::uint8_t>(30.0 + 190.0 * t);
      }
    }
  }
}

}  // namespace swf::hazard::testing
