// StereoModel: the measurement and process models the flight estimator uses, in the form the
// SlidingWindowFilter consumes (any type with this surface works; the tests add a linear one).
//
// State: a pose world_T_camera (geometry.hpp, update delta = [rho; phi]) and landmarks as
// world-frame points (update: l += dl). World-frame points keep the prior's landmark blocks
// independent of any anchor pose, so marginalizing a pose never re-parameterizes a landmark.
// (Inverse depth, which the paper suggests for early marginalization, is not used; see
// estimator/README.md.)
//
// Measurement (paper: z_ij = h_ij(x_mi, x_pj) + v_ij), rectified stereo z = (uL, uR, v):
//     p_c = R^T (l - t),     h = StereoCamera::Project(p_c)
//     dh/d delta_pose = P [ -R^T | [p_c]_x ]         (3x6, P = dProject/dp_c)
//     dh/d dl         = P R^T                         (3x3)
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
  using MotionType = Pose<S>;  // camera_j_T_camera_j+1

  StereoCamera<S> camera;
  // Points closer than this (metres, along the optical axis) are not projected: the measurement
  // is skipped for that iteration rather than producing huge Jacobians.
  S min_depth_m = S(1e-3);

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
    *l_world = world_T_camera.Apply(p_c);
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

}  // namespace swf::estimator
