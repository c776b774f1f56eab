// DenseCholesky<S, MaxDim>: factorizes and solves a symmetric positive-definite system
// A x = b of run-time size n <= MaxDim with all storage inside the object.
//
// Why not Eigen::LLT: for dynamic sizes Eigen's blocked products allocate packing buffers on the
// heap, and fixed-max-size matrices of this size trip its stack-allocation limit. Here the matrix
// is padded to a multiple of kBlock with an identity tail, and the right-looking blocked algorithm
//     for each block column k:   A_kk = L_kk L_kk^T            (kBlock x kBlock Cholesky)
//                                L_ik = A_ik L_kk^-T           (i > k)
//                                A_ij -= L_ik L_jk^T           (i >= j > k)
// runs entirely on fixed-size Eigen blocks (unrolled, vectorized, allocation-free).
// Only the lower triangle of A is read. Deterministic: a fixed operation order.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>

#include "swf/core/assert.hpp"
#include "swf/core/status.hpp"

namespace swf::estimator {

template <typename S, int MaxDim>
class DenseCholesky {
 public:
  static constexpr int kBlock = 8;
  static constexpr int kMaxPadded = ((MaxDim + kBlock - 1) / kBlock) * kBlock;
  using Block = Eigen::Matrix<S, kBlock, kBlock>;
  using BlockMap = Eigen::Map<Block, Eigen::Unaligned, Eigen::OuterStride<>>;

  // Sets the size and clears A to zero (identity on the padding). Must precede filling.
  void Reset(int n) {
    SWF_ASSERT(n >= 0 && n <= MaxDim);
    n_ = n;
    np_ = ((n + kBlock - 1) / kBlock) * kBlock;
    for (int i = 0; i < np_ * np_; ++i) a_[i] = S(0);
    for (int i = n_; i < np_; ++i) At(i, i) = S(1);
    factorized_ = false;
  }

  int size() const { return n_; }
  int Ld() const { return np_; }

  // Column-major element access (row i, column j). Fill the lower triangle (i >= j).
  S& At(int i, int j) { return a_[j * np_ + i]; }
  S At(int i, int j) const { return a_[j * np_ + i]; }
  S* Data() { return a_; }

  // Adds m to the block at (row, col), mirrored into the lower triangle when row < col.
  template <typename Derived>
  void AddBlock(int row, int col, const Eigen::MatrixBase<Derived>& m) {
    constexpr int kR = Derived::RowsAtCompileTime;
    constexpr int kC = Derived::ColsAtCompileTime;
    if (row >= col) {
      Eigen::Map<Eigen::Matrix<S, kR, kC>, Eigen::Unaligned, Eigen::OuterStride<>> dst(
          &At(row, col), Eigen::OuterStride<>(np_));
      dst += m;
    } else {
      Eigen::Map<Eigen::Matrix<S, kC, kR>, Eigen::Unaligned, Eigen::OuterStride<>> dst(
          &At(col, row), Eigen::OuterStride<>(np_));
      dst += m.transpose();
    }
  }

  // In-place factorization A = L L^T. kNumericalFailure if A is not (numerically) positive
  // definite or holds non-finite values; the object must then be Reset before reuse.
  core::Status Factorize() {
    const int nb = np_ / kBlock;
    for (int k = 0; k < nb; ++k) {
      BlockMap akk(&At(k * kBlock, k * kBlock), Eigen::OuterStride<>(np_));
      // Small dense Cholesky of the diagonal block (Eigen's fixed-size LLT allocates nothing).
      for (int c = 0; c < kBlock; ++c) {
        S d = akk(c, c);
        for (int p = 0; p < c; ++p) d -= akk(c, p) * akk(c, p);
        if (!(d > S(0)) || !std::isfinite(d)) return core::Status::kNumericalFailure;
        const S l = std::sqrt(d);
        akk(c, c) = l;
        const S inv = S(1) / l;
        for (int r = c + 1; r < kBlock; ++r) {
          S v = akk(r, c);
          for (int p = 0; p < c; ++p) v -= akk(r, p) * akk(c, p);
          akk(r, c) = v * inv;
        }
      }
      const Block lkk = akk.template triangularView<Eigen::Lower>();
      for (int i = k + 1; i < nb; ++i) {
        BlockMap aik(&At(i * kBlock, k * kBlock), Eigen::OuterStride<>(np_));
        // L_ik = A_ik L_kk^-T  <=>  L_kk L_ik^T = A_ik^T
        Block t = aik.transpose();
        lkk.template triangularView<Eigen::Lower>().solveInPlace(t);
        aik = t.transpose();
      }
      for (int j = k + 1; j < nb; ++j) {
        const BlockMap ljk(&At(j * kBlock, k * kBlock), Eigen::OuterStride<>(np_));
        const Block ljk_t = ljk.transpose();
        for (int i = j; i < nb; ++i) {
          const BlockMap lik(&At(i * kBlock, k * kBlock), Eigen::OuterStride<>(np_));
          BlockMap aij(&At(i * kBlock, j * kBlock), Eigen::OuterStride<>(np_));
          aij.noalias() -= lik * ljk_t;
        }
      }
    }
    factorized_ = true;
    return core::Status::kOk;
  }

  // Solves A x = b in place (b has size() entries). Requires a successful Factorize().
  void SolveInPlace(S* b) const {
    SWF_ASSERT(factorized_);
    // Forward: L y = b.
    for (int i = 0; i < n_; ++i) {
      S v = b[i];
      const S* row = a_ + i;  // L(i, p) = a_[p * np_ + i]
      for (int p = 0; p < i; ++p) v -= row[p * np_] * b[p];
      b[i] = v / a_[i * np_ + i];
    }
    // Backward: L^T x = y.
    for (int i = n_ - 1; i >= 0; --i) {
      S v = b[i];
      const S* col = a_ + i * np_;  // L(p, i) for p > i
      for (int p = i + 1; p < n_; ++p) v -= col[p] * b[p];
      b[i] = v / col[i];
    }
  }

  // Column c of A^-1 into out (size() entries). O(n^2).
  void InverseColumn(int c, S* out) const {
    for (int i = 0; i < n_; ++i) out[i] = S(0);
    out[c] = S(1);
    SolveInPlace(out);
  }

  bool IsFactorized() const { return factorized_; }

 private:
  alignas(64) S a_[kMaxPadded * kMaxPadded];
  int n_ = 0;
  int np_ = 0;
  bool factorized_ = false;
};

}  // namespace swf::estimator
