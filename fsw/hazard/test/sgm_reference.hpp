// A straightforward scalar SGM, the oracle the matcher's vector kernels are tested against bit for
// bit: the same method as dense_stereo.hpp states it (5x5 census as 24-bit words, a stored cost
// volume, one pixel and one path at a time, the right image's winners by a plain search), written
// for clarity, not speed. Test-only: it allocates.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "swf/frontend/image.hpp"
#include "swf/hazard/dense_stereo.hpp"

namespace swf::hazard::testing {

struct ReferenceResult {
  std::vector<float> disparity;
  std::vector<float> confidence;
  int num_valid = 0;
};

class ReferenceSgm {
 public:
  ReferenceSgm(const SgmOptions& options, const frontend::GrayView& left,
               const frontend::GrayView& right, int min_d, int num_d)
      : o_(options), w_(left.width), h_(left.height), m_(min_d), n_(num_d) {
    const std::size_t pixels = static_cast<std::size_t>(w_) * h_;
    census_l_ = Census(left);
    census_r_ = Census(right);
    cost_.resize(pixels * n_);
    sum_.assign(pixels * n_, 0);
    MatchingCost();
    Aggregate(left);
    Select();
  }
  const ReferenceResult& Result() const { return result_; }

 private:
  static constexpr int kCostScale = 4;
  static constexpr int kMaxCost = 24 * kCostScale;
  static constexpr int kBorder = 1 << 20;  // outside the disparity range

  std::vector<std::uint32_t> Census(const frontend::GrayView& image) const {
    std::vector<std::uint32_t> out(static_cast<std::size_t>(w_) * h_);
    for (int y = 0; y < h_; ++y) {
      for (int x = 0; x < w_; ++x) {
        const int c = image.At(x, y);
        std::uint32_t bits = 0;
        for (int dy = -2; dy <= 2; ++dy) {
          for (int dx = -2; dx <= 2; ++dx) {
            if (dx == 0 && dy == 0) continue;
            const int v = image.At(std::clamp(x + dx, 0, w_ - 1), std::clamp(y + dy, 0, h_ - 1));
            bits = (bits << 1) | (v < c ? 1u : 0u);
          }
        }
        out[static_cast<std::size_t>(y) * w_ + x] = bits;
      }
    }
    return out;
  }

  std::size_t At(int x, int y) const { return (static_cast<std::size_t>(y) * w_ + x) * n_; }

  void MatchingCost() {
    for (int y = 0; y < h_; ++y) {
      for (int x = 0; x < w_; ++x) {
        const std::uint32_t l = census_l_[static_cast<std::size_t>(y) * w_ + x];
        for (int d = 0; d < n_; ++d) {
          const int xr = x - m_ - d;
          cost_[At(x, y) + d] =
              xr < 0 ? kMaxCost
                     : std::popcount(l ^ census_r_[static_cast<std::size_t>(y) * w_ + xr]) *
                           kCostScale;
        }
      }
    }
  }

  int P2(int i0, int i1) const {
    return std::max(o_.p2 * 16 / (16 + std::abs(i0 - i1)), o_.p1 + 1);
  }

  // L_r(p, d) = C(p, d) + min(L(p-r, d), L(p-r, d+-1) + P1, min_k L(p-r, k) + P2) - min_k
  // L(p-r, k); a path starts with L = C where p - r leaves the image.
  void Path(int x0, int y0, int rx, int ry, const frontend::GrayView& image) {
    std::vector<int> prev(n_);
    std::vector<int> cur(n_);
    int x = x0;
    int y = y0;
    bool first = true;
    while (x >= 0 && x < w_ && y >= 0 && y < h_) {
      const int* c = cost_.data() + At(x, y);
      if (first) {
        for (int d = 0; d < n_; ++d) cur[d] = c[d];
      } else {
        const int pm = *std::min_element(prev.begin(), prev.end());
        const int p2 = P2(image.At(x, y), image.At(x - rx, y - ry));
        for (int d = 0; d < n_; ++d) {
          const int lo = d > 0 ? prev[d - 1] + o_.p1 : kBorder;
          const int hi = d + 1 < n_ ? prev[d + 1] + o_.p1 : kBorder;
          cur[d] = c[d] + std::min({prev[d], lo, hi, pm + p2}) - pm;
        }
      }
      for (int d = 0; d < n_; ++d) sum_[At(x, y) + d] += cur[d];
      std::swap(prev, cur);
      first = false;
      x += rx;
      y += ry;
    }
  }

