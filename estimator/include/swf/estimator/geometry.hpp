// Geometry shared by the estimator, the front end and the simulator: rotations, rigid poses and
// the rectified stereo camera. Header-only, templated on the scalar, allocation-free.
//
// Frame convention (used everywhere in the project):
//   world_T_camera = {R, t} maps a point from the camera frame to the world frame:
//       p_world = R * p_camera + t,      p_camera = R^T * (p_world - t).
//   The camera frame is the rectified LEFT camera: x right, y down, z along the optical axis.
//   The right camera sits at +baseline along the left camera's x axis.
//
// Pose perturbation (the estimator's 6-vector update delta = [rho; phi], "decoupled" form):
//       t <- t + rho            (world-frame translation, metres)
//       R <- R * Exp(phi)       (rotation about the camera's own axes, radians)
//   With this choice the derivatives of p_camera are simple (derived here, tested numerically):
//       d p_camera / d rho   = -R^T
//       d p_camera / d phi   = [p_camera]_x        (skew matrix: [a]_x b = a x b)
//       d p_camera / d p_world = R^T
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace swf::estimator {

template <typename S>
using Vec2 = Eigen::Matrix<S, 2, 1>;
template <typename S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <typename S>
using Vec6 = Eigen::Matrix<S, 6, 1>;
template <typename S>
using Mat3 = Eigen::Matrix<S, 3, 3>;
template <typename S>
using Mat6 = Eigen::Matrix<S, 6, 6>;
template <typename S>
using Mat36 = Eigen::Matrix<S, 3, 6>;

template <typename S>
Mat3<S> Skew(const Vec3<S>& v) {
  Mat3<S> m;
  m << S(0), -v.z(), v.y(), v.z(), S(0), -v.x(), -v.y(), v.x(), S(0);
  return m;
}

// Rodrigues' formula; a second-order series near zero keeps it exact to rounding.
template <typename S>
Mat3<S> ExpSO3(const Vec3<S>& phi) {
  const S theta2 = phi.squaredNorm();
  const Mat3<S> k = Skew(phi);
  S a;
  S b;
  if (theta2 < S(1e-10)) {
    a = S(1) - theta2 / S(6);
    b = S(0.5) - theta2 / S(24);
  } else {
    const S theta = std::sqrt(theta2);
    a = std::sin(theta) / theta;
    b = (S(1) - std::cos(theta)) / theta2;
  }
  return Mat3<S>::Identity() + a * k + b * k * k;
}

// Inverse of ExpSO3 for rotation angles in [0, pi).
template <typename S>
Vec3<S> LogSO3(const Mat3<S>& r) {
  const Eigen::AngleAxis<S> aa(r);
  return aa.angle() * aa.axis();
}

// Right Jacobian inverse of SO(3): Log(Exp(a) Exp(d)) ~= a + JrInv(a) d for small d.
template <typename S>
Mat3<S> RightJacobianInverseSO3(const Vec3<S>& phi) {
  const S theta2 = phi.squaredNorm();
  const Mat3<S> k = Skew(phi);
  if (theta2 < S(1e-10)) return Mat3<S>::Identity() + S(0.5) * k + k * k / S(12);
  // Singular at pi (a rotation error of half a turn); clamp so a diverging estimate produces a
  // large but finite Jacobian that the solver's checks can see, rather than Inf/NaN.
  const S theta = std::min(std::sqrt(theta2), S(3.14159));
  const S c = S(1) / (theta * theta) - (S(1) + std::cos(theta)) / (S(2) * theta * std::sin(theta));
  return Mat3<S>::Identity() + S(0.5) * k + c * k * k;
}

// A rigid transform a_T_b: maps points from frame b to frame a.
template <typename S>
struct Pose {
  Mat3<S> R = Mat3<S>::Identity();
  Vec3<S> t = Vec3<S>::Zero();

  static Pose Identity() { return Pose{}; }

  Vec3<S> Apply(const Vec3<S>& p_b) const { return R * p_b + t; }
  Vec3<S> ApplyInverse(const Vec3<S>& p_a) const { return R.transpose() * (p_a - t); }
  Pose Inverse() const { return Pose{R.transpose(), -(R.transpose() * t)}; }
  // (a_T_b * b_T_c) = a_T_c
  Pose operator*(const Pose& b_T_c) const { return Pose{R * b_T_c.R, R * b_T_c.t + t}; }

  // The estimator's update (see the file comment): t += rho, R = R Exp(phi).
  Pose Retract(const Vec6<S>& delta) const {
    return Pose{R * ExpSO3<S>(delta.template tail<3>()), t + delta.template head<3>()};
  }
  // Inverse of Retract: other = this->Retract(this->LocalDifference(other)).
  Vec6<S> LocalDifference(const Pose& other) const {
    Vec6<S> d;
    d.template head<3>() = other.t - t;
    d.template tail<3>() = LogSO3<S>(Mat3<S>(R.transpose() * other.R));
    return d;
  }

  Eigen::Matrix<S, 4, 4> Matrix() const {
    Eigen::Matrix<S, 4, 4> m = Eigen::Matrix<S, 4, 4>::Identity();
    m.template topLeftCorner<3, 3>() = R;
    m.template topRightCorner<3, 1>() = t;
    return m;
  }
  static Pose FromMatrix(const Eigen::Matrix<S, 4, 4>& m) {
    return Pose{m.template topLeftCorner<3, 3>(), m.template topRightCorner<3, 1>()};
  }
  template <typename T>
  Pose<T> Cast() const {
    return Pose<T>{R.template cast<T>(), t.template cast<T>()};
  }
};

// A rectified stereo pair: both cameras share fx, fy, cx, cy and differ by a pure x baseline.
// Measurement z = (uL, uR, v) in pixels; disparity d = uL - uR = fx * baseline / Z.
template <typename S>
struct StereoCamera {
  S fx = S(1);
  S fy = S(1);
  S cx = S(0);
  S cy = S(0);
  S baseline_m = S(1);

  // Projects a point in the left camera frame. Valid only for Z > 0 (the caller checks).
  Vec3<S> Project(const Vec3<S>& p) const {
    const S inv_z = S(1) / p.z();
    return Vec3<S>(cx + fx * p.x() * inv_z, cx + fx * (p.x() - baseline_m) * inv_z,
                   cy + fy * p.y() * inv_z);
  }

  // d z / d p_camera:
  //   [ fx/Z   0     -fx X/Z^2     ]
  //   [ fx/Z   0     -fx (X-b)/Z^2 ]
  //   [ 0      fy/Z  -fy Y/Z^2     ]
  Mat3<S> ProjectJacobian(const Vec3<S>& p) const {
    const S inv_z = S(1) / p.z();
    const S inv_z2 = inv_z * inv_z;
    Mat3<S> j;
    j << fx * inv_z, S(0), -fx * p.x() * inv_z2,                //
        fx * inv_z, S(0), -fx * (p.x() - baseline_m) * inv_z2,  //
        S(0), fy * inv_z, -fy * p.y() * inv_z2;
    return j;
  }

  // Inverse of Project. Returns false for non-positive disparity (point at or behind infinity).
  bool Triangulate(const Vec3<S>& z, Vec3<S>* p) const {
    const S disparity = z.x() - z.y();
    if (!(disparity > S(0))) return false;
    const S depth = fx * baseline_m / disparity;
    *p = Vec3<S>((z.x() - cx) * depth / fx, (z.z() - cy) * depth / fy, depth);
    return true;
  }

  bool Valid() const {
    return fx > S(0) && fy > S(0) && baseline_m > S(0) && std::isfinite(cx) && std::isfinite(cy);
  }
};

}  // namespace swf::estimator
