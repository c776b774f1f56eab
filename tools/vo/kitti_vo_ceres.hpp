// The kitti-vo bundle-adjustment cost built in Ceres Solver, the independent reference swf-vo is
// compared with (tests/ceres_reference, tools/bench). Header-only so that only the test and
// benchmark targets, which link Ceres, depend on it; swf-vo does not.
//
// Same problem as swf-vo's batch solve: poses as (quaternion x y z w of world_R_camera,
// translation), landmarks stereo-initialized from their first factor in pose order (as the
// filter initializes them), cost 0.5 * sum |z - h|^2 (sigma 1 px), first pose constant.
#pragma once

#include <ceres/ceres.h>

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "kitti_vo.hpp"

namespace swf::tools {

// Residual z - h for pose (quaternion, translation) and world point.
struct CeresStereoResidual {
  CeresStereoResidual(const estimator::StereoCamera<double>& camera, const Eigen::Vector3d& z)
      : cam(camera), z(z) {}
  template <typename T>
  bool operator()(const T* q, const T* t, const T* l, T* r) const {
    const Eigen::Quaternion<T> world_q_camera(q[3], q[0], q[1], q[2]);
    const Eigen::Matrix<T, 3, 1> p =
        world_q_camera.conjugate() *
        (Eigen::Matrix<T, 3, 1>(l[0], l[1], l[2]) - Eigen::Matrix<T, 3, 1>(t[0], t[1], t[2]));
    r[0] = T(z.x()) - (T(cam.cx) + T(cam.fx) * p.x() / p.z());
    r[1] = T(z.y()) - (T(cam.cx) + T(cam.fx) * (p.x() - T(cam.baseline_m)) / p.z());
    r[2] = T(z.z()) - (T(cam.cy) + T(cam.fy) * p.y() / p.z());
    return true;
  }
  estimator::StereoCamera<double> cam;
  Eigen::Vector3d z;
};

struct CeresKittiVo {
  ceres::Solver::Summary summary;
  std::vector<estimator::Pose<double>> poses;  // final estimates
};

// Builds the problem and solves it with SPARSE_SCHUR on one thread. The tolerances default to
// swf-vo's (relative cost 1e-14, step 1e-12).
inline CeresKittiVo SolveKittiVoWithCeres(const KittiVoProblem& problem,
                                          double function_tolerance = 1e-14,
                                          double parameter_tolerance = 1e-12) {
  const int n = static_cast<int>(problem.poses.size());
  std::vector<std::array<double, 4>> q(n);
  std::vector<std::array<double, 3>> t(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Quaterniond qq(problem.poses[j].R);
    q[j] = {qq.x(), qq.y(), qq.z(), qq.w()};
    t[j] = {problem.poses[j].t.x(), problem.poses[j].t.y(), problem.poses[j].t.z()};
  }
  // Node-based map: the points' addresses must stay valid while Ceres holds them.
  std::unordered_map<std::int64_t, std::array<double, 3>> points;
  ceres::Problem cp;
  for (const KittiFactor& f : problem.factors) {
    auto [it, inserted] = points.try_emplace(f.landmark);
    if (inserted) {
      estimator::Vec3<double> pc = estimator::Vec3<double>::Zero();
      (void)problem.camera.Triangulate(f.z, &pc);  // the loader refuses a non-positive disparity
      const estimator::Vec3<double> pw = problem.poses[f.pose].Apply(pc);
      it->second = {pw.x(), pw.y(), pw.z()};
    }
    cp.AddResidualBlock(new ceres::AutoDiffCostFunction<CeresStereoResidual, 3, 4, 3, 3>(
                            new CeresStereoResidual(problem.camera, f.z)),
                        nullptr, q[f.pose].data(), t[f.pose].data(), it->second.data());
  }
  for (int j = 0; j < n; ++j) cp.SetManifold(q[j].data(), new ceres::EigenQuaternionManifold);
  cp.SetParameterBlockConstant(q[0].data());
  cp.SetParameterBlockConstant(t[0].data());
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_SCHUR;
  options.max_num_iterations = 100;
  options.function_tolerance = function_tolerance;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = parameter_tolerance;
  options.num_threads = 1;
  CeresKittiVo out;
  ceres::Solve(options, &cp, &out.summary);
  out.poses.resize(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Quaterniond qq(q[j][3], q[j][0], q[j][1], q[j][2]);
    out.poses[j] = estimator::Pose<double>{qq.toRotationMatrix(), {t[j][0], t[j][1], t[j][2]}};
  }
  return out;
}

}  // namespace swf::tools
