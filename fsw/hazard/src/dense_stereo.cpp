// Semi-global matching (see dense_stereo.hpp for the method).
#include "swf/hazard/dense_stereo.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace swf::hazard {
namespace {

constexpr int kCensusRadius = 2;
constexpr int kCostScale = 4;              // Hamming (0..24) x 4
constexpr int kMaxCost = 24 * kCostScale;  // cost outside the right image
constexpr std::int16_t kBorder = 0x3FFF;   // sentinel around each path vector

// One step of the SGM recursion for one pixel and one path. prev points at element 0 of a vector
// with sentinels at [-1] and [n]; prev_min = min_k prev[k]. Writes out[0..n) (its sentinels are
// set by the caller) and adds to sum; returns min_k out[k].
inline std::int16_t PathStep(const std::uint8_t* cost, const std::int16_t* prev, int prev_min,
                             int n, int p1, int p2, std::int16_t* out, std::int16_t* sum) {
  // 16-bit arithmetic throughout (all values < 2^14) so the loop vectorizes on plain SSE2/NEON.
  const auto big = static_cast<std::int16_t>(prev_min + p2);
  const auto pen = static_cast<std::int16_t>(p1);
  const auto pm = static_cast<std::int16_t>(prev_min);
  std::int16_t out_min = 0x7FFF;
  for (int d = 0; d < n; ++d) {
    const std::int16_t a = static_cast<std::int16_t>(prev[d - 1] + pen);
    const std::int16_t b = static_cast<std::int16_t>(prev[d + 1] + pen);
    std::int16_t v = prev[d] < big ? prev[d] : big;
    v = a < v ? a : v;
    v = b < v ? b : v;
    const auto l = static_cast<std::int16_t>(cost[d] + v - pm);
    out[d] = l;
    sum[d] = static_cast<std::int16_t>(sum[d] + l);
    out_min = l < out_min ? l : out_min;
  }
  return out_min;
}

inline std::int16_t PathStart(const std::uint8_t* cost, int n, std::int16_t* out,
                              std::int16_t* sum) {
  int out_min = 0x7FFF;
  for (int d = 0; d < n; ++d) {
    out[d] = cost[d];
    sum[d] = static_cast<std::int16_t>(sum[d] + cost[d]);
    out_min = std::min<int>(out_min, cost[d]);
  }
  return static_cast<std::int16_t>(out_min);
}

inline int AdaptiveP2(int p1, int p2, int i0, int i1) {
  const int p = p2 * 16 / (16 + std::abs(i0 - i1));
  return std::max(p, p1 + 1);
}

}  // namespace

void HalveImage(const frontend::GrayView& src, std::uint8_t* dst) {
  const int w = src.width;
  const int h = src.height;
  const int w2 = (w + 1) / 2;
  const int h2 = (h + 1) / 2;
  for (int y = 0; y < h2; ++y) {
    const int sy = 2 * y;
    const std::uint8_t* rm = src.Row(sy > 0 ? sy - 1 : 0);
    const std::uint8_t* rc = src.Row(sy);
    const std::uint8_t* rp = src.Row(sy + 1 < h ? sy + 1 : h - 1);
    std::uint8_t* o = dst + static_cast<std::ptrdiff_t>(y) * w2;
    for (int x = 0; x < w2; ++x) {
      const int sx = 2 * x;
      const int xm = sx > 0 ? sx - 1 : 0;
      const int xp = sx + 1 < w ? sx + 1 : w - 1;
      const int cm = rm[xm] + 2 * rc[xm] + rp[xm];
      const int cc = rm[sx] + 2 * rc[sx] + rp[sx];
      const int cp = rm[xp] + 2 * rc[xp] + rp[xp];
      o[x] = static_cast<std::uint8_t>((cm + 2 * cc + cp + 8) >> 4);
    }
  }
}

