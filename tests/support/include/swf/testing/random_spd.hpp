// A random symmetric positive definite matrix, the same for the same seed: the dense Cholesky's
// test and its benchmark factorize these. Header only (Eigen from the including target), so a
// benchmark takes it through swf::test_matrices without the tests' allocation counting.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <random>

namespace swf::testing {

// A A^T + n I with A's entries uniform in [-1, 1): well conditioned (eigenvalues >= n).
inline Eigen::MatrixXd RandomSpd(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd a(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a(i, j) = u(rng);
  return a * a.transpose() + n * Eigen::MatrixXd::Identity(n, n);
}

}  // namespace swf::testing
