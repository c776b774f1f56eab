// Marginalization on a dense symmetric information form, the filter's one Schur-complement
// step (eqs. 8-10 and 12). Variables are grouped in 3-wide chunks (a pose state is
// kStateDim / 3 chunks, a landmark one); matrices are column-major with a leading dimension.
//
// Removing variable block o (width D) from the information form  Lambda x = g  leaves
//     Lambda_rr - Lambda_ro Lambda_oo^-1 Lambda_or,   g_r - Lambda_ro Lambda_oo^-1 g_o   (eq. 9)
// over the rest r: the exact marginal of the rest. The VSDF (eq. 12) keeps only the blocks of
// that update inside one variable, dropping the fill-in between variables; read literally
// ("only the diagonal elements of the Schur complement") it keeps only its scalar diagonal.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "swf/core/assert.hpp"
#include "swf/estimator/small_factorizations.hpp"

namespace swf::estimator {

// The R x C block at (row, col) of the column-major matrix `a` with leading dimension ld.
template <typename S, int R, int C>
Eigen::Map<Eigen::Matrix<S, R, C>, Eigen::Unaligned, Eigen::OuterStride<>> DenseBlock(S* a, int ld,
                                                                                      int row,
                                                                                      int col) {
  return Eigen::Map<Eigen::Matrix<S, R, C>, Eigen::Unaligned, Eigen::OuterStride<>>(
      a + col * ld + row, Eigen::OuterStride<>(ld));
}

// How much of the Schur term  Lambda_ro Lambda_oo^-1 Lambda_oc  one 3x3 chunk pair (r, c)
// receives.
enum class SchurFill : std::uint8_t {
  kNone,      // nothing: fill-in dropped
  kBlock,     // the whole 3x3 block
  kDiagonal,  // only its diagonal elements (meaningful for r == c)
};

// The factor of the Schur step for the D variables starting at `o` of the dim x dim system
// (lambda, g): x = Lambda_ro Lambda_oo^-1 (ld_x >= dim rows, D columns) for every other chunk
// r, and the right-hand side's complement g_r -= x_r g_o (eq. 9), always exact. The chunks of
// `o` and those flagged in `dropped` (dim / 3 flags, or nullptr: none) get a zero row of x and
// keep their g. False, and nothing changed, when Lambda_oo is not positive definite.
template <int D, typename S>
bool ComputeSchurFactor(S* lambda, int ld, S* g, int dim, int o, S* x, int ld_x,
                        const bool* dropped) {
  static_assert(D % 3 == 0, "variables are whole 3-wide chunks");
  using Block = Eigen::Matrix<S, D, D>;
  const Block aa = DenseBlock<S, D, D>(lambda, ld, o, o);
  Block t;
  if (!SpdInverse(aa, &t)) return false;
  const Eigen::Matrix<S, D, 1> go = DenseBlock<S, D, 1>(g, ld, o, 0);
  for (int r = 0; r < dim / 3; ++r) {
    const bool left_out = (3 * r >= o && 3 * r < o + D) || (dropped != nullptr && dropped[r]);
    if (left_out) {
      DenseBlock<S, 3, D>(x, ld_x, 3 * r, 0).setZero();
      continue;
    }
    const Eigen::Matrix<S, 3, D> xr = DenseBlock<S, 3, D>(lambda, ld, 3 * r, o) * t;
    DenseBlock<S, 3, D>(x, ld_x, 3 * r, 0) = xr;
    DenseBlock<S, 3, 1>(g, ld, 3 * r, 0) -= xr * go;
  }
  return true;
}

// Schur complement of the D variables starting at `o` of the dim x dim system (lambda, g)
// onto the other chunks, in place (eq. 9). The rows and columns of `o` itself are left as they
// were; the caller drops them. Each chunk pair (r, c) is updated as fill(r, c) says (kBlock
// everywhere: the exact marginal; kBlock within one variable: the VSDF's eq. 12 as blocks;
// kDiagonal on r == c only: eq. 12's scalar diagonal). The right-hand side is always exact.
// `x` (ld_x >= dim rows, D columns) receives Lambda_ro Lambda_oo^-1. False, and nothing
// changed, when Lambda_oo is not positive definite. (The exact marginal is faster by
// EliminateVariablesExact below, with the same bits.)
template <int D, typename S, typename Fill>
bool EliminateVariable(S* lambda, int ld, S* g, int dim, int o, S* x, int ld_x, Fill fill) {
  if (!ComputeSchurFactor<D>(lambda, ld, g, dim, o, x, ld_x, nullptr)) return false;
  const int chunks = dim / 3;
  const auto eliminated = [o](int chunk) { return 3 * chunk >= o && 3 * chunk < o + D; };
  for (int c = 0; c < chunks; ++c) {
    if (eliminated(c)) continue;
    const Eigen::Matrix<S, D, 3> a_c = DenseBlock<S, D, 3>(lambda, ld, o, 3 * c);
    for (int r = 0; r < chunks; ++r) {
      if (eliminated(r)) continue;
      const SchurFill how = fill(r, c);
      if (how == SchurFill::kBlock) {
        DenseBlock<S, 3, 3>(lambda, ld, 3 * r, 3 * c) -=
            Eigen::Matrix<S, 3, D>(DenseBlock<S, 3, D>(x, ld_x, 3 * r, 0)) * a_c;
      } else if (how == SchurFill::kDiagonal) {
        const Eigen::Matrix<S, 3, 3> term =
            Eigen::Matrix<S, 3, D>(DenseBlock<S, 3, D>(x, ld_x, 3 * r, 0)) * a_c;
        DenseBlock<S, 3, 3>(lambda, ld, 3 * r, 3 * c).diagonal() -= term.diagonal();
      }
    }
  }
  return true;
}

namespace schur_detail {

// One element of the exact Schur term, sum_k x_k a_k over the D products e_k = x_k a_k of a
// row of Lambda_ro Lambda_oo^-1 and a column of Lambda_oc, summed in the order in which Eigen
// 3.4 evaluates the 3 x D by D x 3 product of EliminateVariable (x86-64, SSE2), so that
// EliminateVariablesExact gives the same bits as the filter's marginalization always did:
// for D >= 8 Eigen's GEMM kernel sums from zero, products ascending; below, its coefficient-
// based product sums rows 0 and 1 of a 3-row chunk from e_0 ascending (two rows per packet) and
// row 2 pairwise (the first half's sum plus the second half's, recursively).
// (Results through pointers: S may be a vector type, which is not passed by value across
// targets.)
template <int D, typename S>
inline void SequentialSum(const S* e, S* sum) {
  *sum = e[0];
  if constexpr (D >= 8) *sum = S{} + e[0];
  for (int k = 1; k < D; ++k) *sum += e[k];
}
template <int Begin, int Length, typename S>
inline void PairwiseSum(const S* e, S* sum) {
  if constexpr (Length == 1) {
    *sum = e[Begin];
  } else {
    S first;
    S second;
    PairwiseSum<Begin, Length / 2>(e, &first);
    PairwiseSum<Begin + Length / 2, Length - Length / 2>(e, &second);
    *sum = first + second;
  }
}

// A vector of W scalars (GCC/Clang vector extension; lowered to what the target has), aligned
// like a scalar, so that it loads from and stores to any row of a column.
template <typename S, int W>
struct Lanes {
  typedef S Type __attribute__((vector_size(W * sizeof(S)), may_alias, aligned(sizeof(S))));
  // The same vector in registers and local arrays: naturally aligned (a pointer to the
  // scalar-aligned Type cannot be passed where the vector's own alignment is assumed).
  typedef S Register __attribute__((vector_size(W * sizeof(S))));
};
template <typename S, int W>
using LanesT = typename Lanes<S, W>::Type;

// Up to kSchurColumns columns of the system take one variable's Schur term together, so each
// vector of x is loaded once for all of them.
constexpr int kSchurColumns = 4;

// column_c[r + w] -= sum_k x[k ld_x + r + w] a[c D + k] for the W rows from r of C columns: the
// lanes where `pairwise` is non-zero sum like PairwiseSum (row 2 of a 3-row chunk when D < 8),
// the others like SequentialSum.
template <int D, int C, int W, typename S>
inline __attribute__((always_inline)) void SubtractSchurRows(
    S* const* columns, const S* x, int ld_x, const S* a, int r,
    const typename Lanes<S, W>::Register& pairwise) {
  using V = LanesT<S, W>;
  using R = typename Lanes<S, W>::Register;
  R xk[D];
  for (int k = 0; k < D; ++k) xk[k] = *reinterpret_cast<const V*>(x + k * ld_x + r);
  for (int c = 0; c < C; ++c) {
    R e[D];
    for (int k = 0; k < D; ++k) e[k] = xk[k] * a[c * D + k];
    R term;
    SequentialSum<D>(e, &term);
    if constexpr (D < 8) {
      R paired;
      PairwiseSum<0, D>(e, &paired);
      term = pairwise != S(0) ? paired : term;
    }
    *reinterpret_cast<V*>(columns[c] + r) -= term;
  }
}

// column_c[r] -= sum_k x[k ld_x + r] a[c D + k] for the rows r < rows (whole 3-row chunks) of
// C columns: the Schur term of one eliminated variable, W rows per vector. Each lane does the
// scalar operations of SequentialSum / PairwiseSum for its row.
template <int D, int C, int W, typename S>
inline __attribute__((always_inline)) void SubtractSchurTermLanes(S* const* columns, const S* x,
                                                                  int ld_x, const S* a, int rows) {
  using R = typename Lanes<S, W>::Register;
  int r = 0;
  if constexpr (D >= 8) {
    const R none = {};
    for (; r + W <= rows; r += W) SubtractSchurRows<D, C, W>(columns, x, ld_x, a, r, none);
  } else {
    // 3 W rows (W chunks) per step; in lane terms, row 2 of a chunk is every third lane.
    R third[3];
    for (int v = 0; v < 3; ++v)
      for (int w = 0; w < W; ++w) third[v][w] = (v * W + w) % 3 == 2 ? S(1) : S(0);
    for (; r + 3 * W <= rows; r += 3 * W) {
      for (int v = 0; v < 3; ++v)
        SubtractSchurRows<D, C, W>(columns, x, ld_x, a, r + v * W, third[v]);
    }
  }
  // The rest row by row (r is at a chunk's start where the rows' position in it matters).
  for (; r < rows; ++r) {
    for (int c = 0; c < C; ++c) {
      S e[D];
      for (int k = 0; k < D; ++k) e[k] = x[k * ld_x + r] * a[c * D + k];
      S term;
      if (D < 8 && r % 3 == 2) {
        PairwiseSum<0, D>(e, &term);
      } else {
        SequentialSum<D>(e, &term);
      }
      columns[c][r] -= term;
    }
  }
}

template <int D, int W, typename S>
inline __attribute__((always_inline)) void SubtractSchurTermWidth(S* const* columns, int count,
                                                                  const S* x, int ld_x, const S* a,
                                                                  int rows) {
  if (count == kSchurColumns) {
    SubtractSchurTermLanes<D, kSchurColumns, W>(columns, x, ld_x, a, rows);
  } else {
    for (int c = 0; c < count; ++c)
      SubtractSchurTermLanes<D, 1, W>(columns + c, x, ld_x, a + c * D, rows);
  }
}

#if defined(__x86_64__)
// The same operations 8 lanes wide (AVX-512F has no FMA of its own; -ffp-contract=off keeps
// multiply and subtract apart), so the same bits.
template <int D, typename S>
__attribute__((target("avx512f"))) void SubtractSchurTermAvx512(S* const* columns, int count,
                                                                const S* x, int ld_x, const S* a,
                                                                int rows) {
  SubtractSchurTermWidth<D, 64 / sizeof(S)>(columns, count, x, ld_x, a, rows);
}
#endif

// The Schur term of one variable (x: its factor, ld_x rows by D columns; a: each column's rows
// of the variable, D per column) subtracted from count <= kSchurColumns columns of the system.
template <int D, typename S>
void SubtractSchurTerm(S* const* columns, int count, const S* x, int ld_x, const S* a, int rows) {
#if defined(__x86_64__)
  static const bool avx512 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") != 0;
  }();
  if (avx512) {
    SubtractSchurTermAvx512<D>(columns, count, x, ld_x, a, rows);
    return;
  }
#endif
  SubtractSchurTermWidth<D, 16 / sizeof(S)>(columns, count, x, ld_x, a, rows);
}

}  // namespace schur_detail

