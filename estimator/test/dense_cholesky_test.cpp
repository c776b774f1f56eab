#include "swf/estimator/dense_cholesky.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <memory>
#include <random>

#include "swf/testing/allocation_counter.hpp"

namespace swf::estimator {
namespace {

Eigen::MatrixXd RandomSpd(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd a(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a(i, j) = u(rng);
  return a * a.transpose() + n * Eigen::MatrixXd::Identity(n, n);
}

// Against Eigen's own dense LDLT, for sizes on and off the block boundary.
TEST(DenseCholesky, SolvesLikeEigenForManySizes) {
  auto chol = std::make_unique<DenseCholesky<double, 100>>();
  for (int n : {1, 3, 7, 8, 9, 16, 45, 100}) {
    const Eigen::MatrixXd a = RandomSpd(n, static_cast<std::uint64_t>(n));
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    chol->Reset(n);
    for (int j = 0; j < n; ++j)
      for (int i = j; i < n; ++i) chol->At(i, j) = a(i, j);
    ASSERT_EQ(chol->Factorize(), core::Status::kOk) << n;
    Eigen::VectorXd x = b;
    chol->SolveInPlace(x.data());
    const Eigen::VectorXd expected = a.ldlt().solve(b);
    EXPECT_LT((x - expected).norm() / expected.norm(), 1e-12) << n;
    Eigen::VectorXd col(n);
    chol->InverseColumn(n - 1, col.data());
    EXPECT_LT((a * col - Eigen::VectorXd::Unit(n, n - 1)).norm(), 1e-10);
  }
}

TEST(DenseCholesky, AddBlockMirrorsIntoTheLowerTriangle) {
  auto chol = std::make_unique<DenseCholesky<double, 12>>();
  chol->Reset(6);
  Eigen::Matrix<double, 3, 3> m;
  m << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  chol->AddBlock(0, 3, m);  // upper block -> stored transposed below the diagonal
  EXPECT_EQ(chol->At(3, 0), 1.0);
  EXPECT_EQ(chol->At(3, 1), 4.0);
  EXPECT_EQ(chol->At(5, 0), 3.0);
  chol->AddBlock(3, 0, m);
  EXPECT_EQ(chol->At(3, 0), 2.0);
  EXPECT_EQ(chol->At(4, 0), 6.0);
}

TEST(DenseCholesky, RefusesIndefiniteAndNonFinite) {
  auto chol = std::make_unique<DenseCholesky<double, 16>>();
  chol->Reset(10);
  for (int i = 0; i < 10; ++i) chol->At(i, i) = 1.0;
  chol->At(7, 7) = -1.0;
  EXPECT_EQ(chol->Factorize(), core::Status::kNumericalFailure);
  chol->Reset(10);
  for (int i = 0; i < 10; ++i) chol->At(i, i) = 1.0;
  chol->At(2, 2) = std::nan("");
  EXPECT_EQ(chol->Factorize(), core::Status::kNumericalFailure);
}

TEST(DenseCholesky, FactorAndSolveNeverAllocate) {
  auto chol = std::make_unique<DenseCholesky<double, 200>>();
  const Eigen::MatrixXd a = RandomSpd(200, 7);
  Eigen::VectorXd b = Eigen::VectorXd::Ones(200);
  swf::testing::AllocationScope scope;
  chol->Reset(200);
  for (int j = 0; j < 200; ++j)
    for (int i = j; i < 200; ++i) chol->At(i, j) = a(i, j);
  ASSERT_EQ(chol->Factorize(), core::Status::kOk);
  chol->SolveInPlace(b.data());
  EXPECT_EQ(scope.Count(), 0u);
}

}  // namespace
}  // namespace swf::estimator
