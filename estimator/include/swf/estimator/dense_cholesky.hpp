// DenseCholesky<S, MaxDim>: factorizes and solves a symmetric positive-definite system
// A x = b of run-time size n <= MaxDim with all storage inside the object.
//
// Why not Eigen::LLT: for dynamic sizes Eigen's blocked products allocate packing buffers on the
// heap, and fixed-max-size matrices of this size trip its stack-allocation limit. Eigen's
// products of small fixed blocks (8x8 and up) also go through its general GEMM path, packing both
// operands on every call, which made the old block-by-block version of this class slow.
//
// Storage: only the lower triangle, in row panels of kBlock = 8 rows. Panel I (rows 8I..8I+7)
// holds columns 0..8I+7, each as 8 consecutive scalars, so element (i, j), i >= j, lives at
//     a_[PanelOffset(i / 8) + 8 j + i % 8]
// and every kernel below streams memory contiguously. The matrix is padded to a multiple of
// kBlock with an identity tail.
//
// Factorization: left-looking (Crout) blocked Cholesky. For each block column J (ascending):
//     for each row panel I >= J:  C_IJ = A_IJ - sum_{p < 8J} L(I rows, p) L(J rows, p)^T
//                                 I == J: C_JJ = L_JJ L_JJ^T   (8x8 Cholesky)
//                                 I >  J: L_IJ = C_IJ L_JJ^-T  (8x8 triangular solve)
// The sum (all but O(n^2) of the n^3/3 flops) runs in a register-blocked micro-kernel: an 8x2
// strip of C_IJ lives in eight 2-wide registers while p runs over a chunk of kChunk columns, the
// chunk of panel I (8 x kChunk) stays in L1 for the four strips, and panel J's chunk is copied
// once per block column with each scalar duplicated into both lanes (SSE2 has no broadcast
// load). The 2-wide vectors are GCC/Clang vector extensions: SSE2 on baseline x86-64, NEON on
// aarch64, each lane a plain IEEE multiply and subtract (no FMA: -ffp-contract=off), so results
// are bit-identical across hosts that round the same way. Deterministic: a fixed operation
// order; no allocation.
//
// On x86-64 CPUs with AVX (double only) the inner product runs in an 8x4 register block of
// 4-wide vectors instead (twice the flops per instruction of two-operand SSE2), broadcasting
// panel J's scalars from memory, so no duplicated copy is needed. Each element still sees
// C(r, c) -= A(r, p) * B(c, p) for p ascending, rounded after the multiply and after the
// subtract (the kernel is compiled for "avx" only, never "fma"), so both kernels give the same
// bits; the test forces each one and compares. The kernel is chosen once, at construction. Where
// the CPU has AVX-512 the tile is instead eight 8-wide accumulators, one per column (half the
// vector instructions of the AVX block for the same products), compiled for "avx512f" only: no
// FMA there either, the same bits.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "swf/core/assert.hpp"
#include "swf/core/status.hpp"

