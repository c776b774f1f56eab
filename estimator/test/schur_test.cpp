// The marginalization step (schur.hpp) against the dense Schur complement written out with
// Eigen on the same system: exact marginal (eq. 9), the VSDF's block-diagonal form (eq. 12),
// and the removal of the marginalized rows.
#include "swf/estimator/schur.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

namespace swf::estimator {
namespace {

using Matrix = Eigen::MatrixXd;
using Vector = Eigen::VectorXd;

// A random symmetric positive definite information matrix and right-hand side.
void RandomSystem(int dim, unsigned seed, Matrix* lambda, Vector* g) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Matrix j(dim + 4, dim);
  for (int c = 0; c < dim; ++c)
    for (int r = 0; r < dim + 4; ++r) j(r, c) = normal(rng);
  *lambda = j.transpose() * j + 0.1 * Matrix::Identity(dim, dim);
  *g = Vector(dim);
  for (int r = 0; r < dim; ++r) (*g)(r) = normal(rng);
}

// The rows/columns of everything but [o, o + width).
std::vector<int> Rest(int dim, int o, int width) {
  std::vector<int> rest;
  for (int i = 0; i < dim; ++i)
    if (i < o || i >= o + width) rest.push_back(i);
  return rest;
}

struct Marginal {
  Matrix lambda;
  Vector g;
};

Marginal DenseSchur(const Matrix& lambda, const Vector& g, int o, int width) {
  const std::vector<int> rest = Rest(static_cast<int>(g.size()), o, width);
  const Matrix a_rr = lambda(rest, rest);
  const Matrix a_ro = lambda(rest, Eigen::seqN(o, width));
  const Matrix a_oo = lambda(Eigen::seqN(o, width), Eigen::seqN(o, width));
  const Eigen::LLT<Matrix> llt(a_oo);
  return {a_rr - a_ro * llt.solve(a_ro.transpose()),
          g(rest) - a_ro * llt.solve(g.segment(o, width))};
}

// Runs EliminateVariable + DropVariable on a copy of the system in a padded buffer (leading
// dimension larger than the system, as in the filter) and returns the result.
template <int D, typename Couple>
Marginal Eliminate(const Matrix& lambda, const Vector& g, int o, Couple couple, bool* ok) {
  const int dim = static_cast<int>(g.size());
  const int ld = dim + 5;
  std::vector<double> a(static_cast<std::size_t>(ld * ld), -7.0);
  std::vector<double> b(static_cast<std::size_t>(ld), -7.0);
  std::vector<double> x(static_cast<std::size_t>(ld * D), 0.0);
  for (int c = 0; c < dim; ++c) {
    for (int r = 0; r < dim; ++r) a[c * ld + r] = lambda(r, c);
    b[c] = g(c);
  }
  *ok = EliminateVariable<D>(a.data(), ld, b.data(), dim, o, x.data(), ld, couple);
  DropVariable(a.data(), ld, b.data(), dim, o, D);
  Marginal m{Matrix(dim - D, dim - D), Vector(dim - D)};
  for (int c = 0; c < dim - D; ++c) {
    for (int r = 0; r < dim - D; ++r) m.lambda(r, c) = a[c * ld + r];
    m.g(c) = b[c];
  }
  return m;
}

const auto kAll = [](int, int) { return SchurFill::kBlock; };

TEST(Schur, OldestPoseMarginalEqualsTheDenseSchurComplement) {
  // [p0 | p1 | four landmarks] with 6-dof poses, and with 15-dim inertial states.
  Matrix lambda;
  Vector g;
  RandomSystem(6 + 6 + 12, 1, &lambda, &g);
  bool ok = false;
  const Marginal m = Eliminate<6>(lambda, g, 0, kAll, &ok);
  ASSERT_TRUE(ok);
  const Marginal expected = DenseSchur(lambda, g, 0, 6);
  EXPECT_LT((m.lambda - expected.lambda).norm(), 1e-10 * expected.lambda.norm());
  EXPECT_LT((m.g - expected.g).norm(), 1e-10 * expected.g.norm());

  RandomSystem(15 + 15 + 9, 2, &lambda, &g);
  const Marginal inertial = Eliminate<15>(lambda, g, 0, kAll, &ok);
  ASSERT_TRUE(ok);
  const Marginal expected_inertial = DenseSchur(lambda, g, 0, 15);
  EXPECT_LT((inertial.lambda - expected_inertial.lambda).norm(),
            1e-10 * expected_inertial.lambda.norm());
  EXPECT_LT((inertial.g - expected_inertial.g).norm(), 1e-10 * expected_inertial.g.norm());
}

TEST(Schur, LandmarkInsideThePriorIsMarginalizedAndItsRowsRemoved) {
  Matrix lambda;
  Vector g;
  RandomSystem(6 + 15, 3, &lambda, &g);
  for (const int o : {6, 12, 18}) {  // first, middle and last landmark
    bool ok = false;
    const Marginal m = Eliminate<3>(lambda, g, o, kAll, &ok);
    ASSERT_TRUE(ok);
    const Marginal expected = DenseSchur(lambda, g, o, 3);
    EXPECT_LT((m.lambda - expected.lambda).norm(), 1e-10 * expected.lambda.norm()) << o;
    EXPECT_LT((m.g - expected.g).norm(), 1e-10 * expected.g.norm()) << o;
  }
}

TEST(Schur, VsdfKeepsOnlyTheBlocksWithinEachVariable) {
  // Eq. 12: the Schur term is applied to the p1 block and to each landmark's own 3x3 block;
  // the fill-in between variables is dropped, so those blocks keep their old values.
  Matrix lambda;
  Vector g;
  RandomSystem(6 + 6 + 9, 4, &lambda, &g);
  const auto variable = [](int chunk) { return chunk < 4 ? 0 : chunk; };  // p1 = chunks 2, 3
  bool ok = false;
  const Marginal m = Eliminate<6>(
      lambda, g, 0,
      [&](int r, int c) {
        return variable(r) == variable(c) ? SchurFill::kBlock : SchurFill::kNone;
      },
      &ok);
  ASSERT_TRUE(ok);
  const Marginal exact = DenseSchur(lambda, g, 0, 6);
  const Matrix original = lambda.bottomRightCorner(15, 15);
  const int starts[] = {0, 6, 9, 12};  // p1, then the landmarks, in the marginal's indices
  const int widths[] = {6, 3, 3, 3};
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      const Matrix got = m.lambda.block(starts[a], starts[b], widths[a], widths[b]);
      const Matrix want =
          (a == b ? exact.lambda : original).block(starts[a], starts[b], widths[a], widths[b]);
      EXPECT_LT((got - want).norm(), 1e-10 * (1.0 + want.norm())) << a << "," << b;
    }
  }
  EXPECT_LT((m.g - exact.g).norm(), 1e-10 * exact.g.norm());  // the vector is exact
}

