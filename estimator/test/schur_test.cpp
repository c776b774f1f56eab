// The marginalization step (schur.hpp) against the dense Schur complement written out with
// Eigen on the same system: exact marginal (eq. 9), the VSDF's block-diagonal form (eq. 12),
// and the removal of the marginalized rows.
#include "swf/estimator/schur.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "swf/estimator/stereo_model.hpp"

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

// Runs EliminateVariable + DropChunks on a copy of the system in a padded buffer (leading
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
  const std::unique_ptr<bool[]> dropped = std::make_unique<bool[]>(dim / 3);
  for (int k = o / 3; k < (o + D) / 3; ++k) dropped[k] = true;
  EXPECT_EQ(DropChunks(a.data(), ld, b.data(), dim, dropped.get()), dim - D);
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

// The local system of the first marginalization on the rendered descent (docs/results.md,
// Fig. 17 image level), built from the flight model's own Jacobians: p0 at 100 m looking down
// with the first-pose prior (1 mm, 0.1 mrad), the relative-motion factor to p1 (2 cm, 0.5 mrad)
// and p0's stereo measurements (0.12 px, f = 1155 px, 1 m baseline) of a grid of ground points
// spanning the field of view. Variables [p0 | p1 | landmarks], landmarks in world XYZ.
struct DescentSystem {
  Matrix lambda;
  Vector g;
  std::vector<Eigen::Vector3d> rays;  // unit line of sight from p0 to each landmark
  Eigen::Vector3d axis;               // p0's optical axis
};

DescentSystem FirstMarginalizationOfTheDescent() {
  StereoModel<double> model;
  const double f = 256.0 / std::tan(12.5 * M_PI / 180.0);
  model.camera = StereoCamera<double>{f, f, 256.0, 192.0, 1.0};
  Pose<double> p0;
  p0.R = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();  // camera z along world -z
  p0.t = Eigen::Vector3d(0.0, 0.0, 100.0);
  Pose<double> p1 = p0;
  p1.t.z() -= 1.0;
  std::vector<Eigen::Vector3d> points;
  for (int i = -4; i <= 4; ++i)
    for (int j = -3; j <= 3; ++j) points.emplace_back(5.0 * i, 5.0 * j, 0.0);
  const int n = static_cast<int>(points.size());
  DescentSystem d{Matrix::Zero(12 + 3 * n, 12 + 3 * n), Vector::Zero(12 + 3 * n), {}, p0.R.col(2)};
  for (int i = 0; i < 3; ++i) {
    d.lambda(i, i) = 1.0 / (1e-3 * 1e-3);
    d.lambda(i + 3, i + 3) = 1.0 / (1e-4 * 1e-4);
  }
  Mat6<double> j_prev;
  Mat6<double> j_next;
  (void)model.ProcessResidual(p0, p1, model.RelativeMotion(p0, p1), &j_prev, &j_next);
  const Vec6<double> w(50.0, 50.0, 50.0, 2000.0, 2000.0, 2000.0);
  Eigen::Matrix<double, 6, 12> process;
  process << w.asDiagonal() * j_prev, w.asDiagonal() * j_next;
  d.lambda.topLeftCorner(12, 12) += process.transpose() * process;
  for (int q = 0; q < n; ++q) {
    Vec3<double> z;
    Mat36<double> jp;
    Mat3<double> jl;
    EXPECT_TRUE(model.Predict(p0, points[q], &z, &jp, &jl)) << q;
    Eigen::Matrix<double, 3, 9> h;
    h << jp, jl;
    h /= 0.12;
    const std::vector<int> at = {0, 1, 2, 3, 4, 5, 12 + 3 * q, 13 + 3 * q, 14 + 3 * q};
    d.lambda(at, at) += h.transpose() * h;
    d.rays.push_back((points[q] - p0.t).normalized());
  }
  return d;
}

double SmallestEigenvalue(const Matrix& m) {
  return Eigen::SelfAdjointEigenSolver<Matrix>(m).eigenvalues().minCoeff();
}

