#include "swf/estimator/geometry.hpp"

#include <gtest/gtest.h>

namespace swf::estimator {
namespace {

using Pose3 = Pose<double>;

Pose3 SomePose() {
  return Pose3{ExpSO3<double>(Vec3<double>(0.2, -0.1, 0.3)), Vec3<double>(1.0, -2.0, 50.0)};
}

TEST(Geometry, ExpLogRoundTripIncludingTinyAngles) {
  for (const Vec3<double>& phi :
       {Vec3<double>(0.3, -0.2, 0.1), Vec3<double>(1e-9, 2e-9, 0.0), Vec3<double>(0.0, 0.0, 3.0)}) {
    const Mat3<double> r = ExpSO3<double>(phi);
    EXPECT_NEAR((r.transpose() * r - Mat3<double>::Identity()).norm(), 0.0, 1e-14);
    EXPECT_NEAR((LogSO3<double>(r) - phi).norm(), 0.0, 1e-12);
  }
}

TEST(Geometry, RightJacobianInverseMatchesNumericLog) {
  const Vec3<double> a(0.4, -0.3, 0.2);
  const Mat3<double> jr_inv = RightJacobianInverseSO3<double>(a);
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Vec3<double> d = Vec3<double>::Zero();
    d[k] = h;
    const Vec3<double> numeric =
        (LogSO3<double>(Mat3<double>(ExpSO3<double>(a) * ExpSO3<double>(d))) -
         LogSO3<double>(Mat3<double>(ExpSO3<double>(a) * ExpSO3<double>(Vec3<double>(-d))))) /
        (2 * h);
    EXPECT_NEAR((numeric - jr_inv.col(k)).norm(), 0.0, 1e-8);
  }
}

TEST(Geometry, PoseComposeInverseRetract) {
  const Pose3 a = SomePose();
  const Pose3 identity = a * a.Inverse();
  EXPECT_NEAR((identity.Matrix() - Eigen::Matrix4d::Identity()).norm(), 0.0, 1e-12);
  const Vec3<double> p(3.0, 4.0, 5.0);
  EXPECT_NEAR((a.ApplyInverse(a.Apply(p)) - p).norm(), 0.0, 1e-12);
  Vec6<double> delta;
  delta << 0.1, -0.2, 0.3, 0.01, 0.02, -0.03;
  const Pose3 b = a.Retract(delta);
  EXPECT_NEAR((a.LocalDifference(b) - delta).norm(), 0.0, 1e-12);
  EXPECT_NEAR((Pose3::FromMatrix(b.Matrix()).Matrix() - b.Matrix()).norm(), 0.0, 0.0);
}

// The derivatives stated in the header, against central differences.
TEST(Geometry, CameraPointJacobiansMatchNumeric) {
  const Pose3 world_T_camera = SomePose();
  const Vec3<double> p_world(2.0, 1.0, 5.0);
  const Vec3<double> p_cam = world_T_camera.ApplyInverse(p_world);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Vec6<double> d = Vec6<double>::Zero();
    d[k] = h;
    const Vec3<double> numeric = (world_T_camera.Retract(d).ApplyInverse(p_world) -
                                  world_T_camera.Retract(-d).ApplyInverse(p_world)) /
                                 (2 * h);
    const Vec3<double> analytic = k < 3 ? Vec3<double>(-world_T_camera.R.transpose().col(k))
                                        : Vec3<double>(Skew(p_cam).col(k - 3));
    EXPECT_NEAR((numeric - analytic).norm(), 0.0, 1e-7) << "column " << k;
  }
}

TEST(Geometry, StereoProjectTriangulateAndJacobian) {
  const StereoCamera<double> cam{721.5, 720.0, 609.5, 172.8, 0.537};
  ASSERT_TRUE(cam.Valid());
  const Vec3<double> p(1.5, -0.7, 12.0);
  const Vec3<double> z = cam.Project(p);
  EXPECT_NEAR(z.x() - z.y(), cam.fx * cam.baseline_m / p.z(), 1e-9);
  Vec3<double> back;
  ASSERT_TRUE(cam.Triangulate(z, &back));
  EXPECT_NEAR((back - p).norm(), 0.0, 1e-9);
  const Mat3<double> j = cam.ProjectJacobian(p);
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Vec3<double> d = Vec3<double>::Zero();
    d[k] = h;
    const Vec3<double> numeric = (cam.Project(p + d) - cam.Project(p - d)) / (2 * h);
    EXPECT_NEAR((numeric - j.col(k)).norm(), 0.0, 1e-6);
  }
  Vec3<double> unused;
  EXPECT_FALSE(cam.Triangulate(Vec3<double>(100.0, 100.0, 50.0), &unused));
  EXPECT_FALSE(cam.Triangulate(Vec3<double>(100.0, 101.0, 50.0), &unused));
}

}  // namespace
}  // namespace swf::estimator
