// StereoModel and InverseDepthStereoModel: the measurement and process models the flight
// estimator uses, in the form the SlidingWindowFilter consumes (any type with this surface works;
// the tests add a linear one). The two differ only in how a landmark is parameterized.
//
// Pose: world_T_camera (geometry.hpp, update delta = [rho; phi]: t += rho in the world frame,
// R = R Exp(phi)).
//
// Landmarks. The filter stores, per landmark, a 3-vector of parameters m (updated additively,
// m += dm) and a constant LandmarkAnchor the model fixes when the landmark is created; the anchor
// is data, not a state variable, so a landmark still couples only to the poses that observe it
// and marginalizing a pose never re-parameterizes one.
//   StereoModel              m = the world-frame point l; no anchor.
//   InverseDepthStereoModel  anchor = the camera pose estimate at the first measurement (frozen),
//                            m = (alpha, beta, rho) = (X/Z, Y/Z, 1/Z) of the point in that
//                            frame:  l = t_a + R_a (alpha, beta, 1) / rho.
// Why both: at long range a stereo point's error is a long thin ellipsoid along its ray, and the
// projection is strongly nonlinear in depth but almost linear in inverse depth. A landmark
// marginalized into the prior early (the paper's Fig. 15 remark) keeps a linearization that is
// good over its whole uncertainty only in inverse depth. Measured in estimator/README.md.
//
// Measurement (paper: z_ij = h_ij(x_mi, x_pj) + v_ij), rectified stereo z = (uL, uR, v):
//   StereoModel:
//     p_c = R^T (l - t),     h = StereoCamera::Project(p_c)
//     dh/d delta_pose = P [ -R^T | [p_c]_x ]         (3x6, P = dProject/dp_c)
//     dh/d dl         = P R^T                         (3x3)
//   InverseDepthStereoModel: with q = rho p_c = R^T (R_a (alpha, beta, 1) + rho (t_a - t)),
//     h = (cx + fx qx/qz,  cx + fx (qx - b rho)/qz,  cy + fy qy/qz)
//   which is Project(q) of a rig with baseline b rho; with P' its Jacobian at q,
//     dh/d delta_pose = P' [ -rho R^T | [q]_x ]
//     dh/d dm         = P' [ R^T R_a e_x | R^T R_a e_y | R^T (t_a - t) ] + (0, -fx b/qz, 0) e_3^T
//   (e_3^T: the explicit rho in uR adds to the third column only). Valid for rho >= 0 (rho = 0
//   is a point at infinity, still measurable) and the point in front of the camera.
//
// Process (paper: x_p(j+1) = f(x_pj, u_j+1) + w), u = camera_j_T_camera_j+1 a relative motion
// from an IMU / navigation filter or the constant-velocity fallback:
//     f(T_j, u) = T_j * u
//     residual e = [ R_j^T (t_j+1 - t_j) - u_t ;  Log( (R_j u_R)^T R_j+1 ) ]   (6, body frame j)
// so Q is expressed in the camera frame of pose j (metres, radians). With d = t_j+1 - t_j,
// E = Exp(e_R) and Jr^-1 the inverse right Jacobian of SO(3):
//     de_t/d rho_j = -R_j^T     de_t/d phi_j = [R_j^T d]_x      de_t/d rho_j+1 = R_j^T
//     de_R/d phi_j = -Jr^-1(e_R) R_j+1^T R_j                    de_R/d phi_j+1 = Jr^-1(e_R)
// (all other blocks zero). The prior's pose difference uses the same Log, so its Jacobian with
// respect to the update is blockdiag(I, Jr^-1(Delta_phi)).
#pragma once

#include "swf/estimator/geometry.hpp"

namespace swf::estimator {

template <typename S>
struct StereoModel {
  using Scalar = S;
  using PoseType = Pose<S>;
  using MotionType = Pose<S>;          // camera_j_T_camera_j+1
  static constexpr int kStateDim = 6;  // a pose state is the pose alone