  // Every path of every direction: one starts at each image pixel its direction enters from.
  void Aggregate(const frontend::GrayView& image) {
    const int dirs8[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {-1, 1}, {1, -1}};
    for (int k = 0; k < o_.paths; ++k) {
      const int rx = dirs8[k][0];
      const int ry = dirs8[k][1];
      for (int y = 0; y < h_; ++y) {
        for (int x = 0; x < w_; ++x) {
          // (x, y) starts a path when the pixel before it along r is outside the image.
          const int px = x - rx;
          const int py = y - ry;
          if (px >= 0 && px < w_ && py >= 0 && py < h_) continue;
          Path(x, y, rx, ry, image);
        }
      }
    }
  }

  void Select() {
    const std::size_t pixels = static_cast<std::size_t>(w_) * h_;
    result_.disparity.assign(pixels, SgmMatcher::kInvalid);
    result_.confidence.assign(pixels, 0.0f);
    std::vector<float> right(static_cast<std::size_t>(w_));
    for (int y = 0; y < h_; ++y) {
      for (int xr = 0; xr < w_; ++xr) {
        int best = 1 << 30;
        int best_d = -1;
        for (int d = 0; d < n_ && xr + m_ + d < w_; ++d) {
          const int s = sum_[At(xr + m_ + d, y) + d];
          if (s < best) {
            best = s;
            best_d = d;
          }
        }
        right[xr] = best_d < 0 ? SgmMatcher::kInvalid : static_cast<float>(best_d + m_);
      }
      for (int x = m_ + n_ - 1; x < w_; ++x) {
        const int* s = sum_.data() + At(x, y);
        const int best_d = static_cast<int>(std::min_element(s, s + n_) - s);
        const int best = s[best_d];
        int second = 1 << 30;
        for (int d = 0; d < n_; ++d) {
          if (std::abs(d - best_d) > 1) second = std::min(second, s[d]);
        }
        if (best_d == 0 || best_d == n_ - 1) continue;
        const float margin =
            static_cast<float>(second - best) / static_cast<float>(std::max(best, 1));
        if (margin <= o_.uniqueness) continue;
        const float sm = static_cast<float>(s[best_d - 1]);
        const float s0 = static_cast<float>(s[best_d]);
        const float sp = static_cast<float>(s[best_d + 1]);
        const float denom = sm - 2.0f * s0 + sp;
        const float offset = denom > 0.0f ? 0.5f * (sm - sp) / denom : 0.0f;
        const float disparity = static_cast<float>(best_d + m_) + offset;
        const int xr = static_cast<int>(std::lround(static_cast<float>(x) - disparity));
        if (xr < 0 || xr >= w_) continue;
        const float dr = right[xr];
        if (dr == SgmMatcher::kInvalid) continue;
        const float lr = std::fabs(dr - disparity);
        if (lr > o_.lr_max_diff + 0.5f) continue;
        const std::size_t i = static_cast<std::size_t>(y) * w_ + x;
        result_.disparity[i] = disparity;
        result_.confidence[i] =
            std::min(1.0f, margin / 0.5f) * (1.0f - lr / (o_.lr_max_diff + 1.0f));
        ++result_.num_valid;
      }
    }
  }

  SgmOptions o_;
  int w_, h_, m_, n_;
  std::vector<std::uint32_t> census_l_, census_r_;
  std::vector<int> cost_;
  std::vector<int> sum_;
  ReferenceResult result_;
};

}  // namespace swf::hazard::testing