namespace swf::estimator {

namespace dense_detail {
// Two lanes of S in one SIMD register (vector extension; lowered to scalar code if needed).
// may_alias: the kernel reads arrays of S through pointers to these (16-byte aligned) types.
template <typename S>
struct Pair;
template <>
struct Pair<double> {
  typedef double Type __attribute__((vector_size(16), may_alias));
};
template <>
struct Pair<float> {
  typedef float Type __attribute__((vector_size(8), may_alias));
};
template <typename S>
using PairT = typename Pair<S>::Type;

#if defined(__x86_64__)
#define SWF_DENSE_CHOLESKY_AVX 1
// Four doubles in one AVX register; only used inside functions compiled for "avx".
typedef double Quad __attribute__((vector_size(32), may_alias));
// Eight doubles in one AVX-512 register; only inside functions compiled for "avx512f".
typedef double Oct __attribute__((vector_size(64), may_alias));
#endif

template <typename S>
inline PairT<S> Load(const S* p) {
  PairT<S> v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
template <typename S>
inline void Store(S* p, const PairT<S>& v) {
  std::memcpy(p, &v, sizeof(v));
}

// One column of a panel or tile (kBlock = 8 scalars) as four pairs: what the 2-wide kernels load,
// update and store at once. Passed by value and inlined, it stays in registers.
template <typename S>
struct Column8 {
  PairT<S> q0, q1, q2, q3;
};
template <typename S>
inline Column8<S> LoadColumn(const S* p) {
  return {Load(p), Load(p + 2), Load(p + 4), Load(p + 6)};
}
template <typename S>
inline void StoreColumn(S* p, const Column8<S>& c) {
  Store(p, c.q0);
  Store(p + 2, c.q1);
  Store(p + 4, c.q2);
  Store(p + 6, c.q3);
}
// c -= a s: the column at a times the scalar s, lane by lane.
template <typename S>
inline void SubtractScaled(Column8<S>* c, const S* a, S s) {
  const PairT<S> sv = {s, s};
  c->q0 -= Load(a) * sv;
  c->q1 -= Load(a + 2) * sv;
  c->q2 -= Load(a + 4) * sv;
  c->q3 -= Load(a + 6) * sv;
}
// c -= a b with the column a already in pairs (16-byte aligned) and b a pair: per lane.
template <typename S>
inline void SubtractProductOfPairs(Column8<S>* c, const PairT<S>* a, const PairT<S>& b) {
  c->q0 -= a[0] * b;
  c->q1 -= a[1] * b;
  c->q2 -= a[2] * b;
  c->q3 -= a[3] * b;
}
}  // namespace dense_detail

template <typename S, int MaxDim>
class DenseCholesky {
 public:
  static constexpr int kBlock = 8;
  static constexpr int kMaxBlocks = (MaxDim + kBlock - 1) / kBlock;
  static constexpr int kMaxPadded = kMaxBlocks * kBlock;
  static constexpr int kStorage = kBlock * kBlock * kMaxBlocks * (kMaxBlocks + 1) / 2;
  // Columns of the inner product per pass: panel I's chunk (8 x kChunk) plus panel J's
  // duplicated chunk (16 x kChunk) is 24 KiB in double, inside a 32 KiB L1.
  static constexpr int kChunk = 128;

  // The inner-product kernel: kAuto picks the widest the CPU has (x86-64, double: AVX-512, else
  // AVX), else the 2-wide kernel. Every kernel gives the same bits; forcing one exists for tests
  // and benchmarks.
  enum class Kernel : std::uint8_t { kAuto, kPortable, kAvx, kAvx512 };

  DenseCholesky() { (void)SetKernel(Kernel::kAuto); }

  // False (and no change) when the requested kernel cannot run here.
  bool SetKernel(Kernel kernel) {
    const bool avx = Available(Kernel::kAvx);
    const bool avx512 = Available(Kernel::kAvx512);
    if ((kernel == Kernel::kAvx && !avx) || (kernel == Kernel::kAvx512 && !avx512)) return false;
    if (kernel == Kernel::kAuto)
      kernel = avx512 ? Kernel::kAvx512 : avx ? Kernel::kAvx : Kernel::kPortable;
    kernel_ = kernel;
    return true;
  }
  bool UsesAvx() const { return kernel_ != Kernel::kPortable; }  // AVX or AVX-512
  Kernel ActiveKernel() const { return kernel_; }

  // Sets the size and clears A to zero (identity on the padding). Must precede filling.
  void Reset(int n) {
    SWF_ASSERT(n >= 0 && n <= MaxDim);
    n_ = n;
    nb_ = (n + kBlock - 1) / kBlock;
    np_ = nb_ * kBlock;
    const int used = PanelOffset(nb_);
    for (int i = 0; i < used; ++i) a_[i] = S(0);
    for (int i = n_; i < np_; ++i) At(i, i) = S(1);
    factorized_ = false;
  }

  int size() const { return n_; }

  // Element (i, j) of the lower triangle, i >= j.
  S& At(int i, int j) {
    SWF_ASSERT(i >= j && i < np_ && j >= 0);
    return a_[Index(i, j)];
  }
  S At(int i, int j) const {
    SWF_ASSERT(i >= j && i < np_ && j >= 0);
    return a_[Index(i, j)];
  }