// The exact Schur complement (eq. 9: every chunk pair kBlock) of `count` D-wide variables at
// offsets[0..count) of the dim x dim system (lambda, g), eliminated one after the other in
// that order, in place, with the bits of as many EliminateVariable<D> calls whose fill skips
// the chunks eliminated before (what a kept element reads and computes is the same, operation
// for operation). What differs is the memory traffic: each variable's factor x is formed first
// (its own columns updated by the variables before it), then every kept column takes the
// updates of all `count` variables while it is in cache, one pass over the matrix instead of
// `count` (the prior is ~2 MB with an inertial window, beyond L2).
// dropped (dim / 3 flags): chunks eliminated earlier, left out; each variable's chunks are set.
// Rows of dropped chunks keep their values (they get a zero x row) and are for the caller to
// discard, as are the eliminated variables' own rows. x: ld_x >= dim rows, count * D columns.
// A variable whose block is not positive definite is dropped without its complement (false).
template <int D, typename S>
bool EliminateVariablesExact(S* lambda, int ld, S* g, int dim, const int* offsets, int count,
                             bool* dropped, S* x, int ld_x) {
  static_assert(D % 3 == 0, "variables are whole 3-wide chunks");
  constexpr int kMaxCount = 16;
  constexpr int kColumns = schur_detail::kSchurColumns;
  SWF_ASSERT(count >= 0 && count <= kMaxCount);
  bool valid[kMaxCount] = {};
  // Variables [0, last) applied to n <= kColumns columns, in order: variable j's rows of each
  // column (updated by those before it), then its term.
  const auto update_columns = [&](S* const* columns, int n, int last) {
    for (int j = 0; j < last; ++j) {
      if (!valid[j]) continue;
      S a[schur_detail::kSchurColumns * D];
      for (int c = 0; c < n; ++c)
        for (int k = 0; k < D; ++k) a[c * D + k] = columns[c][offsets[j] + k];
      schur_detail::SubtractSchurTerm<D>(columns, n, x + j * D * ld_x, ld_x, a, dim);
    }
  };
  bool ok = true;
  for (int j = 0; j < count; ++j) {
    const int o = offsets[j];
    for (int c = o; c < o + D; ++c) {
      S* const column = lambda + c * ld;
      update_columns(&column, 1, j);
    }
    valid[j] = ComputeSchurFactor<D>(lambda, ld, g, dim, o, x + j * D * ld_x, ld_x, dropped);
    ok = ok && valid[j];
    for (int k = o / 3; k < (o + D) / 3; ++k) dropped[k] = true;
  }
  S* columns[kColumns];
  int n = 0;
  for (int c = 0; c < dim; ++c) {
    if (dropped[c / 3]) continue;
    columns[n++] = lambda + c * ld;
    if (n == kColumns) {
      update_columns(columns, n, count);
      n = 0;
    }
  }
  if (n > 0) update_columns(columns, n, count);
  return ok;
}

// Removes the 3-wide chunks c with dropped[c] from the dim x dim system (lambda, g), keeping the
// order of the rest, in one pass (the last step of a marginalization; several variables
// eliminated one after the other leave their rows to be dropped together). Returns the new dim.
template <typename S>
int DropChunks(S* lambda, int ld, S* g, int dim, const bool* dropped) {
  // Every kept element moves to an index at or before its own, and the elements are visited in
  // ascending order, so no source is overwritten before it is read.
  int cc = 0;
  for (int c = 0; c < dim; ++c) {
    if (dropped[c / 3]) continue;
    int rr = 0;
    for (int r = 0; r < dim; ++r) {
      if (dropped[r / 3]) continue;
      lambda[cc * ld + rr] = lambda[c * ld + r];
      ++rr;
    }
    g[cc] = g[c];
    ++cc;
  }
  return cc;
}

}  // namespace swf::estimator