TEST(Schur, VsdfScalarDiagonalKeepsOnlyTheDiagonalElements) {
  // Eq. 12 read literally: only the diagonal elements of the Schur term are applied; every
  // off-diagonal element, inside a variable's block too, keeps its old value.
  Matrix lambda;
  Vector g;
  RandomSystem(6 + 6 + 9, 6, &lambda, &g);
  bool ok = false;
  const Marginal m = Eliminate<6>(
      lambda, g, 0, [](int r, int c) { return r == c ? SchurFill::kDiagonal : SchurFill::kNone; },
      &ok);
  ASSERT_TRUE(ok);
  const Marginal exact = DenseSchur(lambda, g, 0, 6);
  const Matrix original = lambda.bottomRightCorner(15, 15);
  for (int c = 0; c < 15; ++c) {
    for (int r = 0; r < 15; ++r) {
      const double want = r == c ? exact.lambda(r, c) : original(r, c);
      EXPECT_NEAR(m.lambda(r, c), want, 1e-10 * (1.0 + std::abs(want))) << r << "," << c;
    }
  }
  EXPECT_LT((m.g - exact.g).norm(), 1e-10 * exact.g.norm());  // the vector is exact
}

TEST(Schur, RefusesABlockThatIsNotPositiveDefiniteAndChangesNothing) {
  Matrix lambda;
  Vector g;
  RandomSystem(12, 5, &lambda, &g);
  lambda.block(3, 3, 3, 3) = -Matrix::Identity(3, 3);
  const int ld = 12;
  std::vector<double> a(lambda.data(), lambda.data() + 144);
  std::vector<double> b(g.data(), g.data() + 12);
  std::vector<double> x(36, 0.0);
  EXPECT_FALSE(EliminateVariable<3>(a.data(), ld, b.data(), 12, 3, x.data(), ld, kAll));
  EXPECT_EQ(Matrix(Eigen::Map<Matrix>(a.data(), 12, 12)), lambda);
  EXPECT_EQ(Vector(Eigen::Map<Vector>(b.data(), 12)), g);
}

}  // namespace
}  // namespace swf::estimator