  // Adds m to the block at (row, col) of the symmetric A, mirrored into the lower triangle when
  // row < col. Only entries on or below the diagonal are written, so a diagonal block
  // (row == col) contributes its lower triangle (it is assumed symmetric).
  template <typename Derived>
  void AddBlock(int row, int col, const Eigen::MatrixBase<Derived>& block) {
    constexpr int kR = Derived::RowsAtCompileTime;
    constexpr int kC = Derived::ColsAtCompileTime;
    const Eigen::Matrix<S, kR, kC> m = block;
    SWF_ASSERT(row >= 0 && col >= 0 && row + kR <= n_ && col + kC <= n_);
    if (row >= col) {
      for (int c = 0; c < kC; ++c)
        for (int r = 0; r < kR; ++r)
          if (row + r >= col + c) a_[Index(row + r, col + c)] += m(r, c);
    } else {
      for (int c = 0; c < kC; ++c)
        for (int r = 0; r < kR; ++r)
          if (col + c >= row + r) a_[Index(col + c, row + r)] += m(r, c);
    }
  }

  // Adds the lower triangle of the symmetric dim x dim matrix src (column-major, leading
  // dimension ld) at rows/columns offset..offset+dim-1.
  // Panel by panel and column by column, so a panel's column (up to 8 consecutive scalars) takes
  // consecutive scalars of one column of src: contiguous on both sides.
  void AddSymmetric(int offset, const S* src, int ld, int dim) {
    SWF_ASSERT(offset >= 0 && dim >= 0 && offset + dim <= n_ && ld >= dim);
    const int end = offset + dim;
    for (int i0 = offset; i0 < end;) {
      const int ib = i0 / kBlock;
      const int i1 = (ib + 1) * kBlock < end ? (ib + 1) * kBlock : end;  // rows i0..i1-1
      S* panel = a_ + PanelOffset(ib);
      for (int j = offset; j < i1; ++j) {
        S* column = panel + j * kBlock - ib * kBlock;  // column[i] = A(i, j), i in panel ib
        const S* src_column = src + (j - offset) * ld;
        for (int i = i0 > j ? i0 : j; i < i1; ++i) column[i] += src_column[i - offset];
      }
      i0 = i1;
    }
  }

  // In-place factorization A = L L^T. kNumericalFailure if A is not (numerically) positive
  // definite or holds non-finite values; the object must then be Reset before reuse.
  core::Status Factorize() {
    for (int jb = 0; jb < nb_; ++jb) {
      const int depth = jb * kBlock;  // columns left of block column jb
      const S* panel_j = a_ + PanelOffset(jb);
      for (int p0 = 0; p0 < depth; p0 += kChunk) {
        const int len = depth - p0 < kChunk ? depth - p0 : kChunk;
#ifdef SWF_DENSE_CHOLESKY_AVX
        if constexpr (std::is_same_v<S, double>) {
          if (UsesAvx()) {
            for (int ib = jb; ib < nb_; ++ib) {
              S* panel_i = a_ + PanelOffset(ib);
              SubtractColumnsProduct(panel_i + depth * kBlock, panel_i + p0 * kBlock,
                                     panel_j + p0 * kBlock, len);
            }
            continue;
          }
        }
#endif
        DuplicateChunk(panel_j + p0 * kBlock, len);
        for (int ib = jb; ib < nb_; ++ib) {
          S* panel_i = a_ + PanelOffset(ib);
          SubtractProduct(panel_i + depth * kBlock, panel_i + p0 * kBlock, len);
        }
      }
      S* diag = a_ + PanelOffset(jb) + depth * kBlock;
      if (!FactorDiagonal(diag, depth)) return core::Status::kNumericalFailure;
      for (int ib = jb + 1; ib < nb_; ++ib)
        SolveTile(diag, depth, a_ + PanelOffset(ib) + depth * kBlock);
    }
    factorized_ = true;
    return core::Status::kOk;
  }

  // Solves A x = b in place (b has size() entries). Requires a successful Factorize().
  void SolveInPlace(S* b) const {
    SWF_ASSERT(factorized_);
    S* y = work_;
    for (int i = 0; i < n_; ++i) y[i] = b[i];
    for (int i = n_; i < np_; ++i) y[i] = S(0);
    ForwardSubstitute(0, y);
    // Backward, L^T x = y: x_I from the transposed diagonal tile, then y_0..8I -= L_I^T x_I.
    for (int ib = nb_ - 1; ib >= 0; --ib) {
      const S* panel = a_ + PanelOffset(ib);
      const int r0 = ib * kBlock;
      const S* diag = panel + r0 * kBlock;
      S x[kBlock];
      for (int r = kBlock - 1; r >= 0; --r) {
        S v = y[r0 + r];
        for (int q = r + 1; q < kBlock; ++q) v -= diag[r * kBlock + q] * x[q];
        x[r] = v * inv_diag_[r0 + r];
        y[r0 + r] = x[r];
      }
      for (int p = 0; p < r0; ++p) {
        const S* col = panel + p * kBlock;
        S s = S(0);
        for (int r = 0; r < kBlock; ++r) s += col[r] * x[r];
        y[p] -= s;
      }
    }
    for (int i = 0; i < n_; ++i) b[i] = y[i];
  }