  StereoCamera<S> camera;
  // Points closer than this (metres, along the optical axis) are not projected: the measurement
  // is skipped for that iteration rather than producing huge Jacobians.
  S min_depth_m = S(1e-3);
  // A new landmark whose stereo depth exceeds this (metres; 0 = no limit) is refused. A single
  // corrupted disparity can place a landmark kilometres beyond the terrain, where its later
  // measurements hardly constrain it and the robust kernel down-weights them; the caller knows
  // the range the scene can have (e.g. a few times the altitude) and retries with a later frame.
  S max_init_depth_m = S(0);

  // Predicted measurement and Jacobians; false when the point is not in front of the camera.
  bool Predict(const PoseType& world_T_camera, const Vec3<S>& l_world, Vec3<S>* z, Mat36<S>* j_pose,
               Mat3<S>* j_landmark) const {
    const Mat3<S> rt = world_T_camera.R.transpose();
    const Vec3<S> p_c = rt * (l_world - world_T_camera.t);
    if (!(p_c.z() > min_depth_m)) return false;
    *z = camera.Project(p_c);
    if (j_pose != nullptr) {
      const Mat3<S> p = camera.ProjectJacobian(p_c);
      j_pose->template leftCols<3>() = -p * rt;
      j_pose->template rightCols<3>() = p * Skew(p_c);
      *j_landmark = p * rt;
    }
    return true;
  }

  // Stereo initialization of a new landmark from its first measurement.
  bool InitLandmark(const PoseType& world_T_camera, const Vec3<S>& z, Vec3<S>* l_world) const {
    Vec3<S> p_c;
    if (!camera.Triangulate(z, &p_c)) return false;
    if (max_init_depth_m > S(0) && p_c.z() > max_init_depth_m) return false;
    *l_world = world_T_camera.Apply(p_c);
    return true;
  }

  // The filter's landmark surface (see the file comment): no anchor, parameters = world point.
  struct LandmarkAnchor {};
  bool InitLandmark(const PoseType& world_T_camera, const Vec3<S>& z, LandmarkAnchor* /*anchor*/,
                    Vec3<S>* params) const {
    return InitLandmark(world_T_camera, z, params);
  }
  bool Predict(const PoseType& world_T_camera, const LandmarkAnchor& /*anchor*/,
               const Vec3<S>& params, Vec3<S>* z, Mat36<S>* j_pose, Mat3<S>* j_landmark) const {
    return Predict(world_T_camera, params, z, j_pose, j_landmark);
  }
  // World position and its Jacobian with respect to the parameters.
  static bool LandmarkPosition(const LandmarkAnchor& /*anchor*/, const Vec3<S>& params,
                               Vec3<S>* position, Mat3<S>* jacobian) {
    *position = params;
    if (jacobian != nullptr) jacobian->setIdentity();
    return true;
  }

  PoseType Propagate(const PoseType& previous, const MotionType& u) const { return previous * u; }
  MotionType RelativeMotion(const PoseType& a, const PoseType& b) const { return a.Inverse() * b; }

  Vec6<S> ProcessResidual(const PoseType& prev, const PoseType& next, const MotionType& u,
                          Mat6<S>* j_prev, Mat6<S>* j_next) const {
    const Mat3<S> rt = prev.R.transpose();
    const Vec3<S> d = next.t - prev.t;
    const Mat3<S> e_rot = (prev.R * u.R).transpose() * next.R;
    Vec6<S> e;
    e.template head<3>() = rt * d - u.t;
    e.template tail<3>() = LogSO3<S>(e_rot);
    const Mat3<S> jr_inv = RightJacobianInverseSO3<S>(Vec3<S>(e.template tail<3>()));
    j_prev->setZero();
    j_next->setZero();
    j_prev->template block<3, 3>(0, 0) = -rt;
    j_prev->template block<3, 3>(0, 3) = Skew(Vec3<S>(rt * d));
    j_prev->template block<3, 3>(3, 3) = -jr_inv * next.R.transpose() * prev.R;
    j_next->template block<3, 3>(0, 0) = rt;
    j_next->template block<3, 3>(3, 3) = jr_inv;
    return e;
  }

