#include "swf/frontend/consistency.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "swf/estimator/geometry.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::frontend {
namespace {

// GIVEN 200 stereo points moved rigidly with 1 cm noise and 30% of the correspondences replaced
// by gross mismatches WHEN checking consistency THEN >= 95% of the mismatches are removed and
// >= 95% of the inliers kept.
TEST(RigidConsistencyTest, RemovesInjectedMismatches) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> xy(-10.0, 10.0);
  std::uniform_real_distribution<double> z(8.0, 30.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  constexpr std::size_t kN = 200;
  std::vector<Eigen::Vector3d> p0(kN);
  std::vector<Eigen::Vector3d> p1(kN);
  std::vector<bool> outlier(kN, false);
  estimator::Pose<double> motion;
  motion.R = estimator::ExpSO3<double>(estimator::Vec3<double>(0.02, -0.05, 0.1));
  motion.t = estimator::Vec3<double>(0.5, -0.3, -1.2);
  for (std::size_t i = 0; i < kN; ++i) {
    p0[i] = Eigen::Vector3d(xy(rng), xy(rng), z(rng));
    p1[i] = motion.Apply(p0[i]) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  }
  // Mismatches: the current point of another landmark (the typical wrong association).
  for (std::size_t i = 0; i < kN; ++i) {
    if (i % 10 < 3) {
      outlier[i] = true;
      p1[i] = motion.Apply(Eigen::Vector3d(xy(rng), xy(rng), z(rng)));
    }
  }
  auto check = std::make_unique<RigidConsistency<256>>();
  ASSERT_EQ(check->Configure(ConsistencyOptions{0.1, 0.02}), core::Status::kOk);
  bool inlier[kN];
  std::size_t num_inliers = 0;
  swf::testing::AllocationScope scope;
  ASSERT_EQ(check->Run(p0.data(), p1.data(), kN, inlier, &num_inliers), core::Status::kOk);
  EXPECT_EQ(scope.Count(), 0u);
  std::size_t outliers_removed = 0;
  std::size_t inliers_kept = 0;
  for (std::size_t i = 0; i < kN; ++i) {
    if (outlier[i] && !inlier[i]) ++outliers_removed;
    if (!outlier[i] && inlier[i]) ++inliers_kept;
  }
  EXPECT_GE(outliers_removed * 100, 95u * 60u);
  EXPECT_GE(inliers_kept * 100, 95u * 140u);
  std::printf("consistency: removed %zu/60 mismatches, kept %zu/140 inliers\n", outliers_removed,
              inliers_kept);
}

TEST(RigidConsistencyTest, EmptyAndOverCapacity) {
  RigidConsistency<8> check;
  ASSERT_EQ(check.Configure(ConsistencyOptions{}), core::Status::kOk);
  Eigen::Vector3d p[9];
  bool inlier[9];
  std::size_t n = 1;
  EXPECT_EQ(check.Run(p, p, 0, inlier, &n), core::Status::kOk);
  EXPECT_EQ(n, 0u);
  EXPECT_EQ(check.Run(p, p, 9, inlier, &n), core::Status::kInvalidArgument);
  EXPECT_EQ(check.Configure(ConsistencyOptions{-1.0, 0.0}), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::frontend