  // Column c of A^-1 into out (size() entries). O(n^2).
  void InverseColumn(int c, S* out) const {
    for (int i = 0; i < n_; ++i) out[i] = S(0);
    out[c] = S(1);
    SolveInPlace(out);
  }

  // Column c of L^-1 into out (size() entries; those above row c are zero). Since
  // A^-1 = L^-T L^-1, a block of A^-1 whose rows and columns are >= c is a sum of products of
  // such columns over their common rows: a diagonal block costs its columns' forward solves,
  // O((n - c)^2 / 2) each, against O(n^2) for an InverseColumn.
  void FactorInverseColumn(int c, S* out) const {
    SWF_ASSERT(factorized_ && c >= 0 && c < n_);
    S* y = work_;
    const int ib0 = c / kBlock;
    for (int i = ib0 * kBlock; i < np_; ++i) y[i] = S(0);
    y[c] = S(1);
    ForwardSubstitute(ib0, y);  // y is zero above panel ib0: start there
    for (int i = 0; i < c; ++i) out[i] = S(0);
    for (int i = c; i < n_; ++i) out[i] = y[i];
  }

  // Columns c0 .. c0 + count - 1 of A^-1 (count <= kBlock; column k into out + k * ld, size()
  // entries each) with the same bits as count InverseColumn calls: every element sees the same
  // multiplies and subtracts in the same order, but the factor is streamed once for all of
  // them and the products run kBlock columns wide (the factorization's AVX kernel where the CPU
  // has it).
  void InverseColumns(int c0, int count, S* out, int ld) const {
    SWF_ASSERT(factorized_ && count >= 1 && count <= kBlock && c0 >= 0 && c0 + count <= n_);
    SetUnitColumns(0, c0, count);
    ForwardSubstituteColumns(0);
    BackSubstituteColumns();
    for (int k = 0; k < count; ++k)
      for (int i = 0; i < n_; ++i) out[k * ld + i] = columns_[i * kBlock + k];
  }

  // The same for columns c0 .. c0 + count - 1 of L^-1 (the bits of FactorInverseColumn): the
  // forward solve starts at the panel of row c0, since every column is zero above its own row.
  void FactorInverseColumns(int c0, int count, S* out, int ld) const {
    SWF_ASSERT(factorized_ && count >= 1 && count <= kBlock && c0 >= 0 && c0 + count <= n_);
    const int ib0 = c0 / kBlock;
    SetUnitColumns(ib0, c0, count);
    ForwardSubstituteColumns(ib0);
    for (int k = 0; k < count; ++k) {
      S* o = out + k * ld;
      for (int i = 0; i < c0 + k; ++i) o[i] = S(0);
      for (int i = c0 + k; i < n_; ++i) o[i] = columns_[i * kBlock + k];
    }
  }

  // Scalars of workspace LeadingInverseBlock needs for m columns.
  static constexpr int LeadingInverseWorkspace(int m) {
    return kMaxPadded * kBlock * ((m + kBlock - 1) / kBlock);
  }