TEST(Schur, VsdfScalarDiagonalLeavesAnOffAxisStereoLandmarkIndefiniteAlongItsRay) {
  // Why eq. 12 read literally fails at the rendered descent's first marginalization. A stereo
  // landmark at 100 m is known ~1e4 times better across its line of sight than along it, and
  // the Schur term T (what p0's uncertainty explains of it) has the ray in its null space. Its
  // diagonal alone, taken in world XYZ, is not: along the ray v it removes sum_k T_kk v_k^2
  // (~2 theta^2 of T's lateral size, theta the ray's angle to the axis) from an information of
  // under one. Off the nadir the prior's block goes indefinite along the ray; the exact
  // complement and the block-diagonal VSDF stay positive definite.
  const DescentSystem d = FirstMarginalizationOfTheDescent();
  const int n = static_cast<int>(d.rays.size());
  bool ok = false;
  const Marginal exact = Eliminate<6>(d.lambda, d.g, 0, kAll, &ok);
  ASSERT_TRUE(ok);
  const Marginal block = Eliminate<6>(
      d.lambda, d.g, 0,
      [](int r, int c) {
        return (r < 4 ? 0 : r) == (c < 4 ? 0 : c) ? SchurFill::kBlock : SchurFill::kNone;
      },
      &ok);
  ASSERT_TRUE(ok);
  const Marginal scalar = Eliminate<6>(
      d.lambda, d.g, 0,
      [](int r, int c) { return r == c ? SchurFill::kDiagonal : SchurFill::kNone; }, &ok);
  ASSERT_TRUE(ok);
  EXPECT_GT(SmallestEigenvalue(exact.lambda), 0.0);
  EXPECT_GT(SmallestEigenvalue(block.lambda), 0.0);
  // The next pose's block keeps its positive definiteness: the process factor is not the cause.
  EXPECT_GT(SmallestEigenvalue(scalar.lambda.topLeftCorner(6, 6)), 0.0);
  int indefinite = 0;
  for (int q = 0; q < n; ++q) {
    const int o = 6 + 3 * q;
    const Eigen::Matrix3d e = exact.lambda.block(o, o, 3, 3);
    const Eigen::Matrix3d s = scalar.lambda.block(o, o, 3, 3);
    const Eigen::Vector3d& v = d.rays[q];
    const double theta = std::acos(v.dot(d.axis));
    EXPECT_GT(v.dot(e * v), 0.0) << q;
    EXPECT_LT(v.dot(e * v), 1.0) << q;  // depth known to worse than 1 m at 100 m
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(s);
    if (theta < 0.5 * M_PI / 180.0) {  // the nadir point: its ray is a coordinate axis
      EXPECT_GT(es.eigenvalues()(0), 0.0) << q;
      continue;
    }
    if (es.eigenvalues()(0) >= 0.0) continue;
    ++indefinite;
    // The negative direction is the line of sight.
    EXPECT_GT(std::abs(es.eigenvectors().col(0).dot(v)), std::cos(1.0 * M_PI / 180.0)) << q;
  }
  // Every landmark more than a couple of degrees off the axis goes indefinite (here all but the
  // nadir point: the next ones are 2.9 deg off).
  EXPECT_GE(indefinite, n - 5);
  EXPECT_LT(SmallestEigenvalue(scalar.lambda), 0.0);
  // The corner of the grid, farthest off the axis.
  const int corner = 0;
  const Eigen::Vector3d& v = d.rays[corner];
  const Eigen::Matrix3d e = exact.lambda.block(6, 6, 3, 3);
  const Eigen::Matrix3d kept = e.diagonal().asDiagonal();
  EXPECT_LT(v.dot(scalar.lambda.block(6, 6, 3, 3) * v), -10.0 * v.dot(e * v));
  std::printf(
      "corner landmark %.1f deg off the axis: information along its ray exact %.3g, with the "
      "Schur term's diagonal only %.3g (smallest eigenvalue of its block %.3g); %d of %d "
      "landmark blocks indefinite, smallest eigenvalue of the prior %.3g (exact %.3g); the "
      "diagonal of the exact prior claims a depth sigma %.3g m for %.3g m\n",
      std::acos(v.dot(d.axis)) * 180.0 / M_PI, v.dot(e * v),
      v.dot(scalar.lambda.block(6, 6, 3, 3) * v),
      SmallestEigenvalue(scalar.lambda.block(6, 6, 3, 3)), indefinite, n,
      SmallestEigenvalue(scalar.lambda), SmallestEigenvalue(exact.lambda),
      1.0 / std::sqrt(v.dot(kept * v)), std::sqrt(v.dot(e.inverse() * v)));
  // The other reading, the diagonal of the resulting information instead of the Schur term's,
  // is positive definite but drops the dependencies between a landmark's own coordinates too:
  // along an off-axis ray it claims the depth over ten times better than the landmark's own
  // 3x3 block of the exact prior gives it.
  EXPECT_GT(std::sqrt(v.dot(e.inverse() * v)) * std::sqrt(v.dot(kept * v)), 10.0);
}

