// Moravec's rigid-consistency check (paper 4.1.1): correspondences between 3-D points at two
// times are consistent in pairs when their mutual distance is preserved,
//   C_ab = | |p0_a - p0_b| - |p1_a - p1_b| |  <  abs_tolerance_m + rel_tolerance * |p0_a - p0_b|
//                                              + s (max(z0_a, z1_a)^2 + max(z0_b, z1_b)^2),
// with s = disparity_tolerance_px / (fx b): the relative term absorbs calibration scale error,
// the last one stereo depth error, which grows with the square of the depth z (camera frame:
// dz = z^2 dd / (fx b)), and dominates at altitude (at 100 m with a 1 m baseline and fx = 722 px,
// 0.1 px of disparity is 1.4 m of depth). fx b = 0 disables it. In the graph of
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
  double disparity_tolerance_px = 0.3;  // stereo depth term (file comment)
  double focal_baseline_px_m = 0.0;     // fx * baseline of the rig; 0 disables the depth term
};

template <std::size_t kCapacity = kMaxTracks>
class RigidConsistency {
 public:
  static constexpr std::size_t kWords = (kCapacity + 63) / 64;

  core::Status Configure(const ConsistencyOptions& options) {
    if (!(options.abs_tolerance_m >= 0.0) || !(options.rel_tolerance >= 0.0) ||
        !(options.disparity_tolerance_px >= 0.0) || !(options.focal_baseline_px_m >= 0.0)) {
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
    const double s = options_.focal_baseline_px_m > 0.0
                         ? options_.disparity_tolerance_px / options_.focal_baseline_px_m
                         : 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double z = std::fmax(std::fabs(p0[i].z()), std::fabs(p1[i].z()));
      depth_term_[i] = s * z * z;
    }
    for (std::size_t a = 0; a < n; ++a) {
      for (std::size_t b = a + 1; b < n; ++b) {
        const double d0 = (p0[a] - p0[b]).norm();
        const double d1 = (p1[a] - p1[b]).norm();
        if (std::abs(d0 - d1) < options_.abs_tolerance_m + options_.rel_tolerance * d0 +
                                    depth_term_[a] + depth_term_[b]) {
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
  double depth_term_[kCapacity] = {};
  std::size_t order_[kCapacity] = {};
};

}  // namespace swf::frontend