  // The leading m x m block of A^-1 into out (column-major, leading dimension ld; both
  // triangles, exactly symmetric) as X^T X with X = L^-1's first m columns (A^-1 = L^-T L^-1):
  // a forward solve per column, started at its own panel, then the Gram products in the
  // factorization's 8 x 8 product kernel. About a third of the flops of m InverseColumns
  // (forward and backward over all n rows each), which differ from it by rounding only.
  // workspace holds LeadingInverseWorkspace(m) scalars (X, kBlock columns per panel layout)
  // and is 64-byte aligned (the AVX product kernel loads it aligned).
  void LeadingInverseBlock(int m, S* out, int ld, S* workspace) const {
    SWF_ASSERT(factorized_ && m >= 0 && m <= n_ && ld >= m &&
               reinterpret_cast<std::uintptr_t>(workspace) % 64 == 0);
    const int groups = (m + kBlock - 1) / kBlock;
    for (int g = 0; g < groups; ++g) {
      const int c0 = g * kBlock;
      SetUnitColumns(g, c0, m - c0 < kBlock ? m - c0 : kBlock);
      ForwardSubstituteColumns(g);
      S* x = workspace + g * kMaxPadded * kBlock;
      for (int i = c0 * kBlock; i < np_ * kBlock; ++i) x[i] = columns_[i];
    }
    alignas(64) S tile[kBlock * kBlock];
    for (int gj = 0; gj < groups; ++gj) {
      const int r0 = gj * kBlock;  // X's group gj is zero above row r0
      const S* xj = workspace + gj * kMaxPadded * kBlock + r0 * kBlock;
      for (int gi = 0; gi <= gj; ++gi) {
        for (S& t : tile) t = S(0);
        SubtractColumnsProduct(tile, workspace + gi * kMaxPadded * kBlock + r0 * kBlock, xj,
                               np_ - r0);
        for (int k = 0; k < kBlock && r0 + k < m; ++k) {
          for (int r = 0; r < kBlock && gi * kBlock + r < m; ++r) {
            const S v = -tile[k * kBlock + r];
            out[(r0 + k) * ld + gi * kBlock + r] = v;
            out[(gi * kBlock + r) * ld + r0 + k] = v;
          }
        }
      }
    }
  }

  bool IsFactorized() const { return factorized_; }

 private:
  using V = dense_detail::PairT<S>;

  static constexpr int PanelOffset(int ib) { return kBlock * kBlock * ib * (ib + 1) / 2; }

  // Forward substitution L y = b in place over panels ib0.. (y must be zero above row 8 ib0),
  // panel by panel: y_I -= L(I, 8 ib0..8I) y_8ib0..8I, then the diagonal tile.
  void ForwardSubstitute(int ib0, S* y) const {
    const int p0 = ib0 * kBlock;
    for (int ib = ib0; ib < nb_; ++ib) {
      const S* panel = a_ + PanelOffset(ib);
      const int r0 = ib * kBlock;
      S t[kBlock];
      for (int r = 0; r < kBlock; ++r) t[r] = y[r0 + r];
      for (int p = p0; p < r0; ++p) {
        const S yp = y[p];
        for (int r = 0; r < kBlock; ++r) t[r] -= panel[p * kBlock + r] * yp;
      }
      const S* diag = panel + r0 * kBlock;
      for (int c = 0; c < kBlock; ++c) {
        const S v = t[c] * inv_diag_[r0 + c];
        y[r0 + c] = v;
        for (int r = c + 1; r < kBlock; ++r) t[r] -= diag[c * kBlock + r] * v;
      }
    }
  }
  // columns_ (row i of kBlock right-hand sides at columns_ + kBlock i, the layout of a panel's
  // column, so the factorization's product kernels apply) = unit vectors e_c0.., from panel ib0
  // on; the lanes past count stay zero.
  void SetUnitColumns(int ib0, int c0, int count) const {
    for (int i = ib0 * kBlock * kBlock; i < np_ * kBlock; ++i) columns_[i] = S(0);
    for (int k = 0; k < count; ++k) columns_[(c0 + k) * kBlock + k] = S(1);
  }

  // ForwardSubstitute for the kBlock right-hand sides in columns_ at once (rows below 8 ib0 must
  // be zero above each column's unit entry). Per element the same operations as the one-column
  // version: y_I -= L(I, p) y_p for p ascending, then the diagonal tile.
  void ForwardSubstituteColumns(int ib0) const {
    const int p0 = ib0 * kBlock;
    alignas(64) S tile[kBlock * kBlock];  // (row r, right-hand side k) at k * kBlock + r
    for (int ib = ib0; ib < nb_; ++ib) {
      const S* panel = a_ + PanelOffset(ib);
      const int r0 = ib * kBlock;
      for (int k = 0; k < kBlock; ++k)
        for (int r = 0; r < kBlock; ++r) tile[k * kBlock + r] = columns_[(r0 + r) * kBlock + k];
      if (r0 > p0)
        SubtractColumnsProduct(tile, panel + p0 * kBlock, columns_ + p0 * kBlock, r0 - p0);
      const S* diag = panel + r0 * kBlock;
      for (int c = 0; c < kBlock; ++c) {
        for (int k = 0; k < kBlock; ++k) {
          const S v = tile[k * kBlock + c] * inv_diag_[r0 + c];
          columns_[(r0 + c) * kBlock + k] = v;
          for (int r = c + 1; r < kBlock; ++r) tile[k * kBlock + r] -= diag[c * kBlock + r] * v;
        }
      }
    }
  }

