// Factorizations of the small fixed-size matrices the estimator's templates need (a landmark's
// 3x3 information, a 6x6 pose covariance, a 15x15 inertial state), compiled once.
//
// Why not Eigen's decompositions inline: they are the costliest templates the filter
// instantiates (a few seconds of compile time each, per translation unit, per size), and every
// unit that holds a filter instance paid for them again. Here each is Eigen's own algorithm,
// instantiated in one unit of the estimator library (src/small_factorizations.cpp) for
// S = double and the sizes the estimator uses, so results are bit for bit those of the inline
// calls. Another type or size is a link error naming the function: add it to the list there.
//
// Outputs are written only when the function succeeds.
#pragma once

#include <Eigen/Core>

namespace swf::estimator {

template <typename S, int N>
using SquareMat = Eigen::Matrix<S, N, N>;
template <typename S, int N>
using ColumnVec = Eigen::Matrix<S, N, 1>;

// a^-1 from a = L L^T (Eigen::LLT); false if a is not positive definite.
template <typename S, int N>
bool SpdInverse(const SquareMat<S, N>& a, SquareMat<S, N>* inverse);

// L^-1 for a = L L^T, so that L^-T L^-1 = a^-1 (a square-root information from a covariance);
// false if a is not positive definite.
template <typename S, int N>
bool InverseCholeskyFactor(const SquareMat<S, N>& a, SquareMat<S, N>* l_inverse);

// x = a^-1 b by a robust LDL^T (Eigen::LDLT); false if the factorization failed.
template <typename S, int N>
bool LdltSolve(const SquareMat<S, N>& a, const ColumnVec<S, N>& b, ColumnVec<S, N>* x);

// a^-1 by LDL^T; false if the factorization failed.
template <typename S, int N>
bool LdltInverse(const SquareMat<S, N>& a, SquareMat<S, N>* inverse);

// d^T a^-1 d by LDL^T (a squared Mahalanobis distance). The distance is written either way (it
// may be non-finite); false if the factorization failed.
template <typename S, int N>
bool LdltMahalanobis(const SquareMat<S, N>& a, const ColumnVec<S, N>& d, S* squared_distance);

// a^-1 by full-pivoting LU, only when LU finds a invertible at its default threshold.
template <typename S, int N>
bool FullPivInverse(const SquareMat<S, N>& a, SquareMat<S, N>* inverse);

// a^-1 b by partial-pivoting LU (no check: a must be invertible).
template <typename S, int N>
SquareMat<S, N> PartialPivSolve(const SquareMat<S, N>& a, const SquareMat<S, N>& b);

// a.inverse(): closed form up to 4x4, partial-pivoting LU above (no check).
template <typename S, int N>
SquareMat<S, N> PlainInverse(const SquareMat<S, N>& a);

// The eigenvalues of the symmetric a, ascending.
template <typename S, int N>
ColumnVec<S, N> SymmetricEigenvalues(const SquareMat<S, N>& a);

}  // namespace swf::estimator
