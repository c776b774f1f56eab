// Independent reference: the kitti-vo bundle-adjustment cost built in Ceres (automatic
// derivatives, quaternion manifold, SPARSE_SCHUR) must reach the same optimum as swf-vo's batch
// solve: final cost to 1e-6 relative and every pose to 1e-6 m.
#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <string>

#include "kitti_vo.hpp"

namespace swf::tools {
namespace {

std::string DataDir() {
  const char* shared = std::getenv("SWF_SHARED_DIR");
  return std::string(shared != nullptr ? shared : "../shared") + "/data/kitti-vo/";
}

// Residual z - h for pose (quaternion x y z w world_R_camera, translation) and world point.
struct StereoResidual {
  StereoResidual(const estimator::StereoCamera<double>& cam, const Eigen::Vector3d& z)
      : cam(cam), z(z) {}
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

TEST(KittiVoCeres, SwfBatchMatchesCeres) {
  KittiVoProblem problem;
  std::string error;
  ASSERT_TRUE(LoadKittiVo(DataDir() + "VO_calibration.txt", DataDir() + "VO_camera_poses_large.txt",
                          DataDir() + "VO_stereo_factors_large.txt", &problem, &error))
      << error;
  ASSERT_EQ(problem.poses.size(), 26u);
  ASSERT_EQ(problem.factors.size(), 8189u);

  // Ceres: same initial values (poses from the file, landmarks stereo-initialized from their
  // first factor), same cost 0.5 * sum |z - h|^2, first pose constant.
  const int n = static_cast<int>(problem.poses.size());
  std::vector<std::array<double, 4>> q(n);
  std::vector<std::array<double, 3>> t(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Quaterniond qq(problem.poses[j].R);
    q[j] = {qq.x(), qq.y(), qq.z(), qq.w()};
    t[j] = {problem.poses[j].t.x(), problem.poses[j].t.y(), problem.poses[j].t.z()};
  }
  std::map<std::int64_t, std::array<double, 3>> points;
  for (const KittiFactor& f : problem.factors) {
    if (points.count(f.landmark) != 0) continue;
    estimator::Vec3<double> pc;
    ASSERT_TRUE(problem.camera.Triangulate(f.z, &pc));
    const estimator::Vec3<double> pw = problem.poses[f.pose].Apply(pc);
    points[f.landmark] = {pw.x(), pw.y(), pw.z()};
  }
  ceres::Problem ceres_problem;
  for (const KittiFactor& f : problem.factors) {
    ceres_problem.AddResidualBlock(new ceres::AutoDiffCostFunction<StereoResidual, 3, 4, 3, 3>(
                                       new StereoResidual(problem.camera, f.z)),
                                   nullptr, q[f.pose].data(), t[f.pose].data(),
                                   points[f.landmark].data());
  }
  for (int j = 0; j < n; ++j)
    ceres_problem.SetManifold(q[j].data(), new ceres::EigenQuaternionManifold);
  ceres_problem.SetParameterBlockConstant(q[0].data());
  ceres_problem.SetParameterBlockConstant(t[0].data());
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_SCHUR;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-16;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-16;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &ceres_problem, &summary);
  ASSERT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();

  const KittiVoResult swf = SolveKittiVo(problem, 0);
  ASSERT_TRUE(swf.ok) << swf.error;
  std::printf("initial cost: swf %.10g ceres %.10g\nfinal cost:   swf %.10g ceres %.10g\n",
              swf.initial_cost, summary.initial_cost, swf.final_cost, summary.final_cost);
  EXPECT_NEAR(swf.initial_cost, summary.initial_cost, 1e-9 * summary.initial_cost);
  EXPECT_NEAR(swf.final_cost, summary.final_cost, 1e-6 * summary.final_cost);
  EXPECT_LT(swf.final_cost, 0.5 * swf.initial_cost);  // the solve did real work
  double worst = 0.0;
  for (int j = 0; j < n; ++j) {
    const estimator::Vec3<double> ceres_t(t[j][0], t[j][1], t[j][2]);
    worst = std::max(worst, (swf.poses[j].t - ceres_t).norm());
  }
  std::printf("largest pose difference: %.3g m\n", worst);
  EXPECT_LT(worst, 1e-6);
}

// A windowed solve stays close to the batch optimum on the same global cost.
TEST(KittiVoCeres, SlidingWindowStaysNearTheBatchCost) {
  KittiVoProblem problem;
  std::string error;
  ASSERT_TRUE(LoadKittiVo(DataDir() + "VO_calibration.txt", DataDir() + "VO_camera_poses_large.txt",
                          DataDir() + "VO_stereo_factors_large.txt", &problem, &error));
  const KittiVoResult batch = SolveKittiVo(problem, 0);
  const KittiVoResult window = SolveKittiVo(problem, 5);
  ASSERT_TRUE(batch.ok && window.ok) << window.error;
  std::printf("kitti-vo final cost: batch %.6g, SWF(5) %.6g (initial %.6g)\n", batch.final_cost,
              window.final_cost, window.initial_cost);
  EXPECT_GE(window.final_cost, batch.final_cost * (1 - 1e-9));
  EXPECT_LT(window.final_cost, 0.5 * window.initial_cost);
}

// A solver reused across solves (Configure resets its filter) gives the bits of a fresh one,
// also after a windowed solve has left a prior and retired landmarks behind.
TEST(KittiVoCeres, AReusedSolverGivesTheBitsOfAFreshOne) {
  KittiVoProblem problem;
  std::string error;
  ASSERT_TRUE(LoadKittiVo(DataDir() + "VO_calibration.txt", DataDir() + "VO_camera_poses_large.txt",
                          DataDir() + "VO_stereo_factors_large.txt", &problem, &error));
  const KittiVoResult fresh = SolveKittiVo(problem, 0);
  KittiVoSolver solver;
  const KittiVoResult windowed = solver.Solve(problem, 5);
  const KittiVoResult reused = solver.Solve(problem, 0);
  ASSERT_TRUE(fresh.ok && windowed.ok && reused.ok);
  EXPECT_EQ(std::memcmp(&fresh.final_cost, &reused.final_cost, sizeof(double)), 0);
  EXPECT_EQ(fresh.iterations, reused.iterations);
  ASSERT_EQ(fresh.poses.size(), reused.poses.size());
  int differing = 0;
  for (std::size_t j = 0; j < fresh.poses.size(); ++j)
    differing +=
        std::memcmp(fresh.poses[j].t.data(), reused.poses[j].t.data(), 3 * sizeof(double)) ||
                std::memcmp(fresh.poses[j].R.data(), reused.poses[j].R.data(), 9 * sizeof(double))
            ? 1
            : 0;
  EXPECT_EQ(differing, 0);
}

TEST(KittiVoCeres, LoaderNamesTheBadLine) {
  KittiVoProblem problem;
  std::string error;
  EXPECT_FALSE(LoadKittiVo(DataDir() + "VO_calibration.txt", DataDir() + "missing.txt",
                           DataDir() + "VO_stereo_factors_large.txt", &problem, &error));
  EXPECT_NE(error.find("missing.txt:0: cannot open"), std::string::npos) << error;
}

}  // namespace
}  // namespace swf::tools