  // tile (8x8, column-major) -= A B^T over len columns, A = a and B = b both 8 scalars per
  // column p: the product of the factorization's AVX kernel, and a 2-wide version of it.
  void SubtractColumnsProduct(S* tile, const S* a, const S* b, int len) const {
#ifdef SWF_DENSE_CHOLESKY_AVX
    if constexpr (std::is_same_v<S, double>) {
      if (kernel_ == Kernel::kAvx512) {
        SubtractProductAvx512(tile, a, b, len);
        return;
      }
      if (kernel_ == Kernel::kAvx) {
        SubtractProductAvx(tile, a, b, len);
        return;
      }
    }
#endif
    for (int k = 0; k < kBlock; ++k) {
      S* t = tile + k * kBlock;
      dense_detail::Column8<S> c = dense_detail::LoadColumn(t);
      for (int p = 0; p < len; ++p)
        dense_detail::SubtractScaled(&c, a + p * kBlock, b[p * kBlock + k]);
      dense_detail::StoreColumn(t, c);
    }
  }

  // The backward half of SolveInPlace for the kBlock right-hand sides in columns_, per element
  // the same operations: x_I from the transposed diagonal tile, then y_p -= sum_r L(8I + r, p)
  // x_r (the eight products summed from zero, r ascending) for every p < 8I.
  void BackSubstituteColumns() const {
    alignas(64) S x[kBlock * kBlock];  // (row r, right-hand side k) at r * kBlock + k
    for (int ib = nb_ - 1; ib >= 0; --ib) {
      const S* panel = a_ + PanelOffset(ib);
      const int r0 = ib * kBlock;
      const S* diag = panel + r0 * kBlock;
      for (int r = kBlock - 1; r >= 0; --r) {
        for (int k = 0; k < kBlock; ++k) {
          S v = columns_[(r0 + r) * kBlock + k];
          for (int q = r + 1; q < kBlock; ++q) v -= diag[r * kBlock + q] * x[q * kBlock + k];
          x[r * kBlock + k] = v * inv_diag_[r0 + r];
          columns_[(r0 + r) * kBlock + k] = x[r * kBlock + k];
        }
      }
      SubtractTransposedProduct(panel, x, r0);
    }
  }

  // columns_ row p -= sum_r panel(r, p) x(r, .) for p < rows, the sums from zero, r ascending.
  void SubtractTransposedProduct(const S* panel, const S* x, int rows) const {
#ifdef SWF_DENSE_CHOLESKY_AVX
    if constexpr (std::is_same_v<S, double>) {
      if (UsesAvx()) {
        SubtractTransposedProductAvx(panel, x, columns_, rows);
        return;
      }
    }
#endif
    for (int p = 0; p < rows; ++p) {
      const S* col = panel + p * kBlock;
      V s0 = {S(0), S(0)};
      V s1 = s0;
      V s2 = s0;
      V s3 = s0;
      for (int r = 0; r < kBlock; ++r) {
        const V l = {col[r], col[r]};
        const S* xr = x + r * kBlock;
        s0 += l * dense_detail::Load(xr);
        s1 += l * dense_detail::Load(xr + 2);
        s2 += l * dense_detail::Load(xr + 4);
        s3 += l * dense_detail::Load(xr + 6);
      }
      S* y = columns_ + p * kBlock;
      dense_detail::Store(y, dense_detail::Load(y) - s0);
      dense_detail::Store(y + 2, dense_detail::Load(y + 2) - s1);
      dense_detail::Store(y + 4, dense_detail::Load(y + 4) - s2);
      dense_detail::Store(y + 6, dense_detail::Load(y + 6) - s3);
    }
  }

#ifdef SWF_DENSE_CHOLESKY_AVX
  __attribute__((target("avx"))) static void SubtractTransposedProductAvx(const double* panel,
                                                                          const double* x,
                                                                          double* y, int rows) {
    using dense_detail::Quad;
    const Quad* xv = static_cast<const Quad*>(__builtin_assume_aligned(x, 32));
    Quad* yv = static_cast<Quad*>(__builtin_assume_aligned(y, 32));
    for (int p = 0; p < rows; ++p) {
      const double* col = panel + p * kBlock;
      Quad s0 = {0.0, 0.0, 0.0, 0.0};
      Quad s1 = s0;
      for (int r = 0; r < kBlock; ++r) {
        const Quad l = {col[r], col[r], col[r], col[r]};
        s0 += l * xv[2 * r];
        s1 += l * xv[2 * r + 1];
      }
      yv[2 * p] -= s0;
      yv[2 * p + 1] -= s1;
    }
  }
#endif