// What the filter does when several prior landmarks leave at once: eliminate each in place,
// skipping the rows of those eliminated before it, and drop them all in one pass. The same bits
// as eliminating and dropping one at a time (each kept element sees the same operations).
TEST(Schur, SeveralVariablesEliminatedInPlaceAndDroppedOnceEqualOneAtATimeBitForBit) {
  Matrix lambda;
  Vector g;
  RandomSystem(6 + 3 * 9, 11, &lambda, &g);
  const int order[] = {5, 2, 9, 6};  // chunks (3-wide) in the order they leave
  // One at a time: each Eliminate drops its variable, shifting the later chunks down.
  Marginal one{lambda, g};
  std::vector<int> position = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  for (const int chunk : order) {
    bool ok = false;
    one = Eliminate<3>(one.lambda, one.g, 3 * position[chunk], kAll, &ok);
    ASSERT_TRUE(ok);
    for (int& p : position)
      if (p > position[chunk]) --p;
  }
  // In place, then one DropChunks.
  const int dim = static_cast<int>(g.size());
  const int ld = dim + 3;
  std::vector<double> a(static_cast<std::size_t>(ld * ld), -7.0);
  std::vector<double> b(static_cast<std::size_t>(ld), -7.0);
  std::vector<double> x(static_cast<std::size_t>(ld * 3), 0.0);
  for (int c = 0; c < dim; ++c) {
    for (int r = 0; r < dim; ++r) a[c * ld + r] = lambda(r, c);
    b[c] = g(c);
  }
  bool dropped[11] = {};
  for (const int chunk : order) {
    ASSERT_TRUE(EliminateVariable<3>(
        a.data(), ld, b.data(), dim, 3 * chunk, x.data(), ld, [&](int r, int c) {
          return dropped[r] || dropped[c] ? SchurFill::kNone : SchurFill::kBlock;
        }));
    dropped[chunk] = true;
  }
  ASSERT_EQ(DropChunks(a.data(), ld, b.data(), dim, dropped), dim - 12);
  for (int c = 0; c < dim - 12; ++c) {
    EXPECT_EQ(b[c], one.g(c)) << c;
    for (int r = 0; r < dim - 12; ++r) ASSERT_EQ(a[c * ld + r], one.lambda(r, c)) << r << ", " << c;
  }
}

// EliminateVariablesExact (what the filter runs: all the variables' terms in one pass over the
// matrix, SIMD) against EliminateVariable one variable at a time, skipping the chunks eliminated
// before: the same bits in every kept element, for landmarks (D = 3, in batches, one of them not
// positive definite) and for 6- and 15-dimensional pose states. The sizes are the filter's, so
// the vector loops and their scalar tails both run.
template <int D>
void ExpectExactEliminationsBitForBit(int dim, const std::vector<int>& chunks, int batch,
                                      unsigned seed) {
  Matrix lambda;
  Vector g;
  RandomSystem(dim, seed, &lambda, &g);
  if (D == 3 && chunks.size() > 2)  // one block that cannot be eliminated
    lambda.block(3 * chunks[1], 3 * chunks[1], 3, 3) = -Matrix::Identity(3, 3);
  const int ld = dim + 7;
  std::vector<double> a(static_cast<std::size_t>(ld * ld), -7.0);
  std::vector<double> b(static_cast<std::size_t>(ld), -7.0);
  for (int c = 0; c < dim; ++c) {
    for (int r = 0; r < dim; ++r) a[c * ld + r] = lambda(r, c);
    b[c] = g(c);
  }
  std::vector<double> a_exact = a;
  std::vector<double> b_exact = b;
  std::vector<double> x(static_cast<std::size_t>(ld * D * batch), 0.0);
  std::vector<char> dropped(static_cast<std::size_t>(dim / 3), 0);
  bool ok = true;
  for (const int chunk : chunks) {
    ok = EliminateVariable<D>(a.data(), ld, b.data(), dim, 3 * chunk, x.data(), ld,
                              [&](int r, int c) {
                                return dropped[r] || dropped[c] ? SchurFill::kNone
                                                                : SchurFill::kBlock;
                              }) &&
         ok;
    for (int k = chunk; k < chunk + D / 3; ++k) dropped[k] = 1;
  }
  const std::unique_ptr<bool[]> dropped_exact = std::make_unique<bool[]>(dim / 3);
  bool ok_exact = true;
  for (std::size_t i = 0; i < chunks.size(); i += batch) {
    std::vector<int> offsets;
    for (std::size_t k = i; k < chunks.size() && k < i + batch; ++k)
      offsets.push_back(3 * chunks[k]);
    ok_exact = EliminateVariablesExact<D>(a_exact.data(), ld, b_exact.data(), dim, offsets.data(),
                                          static_cast<int>(offsets.size()), dropped_exact.get(),
                                          x.data(), ld) &&
               ok_exact;
  }
  EXPECT_EQ(ok_exact, ok);
  for (int c = 0; c < dim / 3; ++c) ASSERT_EQ(dropped_exact[c], dropped[c] != 0) << c;
  int compared = 0;
  for (int c = 0; c < dim; ++c) {
    if (dropped[c / 3]) continue;
    ASSERT_EQ(b_exact[c], b[c]) << c;
    for (int r = 0; r < dim; ++r) {
      if (dropped[r / 3]) continue;
      ASSERT_EQ(a_exact[c * ld + r], a[c * ld + r]) << "D " << D << " row " << r << " col " << c;
      ++compared;
    }
  }
  EXPECT_GT(compared, 0);
}