  static PoseType Retract(const PoseType& pose, const Vec6<S>& delta) {
    return pose.Retract(delta);
  }

  // Delta = pose "minus" base in the update's coordinates, and dDelta/d delta_pose.
  static Vec6<S> Difference(const PoseType& base, const PoseType& pose, Mat6<S>* jacobian) {
    const Vec6<S> d = base.LocalDifference(pose);
    jacobian->setIdentity();
    jacobian->template block<3, 3>(3, 3) =
        RightJacobianInverseSO3<S>(Vec3<S>(d.template tail<3>()));
    return d;
  }
};

// Same camera and process model; landmarks in anchored inverse depth (see the file comment).
template <typename S>
struct InverseDepthStereoModel : StereoModel<S> {
  using PoseType = Pose<S>;
  using LandmarkAnchor = Pose<S>;  // world_T_anchor, frozen at the landmark's first measurement

  bool InitLandmark(const PoseType& world_T_camera, const Vec3<S>& z, LandmarkAnchor* anchor,
                    Vec3<S>* params) const {
    Vec3<S> p_c;
    if (!this->camera.Triangulate(z, &p_c)) return false;
    if (this->max_init_depth_m > S(0) && p_c.z() > this->max_init_depth_m) return false;
    *anchor = world_T_camera;
    *params = Vec3<S>(p_c.x() / p_c.z(), p_c.y() / p_c.z(), S(1) / p_c.z());
    return true;
  }

  bool Predict(const PoseType& world_T_camera, const LandmarkAnchor& anchor, const Vec3<S>& params,
               Vec3<S>* z, Mat36<S>* j_pose, Mat3<S>* j_landmark) const {
    const S rho = params.z();
    if (!(rho >= S(0))) return false;
    const Mat3<S> rt = world_T_camera.R.transpose();
    const Mat3<S> r_ca = rt * anchor.R;
    const Vec3<S> t_ca = rt * (anchor.t - world_T_camera.t);
    const Vec3<S> q = r_ca * Vec3<S>(params.x(), params.y(), S(1)) + rho * t_ca;
    // In front of the camera: depth q.z / rho above min_depth (any positive q.z at infinity).
    if (!(q.z() > rho * this->min_depth_m) || !(q.z() > S(0))) return false;
    StereoCamera<S> scaled = this->camera;
    scaled.baseline_m = this->camera.baseline_m * rho;
    *z = scaled.Project(q);
    if (j_pose != nullptr) {
      const Mat3<S> p = scaled.ProjectJacobian(q);
      j_pose->template leftCols<3>() = -rho * p * rt;
      j_pose->template rightCols<3>() = p * Skew(q);
      j_landmark->col(0) = p * r_ca.col(0);
      j_landmark->col(1) = p * r_ca.col(1);
      j_landmark->col(2) = p * t_ca;
      (*j_landmark)(1, 2) -= this->camera.fx * this->camera.baseline_m / q.z();
    }
    return true;
  }

  // l = t_a + R_a (alpha, beta, 1) / rho; false for a point at or beyond infinity (rho <= 0).
  static bool LandmarkPosition(const LandmarkAnchor& anchor, const Vec3<S>& params,
                               Vec3<S>* position, Mat3<S>* jacobian) {
    const S rho = params.z();
    if (!(rho > S(0))) return false;
    const S inv_rho = S(1) / rho;
    const Vec3<S> ray(params.x(), params.y(), S(1));
    *position = anchor.t + anchor.R * (ray * inv_rho);
    if (jacobian != nullptr) {
      Mat3<S> d;
      d << inv_rho, S(0), -params.x() * inv_rho * inv_rho,  //
          S(0), inv_rho, -params.y() * inv_rho * inv_rho,   //
          S(0), S(0), -inv_rho * inv_rho;
      *jacobian = anchor.R * d;
    }
    return true;
  }
};

}  // namespace swf::estimator