  // Unsigned arithmetic: callers guarantee 0 <= j <= i < np_ (and i / 8 becomes a shift).
  static unsigned Index(int i, int j) {
    const auto ui = static_cast<unsigned>(i);
    const auto uj = static_cast<unsigned>(j);
    const unsigned panel = ui / kBlock;
    return kBlock * kBlock * panel * (panel + 1) / 2 + uj * kBlock + ui % kBlock;
  }

  // dup_[p][c] = {L(J, p0 + p)[c], same}, laid out strip-major: strip s (columns 2s, 2s+1)
  // holds for each p the four scalars {l_2s, l_2s, l_2s+1, l_2s+1}.
  void DuplicateChunk(const S* src, int len) {
    for (int s = 0; s < kBlock / 2; ++s) {
      S* dst = dup_ + s * 4 * kChunk;
      for (int p = 0; p < len; ++p) {
        const S u = src[p * kBlock + 2 * s];
        const S w = src[p * kBlock + 2 * s + 1];
        dst[4 * p] = u;
        dst[4 * p + 1] = u;
        dst[4 * p + 2] = w;
        dst[4 * p + 3] = w;
      }
    }
  }

  // tile (8x8, column-major) -= A B^T over len columns, A = a (8 rows, len columns, 8 per
  // column), B = the duplicated chunk of panel J. a and dup_ are 16-byte aligned (panels start
  // on 64-byte boundaries), which lets the compiler fold loads into the multiplies.
  void SubtractProduct(S* tile, const S* a, int len) const {
    for (int s = 0; s < kBlock / 2; ++s) {
      S* t0 = tile + 2 * s * kBlock;
      S* t1 = t0 + kBlock;
      dense_detail::Column8<S> c0 = dense_detail::LoadColumn(t0);
      dense_detail::Column8<S> c1 = dense_detail::LoadColumn(t1);
      const V* b = static_cast<const V*>(__builtin_assume_aligned(dup_ + s * 4 * kChunk, 16));
      const V* av = static_cast<const V*>(__builtin_assume_aligned(a, 16));
#pragma GCC unroll 2
      for (int p = 0; p < len; ++p) {
        dense_detail::SubtractProductOfPairs(&c0, av + 4 * p, b[2 * p]);
        dense_detail::SubtractProductOfPairs(&c1, av + 4 * p, b[2 * p + 1]);
      }
      dense_detail::StoreColumn(t0, c0);
      dense_detail::StoreColumn(t1, c1);
    }
  }

#ifdef SWF_DENSE_CHOLESKY_AVX
  // The same product as SubtractProduct, b = panel J's chunk (8 scalars per column p). Two
  // passes of an 8x4 block: tile columns 4h..4h+3 in eight 4-wide accumulators (two per column),
  // panel I's two row halves loaded once per p, panel J's four scalars broadcast from memory.
  __attribute__((target("avx"))) static void SubtractProductAvx(double* tile, const double* a,
                                                                const double* b, int len) {
    using dense_detail::Quad;
    const Quad* av = static_cast<const Quad*>(__builtin_assume_aligned(a, 32));
    for (int h = 0; h < 2; ++h) {
      Quad* t = static_cast<Quad*>(__builtin_assume_aligned(tile + 4 * h * kBlock, 32));
      Quad c[8];  // tile column 4h + k: rows 0-3 in c[2k], rows 4-7 in c[2k + 1]
#pragma GCC unroll 8
      for (int k = 0; k < 8; ++k) c[k] = t[k];
      const double* bh = b + 4 * h;
#pragma GCC unroll 2
      for (int p = 0; p < len; ++p) {
        const Quad a0 = av[2 * p];
        const Quad a1 = av[2 * p + 1];
        const double* bp = bh + kBlock * p;
        Quad bk[4];  // panel J's scalar k broadcast
#pragma GCC unroll 4
        for (int k = 0; k < 4; ++k) bk[k] = Quad{bp[k], bp[k], bp[k], bp[k]};
#pragma GCC unroll 4
        for (int k = 0; k < 4; ++k) {
          c[2 * k] -= a0 * bk[k];
          c[2 * k + 1] -= a1 * bk[k];
        }
      }
#pragma GCC unroll 8
      for (int k = 0; k < 8; ++k) t[k] = c[k];
    }
  }
#endif

#ifdef SWF_DENSE_CHOLESKY_AVX
  // The same product with tile column k in one 8-wide accumulator: panel I's column p loaded
  // once, panel J's eight scalars broadcast from memory (all three 64-byte aligned).
  __attribute__((target("avx512f"))) static void SubtractProductAvx512(double* tile,
                                                                       const double* a,
                                                                       const double* b, int len) {
    using dense_detail::Oct;
    const Oct* av = static_cast<const Oct*>(__builtin_assume_aligned(a, 64));
    Oct* t = static_cast<Oct*>(__builtin_assume_aligned(tile, 64));
    Oct c[kBlock];  // tile column k
#pragma GCC unroll 8
    for (int k = 0; k < kBlock; ++k) c[k] = t[k];
#pragma GCC unroll 2
    for (int p = 0; p < len; ++p) {
      const Oct ap = av[p];
      const double* bp = b + kBlock * p;
#pragma GCC unroll 8
      for (int k = 0; k < kBlock; ++k)
        c[k] -= ap * Oct{bp[k], bp[k], bp[k], bp[k], bp[k], bp[k], bp[k], bp[k]};
    }
#pragma GCC unroll 8
    for (int k = 0; k < kBlock; ++k) t[k] = c[k];
  }
#endif