TEST(Schur, ExactEliminationsInOnePassEqualOneAtATimeBitForBit) {
  // Prior landmarks leaving an inertial prior (15 + 3 x 160 wide), 19 of them in batches of 8.
  ExpectExactEliminationsBitForBit<3>(
      15 + 3 * 160, {7, 100, 5, 6, 160, 33, 34, 35, 12, 150, 151, 80, 81, 9, 10, 11, 140, 20, 21},
      8, 21);
  ExpectExactEliminationsBitForBit<3>(6 + 3 * 31, {2, 3, 32}, 1, 22);
  // The oldest pose out of the local system [p0 | p1 | landmarks].
  ExpectExactEliminationsBitForBit<6>(12 + 3 * 53, {0}, 1, 23);
  ExpectExactEliminationsBitForBit<15>(30 + 3 * 160, {0}, 1, 24);
  ExpectExactEliminationsBitForBit<15>(30 + 3 * 3, {0}, 1, 25);
}

// The Schur term's SIMD loops at every vector width (the host's dispatch picks one: AVX-512 on
// x86-64 where the CPU has it, else 2 lanes, as on aarch64) give the same bits, for one column
// and for kSchurColumns at once, over rows that leave a scalar tail.
template <int D, int W>
void SchurTermAtWidth(std::vector<double>* columns, int ld, const std::vector<double>& x,
                      const std::vector<double>& a, int count, int rows) {
  double* pointers[schur_detail::kSchurColumns];
  for (int c = 0; c < count; ++c) pointers[c] = columns->data() + c * ld;
  schur_detail::SubtractSchurTermWidth<D, W>(pointers, count, x.data(), ld, a.data(), rows);
}

template <int D>
void ExpectSchurTermSameAtEveryWidth() {
  std::mt19937 rng(D);
  std::normal_distribution<double> normal;
  const int rows = 3 * 37;
  const int ld = rows + 2;
  std::vector<double> x(static_cast<std::size_t>(ld * D));
  std::vector<double> a(static_cast<std::size_t>(schur_detail::kSchurColumns * D));
  std::vector<double> columns(static_cast<std::size_t>(ld * schur_detail::kSchurColumns));
  for (double& v : x) v = normal(rng);
  for (double& v : a) v = normal(rng);
  for (double& v : columns) v = normal(rng);
  for (const int count : {1, schur_detail::kSchurColumns}) {
    std::vector<double> w1 = columns;
    std::vector<double> w2 = columns;
    std::vector<double> w8 = columns;
    std::vector<double> dispatched = columns;
    SchurTermAtWidth<D, 1>(&w1, ld, x, a, count, rows);
    SchurTermAtWidth<D, 2>(&w2, ld, x, a, count, rows);
    SchurTermAtWidth<D, 8>(&w8, ld, x, a, count, rows);
    double* pointers[schur_detail::kSchurColumns];
    for (int c = 0; c < count; ++c) pointers[c] = dispatched.data() + c * ld;
    schur_detail::SubtractSchurTerm<D>(pointers, count, x.data(), ld, a.data(), rows);
    EXPECT_NE(w1, columns);
    EXPECT_EQ(w2, w1) << D << " " << count;
    EXPECT_EQ(w8, w1) << D << " " << count;
    EXPECT_EQ(dispatched, w1) << D << " " << count;
  }
}

TEST(Schur, SchurTermHasTheSameBitsAtEveryVectorWidth) {
  ExpectSchurTermSameAtEveryWidth<3>();
  ExpectSchurTermSameAtEveryWidth<6>();
  ExpectSchurTermSameAtEveryWidth<15>();
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
