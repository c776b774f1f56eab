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

// Schur complement of the D variables starting at `o` of the dim x dim system (lambda, g)
// onto the other chunks, in place (eq. 9). The rows and columns of `o` itself are left as they
// were; the caller drops them. Each chunk pair (r, c) is updated as fill(r, c) says (kBlock
// everywhere: the exact marginal; kBlock within one variable: the VSDF's eq. 12 as blocks;
// kDiagonal on r == c only: eq. 12's scalar diagonal). The right-hand side is always exact.
// `x` (ld_x >= dim rows, D columns) receives Lambda_ro Lambda_oo^-1. False, and nothing
// changed, when Lambda_oo is not positive definite.
template <int D, typename S, typename Fill>
bool EliminateVariable(S* lambda, int ld, S* g, int dim, int o, S* x, int ld_x, Fill fill) {
  static_assert(D % 3 == 0, "variables are whole 3-wide chunks");
  using Block = Eigen::Matrix<S, D, D>;
  const Block aa = DenseBlock<S, D, D>(lambda, ld, o, o);
  Block t;
  if (!SpdInverse(aa, &t)) return false;
  const Eigen::Matrix<S, D, 1> go = DenseBlock<S, D, 1>(g, ld, o, 0);
  const int chunks = dim / 3;
  const auto eliminated = [o](int chunk) { return 3 * chunk >= o && 3 * chunk < o + D; };
  for (int r = 0; r < chunks; ++r) {
    if (eliminated(r)) continue;
    const Eigen::Matrix<S, 3, D> xr = DenseBlock<S, 3, D>(lambda, ld, 3 * r, o) * t;
    DenseBlock<S, 3, D>(x, ld_x, 3 * r, 0) = xr;
    DenseBlock<S, 3, 1>(g, ld, 3 * r, 0) -= xr * go;
  }
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