  static bool Available(Kernel kernel) {
#ifdef SWF_DENSE_CHOLESKY_AVX
    if constexpr (std::is_same_v<S, double>) {
      __builtin_cpu_init();
      if (kernel == Kernel::kAvx) return __builtin_cpu_supports("avx") != 0;
      if (kernel == Kernel::kAvx512) return __builtin_cpu_supports("avx512f") != 0;
    }
#endif
    return kernel == Kernel::kPortable;
  }

  // In-place Cholesky of the 8x8 diagonal tile d (lower triangle) of rows r0..r0+7; keeps
  // 1 / L_cc in inv_diag_.
  bool FactorDiagonal(S* d, int r0) {
    for (int c = 0; c < kBlock; ++c) {
      S v = d[c * kBlock + c];
      for (int p = 0; p < c; ++p) v -= d[p * kBlock + c] * d[p * kBlock + c];
      if (!(v > S(0)) || !std::isfinite(v)) return false;
      const S l = std::sqrt(v);
      d[c * kBlock + c] = l;
      const S inv = S(1) / l;
      inv_diag_[r0 + c] = inv;
      for (int r = c + 1; r < kBlock; ++r) {
        S w = d[c * kBlock + r];
        for (int p = 0; p < c; ++p) w -= d[p * kBlock + r] * d[p * kBlock + c];
        d[c * kBlock + r] = w * inv;
      }
    }
    return true;
  }

  // X = C L_JJ^-T for the 8x8 tile x (column-major), column by column; d = L_JJ at rows r0..
  void SolveTile(const S* d, int r0, S* x) const {
    for (int c = 0; c < kBlock; ++c) {
      S* xc = x + c * kBlock;
      dense_detail::Column8<S> v = dense_detail::LoadColumn(xc);
      for (int p = 0; p < c; ++p)
        dense_detail::SubtractScaled(&v, x + p * kBlock, d[p * kBlock + c]);
      const S inv = inv_diag_[r0 + c];
      const V iv = {inv, inv};
      dense_detail::StoreColumn(xc, {v.q0 * iv, v.q1 * iv, v.q2 * iv, v.q3 * iv});
    }
  }

  alignas(64) S a_[kStorage];
  alignas(64) S dup_[2 * kBlock * kChunk];
  alignas(64) S inv_diag_[kMaxPadded];
  alignas(64) mutable S work_[kMaxPadded];
  alignas(64) mutable S columns_[kMaxPadded * kBlock];  // InverseColumns' right-hand sides
  int n_ = 0;
  int nb_ = 0;
  int np_ = 0;
  bool factorized_ = false;
  Kernel kernel_ = Kernel::kPortable;
};

}  // namespace swf::estimator
