#include "swf/estimator/dense_cholesky.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "swf/testing/allocation_counter.hpp"
#include "swf/testing/random_spd.hpp"

namespace swf::estimator {
namespace {

using testing::RandomSpd;

// The symmetric matrix a into chol (its lower triangle), factorized.
template <typename Chol>
core::Status LoadAndFactorize(Chol* chol, const Eigen::MatrixXd& a) {
  const int n = static_cast<int>(a.rows());
  chol->Reset(n);
  chol->AddSymmetric(0, a.data(), n, n);
  return chol->Factorize();
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

// Sizes around the 8-row panels and the 128-column inner-product chunks of the kernel.
TEST(DenseCholesky, SolvesLikeEigenAcrossPanelAndChunkBoundaries) {
  auto chol = std::make_unique<DenseCholesky<double, 300>>();
  for (int n : {127, 128, 129, 136, 137, 255, 257, 300}) {
    const Eigen::MatrixXd a = RandomSpd(n, static_cast<std::uint64_t>(n) + 11);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 2.0, -1.0);
    chol->Reset(n);
    for (int j = 0; j < n; ++j)
      for (int i = j; i < n; ++i) chol->At(i, j) = a(i, j);
    ASSERT_EQ(chol->Factorize(), core::Status::kOk) << n;
    // The factor itself, against Eigen's (unique for an SPD matrix).
    const Eigen::MatrixXd l = a.llt().matrixL();
    double max_err = 0.0;
    for (int j = 0; j < n; ++j)
      for (int i = j; i < n; ++i) max_err = std::max(max_err, std::abs(chol->At(i, j) - l(i, j)));
    EXPECT_LT(max_err, 1e-12 * l.cwiseAbs().maxCoeff()) << n;
    Eigen::VectorXd x = b;
    chol->SolveInPlace(x.data());
    EXPECT_LT((a * x - b).norm() / b.norm(), 1e-13) << n;
  }
}

// Same input, same bits (fixed operation order), including after a different problem.
TEST(DenseCholesky, IsDeterministic) {
  auto chol = std::make_unique<DenseCholesky<double, 200>>();
  const Eigen::MatrixXd a = RandomSpd(190, 5);
  const Eigen::MatrixXd other = RandomSpd(200, 6);
  Eigen::VectorXd x1 = Eigen::VectorXd::Ones(190);
  Eigen::VectorXd x2 = x1;
  for (Eigen::VectorXd* x : {&x1, &x2}) {
    chol->Reset(190);
    for (int j = 0; j < 190; ++j)
      for (int i = j; i < 190; ++i) chol->At(i, j) = a(i, j);
    ASSERT_EQ(chol->Factorize(), core::Status::kOk);
    chol->SolveInPlace(x->data());
    chol->Reset(200);
    for (int j = 0; j < 200; ++j)
      for (int i = j; i < 200; ++i) chol->At(i, j) = other(i, j);
    ASSERT_EQ(chol->Factorize(), core::Status::kOk);
  }
  EXPECT_EQ(std::memcmp(x1.data(), x2.data(), sizeof(double) * 190), 0);
}

// Every kernel the CPU can run gives the same factor and solution bits as the portable one
// (same per-element operation order, no fused multiply-add), across panel and chunk boundaries.
TEST(DenseCholesky, EveryKernelMatchesPortableBitForBit) {
  using Chol = DenseCholesky<double, 300>;
  auto portable = std::make_unique<Chol>();
  auto other = std::make_unique<Chol>();
  ASSERT_TRUE(portable->SetKernel(Chol::Kernel::kPortable));
  EXPECT_FALSE(portable->UsesAvx());
  int compared = 0;
  for (const Chol::Kernel kernel : {Chol::Kernel::kAvx, Chol::Kernel::kAvx512}) {
    if (!other->SetKernel(kernel)) {
      std::printf("kernel %d not on this CPU\n", static_cast<int>(kernel));
      continue;
    }
    EXPECT_TRUE(other->UsesAvx());
    ++compared;
    for (int n : {5, 8, 136, 137, 260, 300}) {
      const Eigen::MatrixXd a = RandomSpd(n, 100 + static_cast<std::uint64_t>(n));
      Eigen::VectorXd x1 = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
      Eigen::VectorXd x2 = x1;
      for (Chol* c : {portable.get(), other.get()}) {
        c->Reset(n);
        for (int j = 0; j < n; ++j)
          for (int i = j; i < n; ++i) c->At(i, j) = a(i, j);
        ASSERT_EQ(c->Factorize(), core::Status::kOk);
      }
      int differing = 0;
      for (int j = 0; j < n; ++j)
        for (int i = j; i < n; ++i) {
          const double u = portable->At(i, j);
          const double v = other->At(i, j);
          differing += std::memcmp(&u, &v, sizeof(double)) != 0 ? 1 : 0;
        }
      EXPECT_EQ(differing, 0) << n << " kernel " << static_cast<int>(kernel);
      portable->SolveInPlace(x1.data());
      other->SolveInPlace(x2.data());
      EXPECT_EQ(std::memcmp(x1.data(), x2.data(), sizeof(double) * n), 0) << n;
    }
  }
  std::printf("kernels compared with the portable one: %d\n", compared);
  ASSERT_TRUE(other->SetKernel(Chol::Kernel::kAuto));
}

// Blocks straddling the 8-row panels (6x6 pose blocks at 6 j, 3x3 landmark blocks) and the
// bulk symmetric add build the same matrix as a dense reference.
TEST(DenseCholesky, BlocksAndSymmetricAddsBuildTheMatrix) {
  constexpr int kN = 33;
  auto chol = std::make_unique<DenseCholesky<double, 40>>();
  const Eigen::MatrixXd a = RandomSpd(kN, 9);
  const Eigen::MatrixXd prior = RandomSpd(15, 10);
  chol->Reset(kN);
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(kN, kN);
  for (int j = 0; j < 3; ++j) {  // 6x6 diagonal blocks and their off-diagonal neighbours
    const Eigen::Matrix<double, 6, 6> d = a.block<6, 6>(6 * j, 6 * j);
    chol->AddBlock(6 * j, 6 * j, d);
    expected.block<6, 6>(6 * j, 6 * j) += d;
    if (j > 0) {
      const Eigen::Matrix<double, 6, 6> o = a.block<6, 6>(6 * j, 6 * (j - 1));
      chol->AddBlock(6 * (j - 1), 6 * j, o.transpose());  // upper: mirrored
      expected.block<6, 6>(6 * j, 6 * (j - 1)) += o;
      expected.block<6, 6>(6 * (j - 1), 6 * j) += o.transpose();
    }
  }
  chol->AddSymmetric(18, prior.data(), 15, 15);
  expected.block<15, 15>(18, 18) += prior;
  for (int q = 0; q < 5; ++q) {
    const Eigen::Matrix<double, 3, 6> c = a.block<3, 6>(18 + 3 * q, 0);
    chol->AddBlock(18 + 3 * q, 0, c);
    expected.block<3, 6>(18 + 3 * q, 0) += c;
    expected.block<6, 3>(0, 18 + 3 * q) += c.transpose();
  }
  for (int j = 0; j < kN; ++j)
    for (int i = j; i < kN; ++i) EXPECT_EQ(chol->At(i, j), expected(i, j)) << i << "," << j;
  // Make it positive definite and compare the solve.
  for (int i = 0; i < kN; ++i) {
    chol->At(i, i) += 100.0;
    expected(i, i) += 100.0;
  }
  ASSERT_EQ(chol->Factorize(), core::Status::kOk);
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(kN, 1.0, 3.0);
  const Eigen::VectorXd b = x;
  chol->SolveInPlace(x.data());
  EXPECT_LT((expected * x - b).norm() / b.norm(), 1e-13);
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

// Diagonal blocks of A^-1 from columns of L^-1 (what ComputeCovariances uses for the prior
// landmarks' marginals), against the inverse itself, for blocks inside, across and at the end of
// the 8-row panels.
TEST(DenseCholesky, DiagonalBlocksOfTheInverseFromFactorInverseColumns) {
  auto chol = std::make_unique<DenseCholesky<double, 300>>();
  for (int n : {3, 9, 61, 137, 300}) {
    const Eigen::MatrixXd a = RandomSpd(n, static_cast<std::uint64_t>(n) + 29);
    ASSERT_EQ(LoadAndFactorize(chol.get(), a), core::Status::kOk) << n;
    const Eigen::MatrixXd inverse = a.inverse();
    const Eigen::MatrixXd l_inverse = Eigen::MatrixXd(a.llt().matrixL())
                                          .triangularView<Eigen::Lower>()
                                          .solve(Eigen::MatrixXd::Identity(n, n));
    for (int c0 : {0, 6, n / 2 - 1, n - 3}) {
      if (c0 < 0 || c0 + 3 > n) continue;
      Eigen::MatrixXd x(n, 3);
      for (int k = 0; k < 3; ++k) chol->FactorInverseColumn(c0 + k, x.col(k).data());
      EXPECT_LT((x - l_inverse.middleCols(c0, 3)).cwiseAbs().maxCoeff(), 1e-12) << n << " " << c0;
      if (c0 > 0) {
        EXPECT_EQ(x.topRows(c0).cwiseAbs().maxCoeff(), 0.0);  // zero above row c0
      }
      const Eigen::Matrix3d block = x.transpose() * x;
      EXPECT_LT((block - inverse.block(c0, c0, 3, 3)).cwiseAbs().maxCoeff(),
                1e-12 * inverse.block(c0, c0, 3, 3).cwiseAbs().maxCoeff())
          << n << " " << c0;
    }
  }
}

// The multi-column solves (ComputeCovariances' kernels) give the bits of the one-column ones,
// with both product kernels, for column groups inside, across and at the end of the 8-row panels
// and partial groups; and the columns are those of the inverses themselves.
TEST(DenseCholesky, ColumnGroupsMatchSingleColumnsBitForBit) {
  using Chol = DenseCholesky<double, 300>;
  auto chol = std::make_unique<Chol>();
  for (const Chol::Kernel kernel :
       {Chol::Kernel::kPortable, Chol::Kernel::kAvx, Chol::Kernel::kAvx512}) {
    if (!chol->SetKernel(kernel)) continue;  // no AVX on this CPU
    for (int n : {3, 9, 61, 137, 300}) {
      const Eigen::MatrixXd a = RandomSpd(n, static_cast<std::uint64_t>(n) + 71);
      ASSERT_EQ(LoadAndFactorize(chol.get(), a), core::Status::kOk) << n;
      const Eigen::MatrixXd inverse = a.inverse();
      for (int c0 : {0, 5, 8, n / 2 - 1, n - 8, n - 3}) {
        for (int count : {1, 3, 8}) {
          if (c0 < 0 || c0 + count > n) continue;
          Eigen::MatrixXd group(n, count);
          Eigen::MatrixXd factor_group(n, count);
          chol->InverseColumns(c0, count, group.data(), n);
          chol->FactorInverseColumns(c0, count, factor_group.data(), n);
          Eigen::VectorXd single(n);
          for (int k = 0; k < count; ++k) {
            chol->InverseColumn(c0 + k, single.data());
            EXPECT_EQ(std::memcmp(single.data(), group.col(k).data(), sizeof(double) * n), 0)
                << n << " " << c0 << " " << k;
            chol->FactorInverseColumn(c0 + k, single.data());
            EXPECT_EQ(std::memcmp(single.data(), factor_group.col(k).data(), sizeof(double) * n), 0)
                << n << " " << c0 << " " << k;
          }
          // Against the dense inverse: solves of a well-conditioned matrix (condition < 10),
          // so 1e-12 relative covers their rounding.
          EXPECT_LT((group - inverse.middleCols(c0, count)).cwiseAbs().maxCoeff(),
                    1e-12 * inverse.cwiseAbs().maxCoeff())
              << n << " " << c0;
        }
      }
    }
  }
}

// LeadingInverseBlock's workspace: 64-byte aligned, as the product kernels need.
struct LeadingWorkspace {
  alignas(64) double data[DenseCholesky<double, 300>::LeadingInverseWorkspace(300)];
};

// The leading block of the inverse from the Gram of L^-1's columns (ComputeCovariances' older
// states) against the inverse and against InverseColumns, with both product kernels, for block
// sizes inside, on and across the 8-row panels; exactly symmetric, entries outside untouched.
TEST(DenseCholesky, LeadingInverseBlockIsTheInversesBlock) {
  using Chol = DenseCholesky<double, 300>;
  auto chol = std::make_unique<Chol>();
  auto workspace = std::make_unique<LeadingWorkspace>();
  for (const Chol::Kernel kernel :
       {Chol::Kernel::kPortable, Chol::Kernel::kAvx, Chol::Kernel::kAvx512}) {
    if (!chol->SetKernel(kernel)) continue;
    for (int n : {3, 9, 61, 137, 300}) {
      const Eigen::MatrixXd a = RandomSpd(n, static_cast<std::uint64_t>(n) + 113);
      ASSERT_EQ(LoadAndFactorize(chol.get(), a), core::Status::kOk) << n;
      const Eigen::MatrixXd inverse = a.inverse();
      for (int m : {0, 1, 7, 8, 9, n / 2, n - 1, n}) {
        if (m > n) continue;
        const int ld = m + 3;
        Eigen::MatrixXd out = Eigen::MatrixXd::Constant(ld, m + 1, -7.0);
        chol->LeadingInverseBlock(m, out.data(), ld, workspace->data);
        if (m == 0) continue;
        const Eigen::MatrixXd block = out.topLeftCorner(m, m);
        EXPECT_EQ((block - block.transpose()).cwiseAbs().maxCoeff(), 0.0) << n << " " << m;
        EXPECT_LT((block - inverse.topLeftCorner(m, m)).cwiseAbs().maxCoeff(),
                  1e-12 * inverse.cwiseAbs().maxCoeff())
            << n << " " << m;
        Eigen::MatrixXd columns(n, 1);
        chol->InverseColumns(m - 1, 1, columns.data(), n);
        EXPECT_LT((block.col(m - 1) - columns.topRows(m)).cwiseAbs().maxCoeff(),
                  1e-12 * inverse.cwiseAbs().maxCoeff());
        EXPECT_EQ(out.bottomRows(3).cwiseAbs().minCoeff(), 7.0);  // rows past m untouched
        EXPECT_EQ(out.col(m).cwiseAbs().minCoeff(), 7.0);         // and columns
      }
    }
  }
}

TEST(DenseCholesky, FactorAndSolveNeverAllocate) {
  auto chol = std::make_unique<DenseCholesky<double, 300>>();
  const Eigen::MatrixXd a = RandomSpd(290, 7);
  Eigen::VectorXd b = Eigen::VectorXd::Ones(290);
  Eigen::VectorXd column(290);
  Eigen::VectorXd factor_column(290);
  Eigen::MatrixXd leading(20, 20);
  auto workspace = std::make_unique<LeadingWorkspace>();
  swf::testing::AllocationScope scope;
  chol->Reset(290);
  chol->AddSymmetric(0, a.data(), 290, 290);
  ASSERT_EQ(chol->Factorize(), core::Status::kOk);
  chol->SolveInPlace(b.data());
  chol->InverseColumn(3, column.data());
  chol->FactorInverseColumn(3, factor_column.data());
  chol->InverseColumns(3, 1, column.data(), 290);
  chol->FactorInverseColumns(3, 1, factor_column.data(), 290);
  chol->LeadingInverseBlock(20, leading.data(), 20, workspace->data);
  EXPECT_EQ(scope.Count(), 0u);
  EXPECT_LT((a * column - Eigen::VectorXd::Unit(290, 3)).norm(), 1e-12);
}

}  // namespace
}  // namespace swf::estimator
