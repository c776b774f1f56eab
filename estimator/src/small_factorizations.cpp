// Eigen's decompositions behind small_factorizations.hpp, instantiated once for the sizes the
// estimator uses (see the header for why).
#include "swf/estimator/small_factorizations.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace swf::estimator {

namespace {

// x = a^-1 b by the factorization Decomposition (Eigen::LLT or Eigen::LDLT); x is written only
// when the factorization succeeded.
template <typename Decomposition, typename Rhs, typename Out>
bool FactorAndSolve(const typename Decomposition::MatrixType& a, const Rhs& b, Out* x) {
  const Decomposition factorization(a);
  if (factorization.info() != Eigen::Success) return false;
  *x = factorization.solve(b);
  return true;
}

}  // namespace

template <typename S, int N>
bool SpdInverse(const SquareMat<S, N>& a, SquareMat<S, N>* inverse) {
  return FactorAndSolve<Eigen::LLT<SquareMat<S, N>>>(a, SquareMat<S, N>::Identity(), inverse);
}

template <typename S, int N>
bool InverseCholeskyFactor(const SquareMat<S, N>& a, SquareMat<S, N>* l_inverse) {
  const Eigen::LLT<SquareMat<S, N>> llt(a);
  if (llt.info() != Eigen::Success) return false;
  *l_inverse = llt.matrixL().solve(SquareMat<S, N>::Identity());
  return true;
}

template <typename S, int N>
bool LdltSolve(const SquareMat<S, N>& a, const ColumnVec<S, N>& b, ColumnVec<S, N>* x) {
  return FactorAndSolve<Eigen::LDLT<SquareMat<S, N>>>(a, b, x);
}

template <typename S, int N>
bool LdltInverse(const SquareMat<S, N>& a, SquareMat<S, N>* inverse) {
  return FactorAndSolve<Eigen::LDLT<SquareMat<S, N>>>(a, SquareMat<S, N>::Identity(), inverse);
}

template <typename S, int N>
bool LdltMahalanobis(const SquareMat<S, N>& a, const ColumnVec<S, N>& d, S* squared_distance) {
  const Eigen::LDLT<SquareMat<S, N>> ldlt(a);
  *squared_distance = d.dot(ldlt.solve(d));
  return ldlt.info() == Eigen::Success;
}

template <typename S, int N>
bool FullPivInverse(const SquareMat<S, N>& a, SquareMat<S, N>* inverse) {
  const Eigen::FullPivLU<SquareMat<S, N>> lu(a);
  if (!lu.isInvertible()) return false;
  *inverse = lu.inverse();
  return true;
}

template <typename S, int N>
SquareMat<S, N> PartialPivSolve(const SquareMat<S, N>& a, const SquareMat<S, N>& b) {
  return a.partialPivLu().solve(b);
}

template <typename S, int N>
SquareMat<S, N> PlainInverse(const SquareMat<S, N>& a) {
  return a.inverse();
}

template <typename S, int N>
ColumnVec<S, N> SymmetricEigenvalues(const SquareMat<S, N>& a) {
  const Eigen::SelfAdjointEigenSolver<SquareMat<S, N>> eig(a, Eigen::EigenvaluesOnly);
  return eig.eigenvalues();
}

// The sizes the estimator uses: 3 (a landmark, a measurement), 6 (a pose) and 15 (a pose with
// velocity and IMU biases) where a pose state's dimension goes, 2 for the horizontal plane.
template bool SpdInverse(const SquareMat<double, 3>&, SquareMat<double, 3>*);
template bool SpdInverse(const SquareMat<double, 6>&, SquareMat<double, 6>*);
template bool SpdInverse(const SquareMat<double, 15>&, SquareMat<double, 15>*);
template bool InverseCholeskyFactor(const SquareMat<double, 3>&, SquareMat<double, 3>*);
template bool InverseCholeskyFactor(const SquareMat<double, 15>&, SquareMat<double, 15>*);
template bool LdltSolve(const SquareMat<double, 6>&, const ColumnVec<double, 6>&,
                        ColumnVec<double, 6>*);
template bool LdltInverse(const SquareMat<double, 6>&, SquareMat<double, 6>*);
template bool LdltMahalanobis(const SquareMat<double, 3>&, const ColumnVec<double, 3>&, double*);
template bool LdltMahalanobis(const SquareMat<double, 6>&, const ColumnVec<double, 6>&, double*);
template bool FullPivInverse(const SquareMat<double, 3>&, SquareMat<double, 3>*);
template bool FullPivInverse(const SquareMat<double, 6>&, SquareMat<double, 6>*);
template bool FullPivInverse(const SquareMat<double, 15>&, SquareMat<double, 15>*);
template SquareMat<double, 15> PartialPivSolve(const SquareMat<double, 15>&,
                                               const SquareMat<double, 15>&);
template SquareMat<double, 3> PlainInverse(const SquareMat<double, 3>&);
template SquareMat<double, 6> PlainInverse(const SquareMat<double, 6>&);
template SquareMat<double, 15> PlainInverse(const SquareMat<double, 15>&);
template ColumnVec<double, 2> SymmetricEigenvalues(const SquareMat<double, 2>&);
template ColumnVec<double, 3> SymmetricEigenvalues(const SquareMat<double, 3>&);
template ColumnVec<double, 6> SymmetricEigenvalues(const SquareMat<double, 6>&);
template ColumnVec<double, 15> SymmetricEigenvalues(const SquareMat<double, 15>&);

}  // namespace swf::estimator