core::Status SgmMatcher::Configure(const SgmOptions& options) {
  configured_ = false;
  if (options.max_width < 8 || options.max_height < 8 ||
      (options.paths != 4 && options.paths != 8) || options.p1 <= 0 || options.p2 < options.p1 ||
      options.p2 > 1000 || options.max_disparities < 4 || options.max_disparities > 256 ||
      !(options.uniqueness >= 0.0f) || !(options.lr_max_diff >= 0.0f)) {
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  const std::size_t pixels =
      static_cast<std::size_t>(options.max_width) * static_cast<std::size_t>(options.max_height);
  const std::size_t nd = static_cast<std::size_t>(options.max_disparities);
  const std::size_t stride = nd + 2;
  census_left_.assign(pixels, 0);
  census_right_.assign(pixels, 0);
  cost_.assign(pixels * nd, 0);
  sum_.assign(pixels * nd, 0);
  path_prev_.assign(3 * static_cast<std::size_t>(options.max_width) * stride, kBorder);
  path_cur_.assign(3 * static_cast<std::size_t>(options.max_width) * stride, kBorder);
  path_min_prev_.assign(3 * static_cast<std::size_t>(options.max_width), 0);
  path_min_cur_.assign(3 * static_cast<std::size_t>(options.max_width), 0);
  row_path_.assign(2 * stride, kBorder);
  disparity_.assign(pixels, kInvalid);
  confidence_.assign(pixels, 0.0f);
  right_disparity_.assign(static_cast<std::size_t>(options.max_width), kInvalid);
  width_ = 0;
  height_ = 0;
  configured_ = true;
  return core::Status::kOk;
}

void SgmMatcher::Census(const frontend::GrayView& image, std::uint32_t* out) const {
  for (int y = 0; y < height_; ++y) {
    const bool inner_row = y >= kCensusRadius && y < height_ - kCensusRadius;
    for (int x = 0; x < width_; ++x) {
      if (inner_row && x >= kCensusRadius && x < width_ - kCensusRadius) {
        // Interior: no clamping.
        const int c = image.At(x, y);
        std::uint32_t bits = 0;
        for (int dy = -kCensusRadius; dy <= kCensusRadius; ++dy) {
          const std::uint8_t* row = image.Row(y + dy) + x;
          for (int dx = -kCensusRadius; dx <= kCensusRadius; ++dx) {
            if (dx == 0 && dy == 0) continue;
            bits = (bits << 1) | (row[dx] < c ? 1u : 0u);
          }
        }
        out[static_cast<std::size_t>(y) * width_ + x] = bits;
        continue;
      }
      const int c = image.At(x, y);
      std::uint32_t bits = 0;
      for (int dy = -kCensusRadius; dy <= kCensusRadius; ++dy) {
        const int yy = std::clamp(y + dy, 0, height_ - 1);
        const std::uint8_t* row = image.Row(yy);
        for (int dx = -kCensusRadius; dx <= kCensusRadius; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int xx = std::clamp(x + dx, 0, width_ - 1);
          bits = (bits << 1) | (row[xx] < c ? 1u : 0u);
        }
      }
      out[static_cast<std::size_t>(y) * width_ + x] = bits;
    }
  }
}

void SgmMatcher::MatchingCost(int min_disparity) {
  const int n = num_d_;
  for (int y = 0; y < height_; ++y) {
    const std::uint32_t* cl = census_left_.data() + static_cast<std::size_t>(y) * width_;
    const std::uint32_t* cr = census_right_.data() + static_cast<std::size_t>(y) * width_;
    std::uint8_t* c = cost_.data() + static_cast<std::size_t>(y) * width_ * n;
    for (int x = 0; x < width_; ++x, c += n) {
      const std::uint32_t l = cl[x];
      const int first_out = x - min_disparity + 1;  // d >= first_out has xr < 0
      const int limit = std::clamp(first_out, 0, n);
      for (int d = 0; d < limit; ++d) {
        c[d] = static_cast<std::uint8_t>(std::popcount(l ^ cr[x - min_disparity - d]) * kCostScale);
      }
      for (int d = limit; d < n; ++d) c[d] = kMaxCost;
    }
  }
}

void SgmMatcher::Aggregate(const frontend::GrayView& left) {
  const int n = num_d_;
  const int w = width_;
  const std::size_t stride = static_cast<std::size_t>(n) + 2;
  const int p1 = options_.p1;
  const int p2 = options_.p2;
  std::fill(sum_.begin(), sum_.begin() + static_cast<std::ptrdiff_t>(w) * height_ * n, 0);
  const int num_vertical = options_.paths == 8 ? 3 : 1;
  // Sentinels around every path vector for this call's disparity count.
  for (std::size_t i = 0; i < 3 * static_cast<std::size_t>(w); ++i) {
    path_prev_[i * stride] = kBorder;
    path_prev_[i * stride + n + 1] = kBorder;
    path_cur_[i * stride] = kBorder;
    path_cur_[i * stride + n + 1] = kBorder;
  }
  row_path_[0] = row_path_[n + 1] = row_path_[stride] = row_path_[stride + n + 1] = kBorder;
  static constexpr int kDx[3] = {0, -1, 1};  // previous pixel at x + dx * dir of the row before
  for (int pass = 0; pass < 2; ++pass) {
    const int dir = pass == 0 ? 1 : -1;  // 1: top-down with left-to-right, -1: bottom-up, R-to-L
    for (int y0 = 0; y0 < height_; ++y0) {
      const int y = dir > 0 ? y0 : height_ - 1 - y0;
      const std::uint8_t* irow = left.Row(y);
      const std::uint8_t* iprev = left.Row(y0 == 0 ? y : y - dir);
      const std::uint8_t* crow = cost_.data() + static_cast<std::size_t>(y) * w * n;
      std::int16_t* srow = sum_.data() + static_cast<std::size_t>(y) * w * n;
      // Vertical and diagonal paths.
      const bool odd = (y0 & 1) != 0;
      for (int k = 0; k < num_vertical; ++k) {
        std::int16_t* buf_a = path_prev_.data() + k * w * stride;
        std::int16_t* buf_b = path_cur_.data() + k * w * stride;
        std::int16_t* min_a = path_min_prev_.data() + static_cast<std::size_t>(k) * w;
        std::int16_t* min_b = path_min_cur_.data() + static_cast<std::size_t>(k) * w;
        const std::int16_t* prev = odd ? buf_a : buf_b;
        std::int16_t* cur = odd ? buf_b : buf_a;
        const std::int16_t* pmin = odd ? min_a : min_b;
        std::int16_t* cmin = odd ? min_b : min_a;
        const int dx = kDx[k] * dir;
        for (int x = 0; x < w; ++x) {
          std::int16_t* out = cur + x * stride + 1;
          const int xp = x + dx;
          if (y0 == 0 || xp < 0 || xp >= w) {
            cmin[x] = PathStart(crow + static_cast<std::size_t>(x) * n, n, out,
                                srow + static_cast<std::size_t>(x) * n);
          } else {
            cmin[x] = PathStep(crow + static_cast<std::size_t>(x) * n, prev + xp * stride + 1,
                               pmin[xp], n, p1, AdaptiveP2(p1, p2, irow[x], iprev[xp]), out,
                               srow + static_cast<std::size_t>(x) * n);
          }
        }
      }
      // Horizontal path along this row.
      std::int16_t* a = row_path_.data() + 1;
      std::int16_t* b = row_path_.data() + stride + 1;
      int amin = 0;
      for (int x0 = 0; x0 < w; ++x0) {
        const int x = dir > 0 ? x0 : w - 1 - x0;
        const std::uint8_t* c = crow + static_cast<std::size_t>(x) * n;
        std::int16_t* s = srow + static_cast<std::size_t>(x) * n;
        if (x0 == 0) {
          amin = PathStart(c, n, a, s);
        } else {
          amin = PathStep(c, a, amin, n, p1, AdaptiveP2(p1, p2, irow[x], irow[x - dir]), b, s);
          std::swap(a, b);
        }
      }
    }
  }
}

void SgmMatcher::SelectDisparities(int min_disparity) {
  const int n = num_d_;
  const int w = width_;
  num_valid_ = 0;
  for (int y = 0; y < height_; ++y) {
    const std::int16_t* srow = sum_.data() + static_cast<std::size_t>(y) * w * n;
    // Right-image winners from the same volume: d_R(xr) = argmin_d S(xr + min + d, d).
    for (int xr = 0; xr < w; ++xr) {
      int best = 0xFFFFF;
      int best_d = -1;
      for (int d = 0; d < n; ++d) {
        const int x = xr + min_disparity + d;
        if (x >= w) break;
        const int s = srow[static_cast<std::size_t>(x) * n + d];
        if (s < best) {
          best = s;
          best_d = d;
        }
      }
      right_disparity_[xr] = best_d < 0 ? kInvalid : static_cast<float>(best_d + min_disparity);
    }
    float* drow = disparity_.data() + static_cast<std::size_t>(y) * w;
    float* qrow = confidence_.data() + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      drow[x] = kInvalid;
      qrow[x] = 0.0f;
      const std::int16_t* s = srow + static_cast<std::size_t>(x) * n;
      // Only pixels whose whole search range lies in the right image (as OpenCV's SGBM).
      if (x - min_disparity - (n - 1) < 0) continue;
      const int valid_n = n;
      int best = 0xFFFFF;
      int best_d = 0;
      for (int d = 0; d < valid_n; ++d) {
        if (s[d] < best) {
          best = s[d];
          best_d = d;
        }
      }
      int second = 0xFFFFF;
      for (int d = 0; d < valid_n; ++d) {
        if (d < best_d - 1 || d > best_d + 1) second = std::min<int>(second, s[d]);
      }
      if (best_d == 0 || best_d == valid_n - 1) continue;  // at the search limit: unreliable
      const float margin =
          static_cast<float>(second - best) / static_cast<float>(std::max(best, 1));
      if (margin <= options_.uniqueness) continue;
      const float sm = s[best_d - 1];
      const float s0 = s[best_d];
      const float sp = s[best_d + 1];
      const float denom = sm - 2.0f * s0 + sp;
      const float offset = denom > 0.0f ? 0.5f * (sm - sp) / denom : 0.0f;
      const float disparity = static_cast<float>(best_d + min_disparity) + offset;
      const int xr = static_cast<int>(std::lround(static_cast<float>(x) - disparity));
      if (xr < 0 || xr >= w) continue;
      const float dr = right_disparity_[xr];
      if (dr == kInvalid) continue;
      const float lr = std::fabs(dr - disparity);
      if (lr > options_.lr_max_diff + 0.5f) continue;
      drow[x] = disparity;
      const float unique_conf = std::min(1.0f, margin / 0.5f);
      const float lr_conf = 1.0f - lr / (options_.lr_max_diff + 1.0f);
      qrow[x] = unique_conf * lr_conf;
      ++num_valid_;
    }
  }
}

core::Status SgmMatcher::Compute(const frontend::GrayView& left, const frontend::GrayView& right,
                                 int min_disparity, int num_disparities) {
  if (!configured_) return core::Status::kNotConfigured;
  if (!left.Valid() || !right.Valid() || left.width != right.width || left.height != right.height ||
      left.width > options_.max_width || left.height > options_.max_height || left.width < 8 ||
      left.height < 8 || num_disparities < 4 || num_disparities > options_.max_disparities ||
      min_disparity < 0 || min_disparity + num_disparities >= left.width) {
    return core::Status::kInvalidArgument;
  }
  width_ = left.width;
  height_ = left.height;
  num_d_ = num_disparities;
  Census(left, census_left_.data());
  Census(right, census_right_.data());
  MatchingCost(min_disparity);
  Aggregate(left);
  SelectDisparities(min_disparity);
  return core::Status::kOk;
}

}  // namespace swf::hazard
