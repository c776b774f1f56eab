// Moravec's rigid-consistency check (paper 4.1.1): correspondences between 3-D points at two
// times are consistent in pairs when their mutual distance is preserved,
//   C_ab = | |p0_a - p0_b| - |p1_a - p1_b| |  <  abs_tolerance_m + rel_tolerance * |p0_a - p0_b|,
// (the relative term absorbs stereo depth error, which grows with range). In the graph of
// consistent pairs the largest clique is the largest rigidly moving subset; the greedy maximal
// clique grown from the highest-degree node (ties: lowest index; candidates by decreasing degree)
// approximates it in O(n^2) with a bit matrix.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "swf/core/status.hpp"
#include "swf/frontend/config.hpp"

namespace swf::frontend {

struct ConsistencyOptions {
  double abs_tolerance_m = 0.05;
  double rel_tolerance = 0.05;
};

template <std::size_t kCapacity = kMaxTracks>
class RigidConsistency {
 public:
  static constexpr std::size_t kWords = (kCapacity + 63) / 64;

  core::Status Configure(const ConsistencyOptions& options) {
    if (!(options.abs_tolerance_m >= 0.0) || !(options.rel_tolerance >= 0.0)) {
      return core::Status::kInvalidArgument;
    }
    options_ = options;
    return core::Status::kOk;
  }

  // p0[i] and p1[i] are one correspondence (any frames, metres). inlier[i] receives membership in
  // the clique; *num_inliers its size. kInvalidArgument when n exceeds the capacity.
  core::Status Run(const Eigen::Vector3d* p0, const Eigen::Vector3d* p1, std::size_t n,
                   bool* inlier, std::size_t* num_inliers) {
    *num_inliers = 0;
    if (n > kCapacity) return core::Status::kInvalidArgument;
    for (std::size_t i = 0; i < n; ++i) {
      inlier[i] = false;
      degree_[i] = 0;
      for (std::size_t w = 0; w < kWords; ++w) adjacency_[i][w] = 0;
    }
    if (n == 0) return core::Status::kOk;
    for (std::size_t a = 0; a < n; ++a) {
      for (std::size_t b = a + 1; b < n; ++b) {
        const double d0 = (p0[a] - p0[b]).norm();
        const double d1 = (p1[a] - p1[b]).norm();
        if (std::abs(d0 - d1) < options_.abs_tolerance_m + options_.rel_tolerance * d0) {
          adjacency_[a][b / 64] |= std::uint64_t{1} << (b % 64);
          adjacency_[b][a / 64] |= std::uint64_t{1} << (a % 64);
          ++degree_[a];
          ++degree_[b];
        }
      }
    }
    std::size_t seed = 0;
    for (std::size_t i = 1; i < n; ++i) {
      if (degree_[i] > degree_[seed]) seed = i;
    }
    // Candidates: the seed's neighbours by decreasing degree (stable: insertion sort by index).
    std::size_t num_candidates = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!Adjacent(seed, i)) continue;
      std::size_t pos = num_candidates++;
      while (pos > 0 && degree_[order_[pos - 1]] < degree_[i]) {
        order_[pos] = order_[pos - 1];
        --pos;
      }
      order_[pos] = i;
    }
    for (std::size_t w = 0; w < kWords; ++w) clique_[w] = 0;
    clique_[seed / 64] |= std::uint64_t{1} << (seed % 64);
    for (std::size_t c = 0; c < num_candidates; ++c) {
      const std::size_t v = order_[c];
      bool all = true;
      for (std::size_t w = 0; w < kWords && all; ++w) {
        all = (adjacency_[v][w] & clique_[w]) == clique_[w];
      }
      if (all) clique_[v / 64] |= std::uint64_t{1} << (v % 64);
    }
    for (std::size_t i = 0; i < n; ++i) {
      inlier[i] = (clique_[i / 64] >> (i % 64)) & 1u;
      if (inlier[i]) ++*num_inliers;
    }
    return core::Status::kOk;
  }

 private:
  bool Adjacent(std::size_t a, std::size_t b) const {
    return (adjacency_[a][b / 64] >> (b % 64)) & 1u;
  }

  ConsistencyOptions options_{};
  std::uint64_t adjacency_[kCapacity][kWords] = {};
  std::uint64_t clique_[kWords] = {};
  std::uint32_t degree_[kCapacity] = {};
  std::size_t order_[kCapacity] = {};
};

}  // namespace swf::frontend
