// Semi-global matching (see dense_stereo.hpp for the method).
#include "swf/hazard/dense_stereo.hpp"

#include <algorithm>
#include <cstdlib>

#include "sgm_kernels.hpp"

namespace swf::hazard {

using sgm_detail::kBorder;
using sgm_detail::kCensusPlanes;
using sgm_detail::kDisparityUnit;
using sgm_detail::kLead;

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

namespace {

int RoundUp(int v, int unit) { return (v + unit - 1) / unit * unit; }

}  // namespace

core::Status SgmMatcher::Configure(const SgmOptions& options) {
  configured_ = false;
  if (options.max_width < 8 || options.max_height < 8 ||
      (options.paths != 4 && options.paths != 8) || options.p1 <= 0 || options.p2 < options.p1 ||
      options.p2 > 1000 || options.max_disparities < 4 || options.max_disparities > 256 ||
      !(options.uniqueness >= 0.0f) || !(options.lr_max_diff >= 0.0f) ||
      !SgmKernelSupported(options.kernel)) {
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  kernel_ = sgm_detail::Resolve(options.kernel);
  const std::size_t w = static_cast<std::size_t>(options.max_width);
  const std::size_t h = static_cast<std::size_t>(options.max_height);
  const int max_padded = RoundUp(options.max_disparities, kDisparityUnit);
  const std::size_t dp = static_cast<std::size_t>(max_padded);
  const std::size_t max_path_stride = dp + 2 * kLead;
  census_stride_ = options.max_width + sgm_detail::kCostUnit;
  const std::size_t census = kCensusPlanes * h * static_cast<std::size_t>(census_stride_);
  census_left_.assign(census, 0);
  census_right_.assign(census, 0);
  cost_volume_.assign(h * w * static_cast<std::size_t>(RoundUp(max_padded, sgm_detail::kCostUnit)),
                      0);
  forward_sum_.assign(h * w * dp, 0);
  row_sum_.assign(w * dp, 0);
  path_rows_.assign(2 * 3 * w * max_path_stride, kBorder);
  path_mins_.assign(2 * 3 * w, 0);
  path_horizontal_.assign(2 * max_path_stride, kBorder);
  path_start_.assign(max_path_stride, 0);
  pad_floor_.assign(dp, 0);
  right_window_.assign(2 * (dp + 2 * kDisparityUnit), 0);
  p2_table_.resize(256);
  for (int di = 0; di < 256; ++di) {
    // P2 falls at intensity edges, where disparity jumps are likely; it stays above P1.
    p2_table_[di] =
        static_cast<std::int16_t>(std::max(options.p2 * 16 / (16 + di), options.p1 + 1));
  }
  disparity_.assign(w * h, kInvalid);
  confidence_.assign(w * h, 0.0f);
  right_disparity_.assign(w, kInvalid);
  width_ = 0;
  height_ = 0;
  configured_ = true;
  return core::Status::kOk;
}

void SgmMatcher::CensusPair(const frontend::GrayView& left, const frontend::GrayView& right) {
  const std::size_t plane = static_cast<std::size_t>(height_) * census_stride_;
  for (int y = 0; y < height_; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * census_stride_;
    std::uint8_t* l[kCensusPlanes];
    std::uint8_t* r[kCensusPlanes];
    for (int p = 0; p < kCensusPlanes; ++p) {
      l[p] = census_left_.data() + p * plane + row;
      r[p] = census_right_.data() + p * plane + row;
    }
    sgm_detail::CensusRow(left, y, false, l);
    sgm_detail::CensusRow(right, y, true, r);
  }
}

void SgmMatcher::CostRow(int y, int min_disparity) {
  const std::size_t plane = static_cast<std::size_t>(height_) * census_stride_;
  const std::size_t row = static_cast<std::size_t>(y) * census_stride_;
  sgm_detail::CostRowJob job;
  for (int p = 0; p < kCensusPlanes; ++p) {
    job.left[p] = census_left_.data() + p * plane + row;
    job.right[p] = census_right_.data() + p * plane + row;
  }
  job.width = width_;
  job.min_disparity = min_disparity;
  job.padded_d = padded_d_;
  job.cost_stride = RoundUp(padded_d_, sgm_detail::kCostUnit);
  job.cost = CostsOfRow(y);
  sgm_detail::KernelsOf(kernel_).cost_row(job);
}

std::uint8_t* SgmMatcher::CostsOfRow(int y) {
  return cost_volume_.data() +
         static_cast<std::size_t>(y) * width_ *
             static_cast<std::size_t>(RoundUp(padded_d_, sgm_detail::kCostUnit));
}

void SgmMatcher::PassRow(int y, bool forward, bool first_row, const frontend::GrayView& left) {
  const std::size_t w = static_cast<std::size_t>(width_);
  const std::size_t block = 3 * w * static_cast<std::size_t>(path_stride_);
  // The vertical paths' rows alternate between the two halves of path_rows_ / path_mins_.
  const bool odd = (y & 1) != 0;
  sgm_detail::PassRowJob job;
  job.forward = forward;
  job.num_vertical = options_.paths == 8 ? 3 : 1;
  job.width = width_;
  job.padded_d = padded_d_;
  job.path_stride = path_stride_;
  job.cost_stride = RoundUp(padded_d_, sgm_detail::kCostUnit);
  job.p1 = static_cast<std::int16_t>(options_.p1);
  job.p2_table = p2_table_.data();
  job.cost = CostsOfRow(y);
  job.image = left.Row(y);
  job.image_prev = first_row ? nullptr : left.Row(forward ? y - 1 : y + 1);
  job.prev_rows = path_rows_.data() + (odd ? 0 : block);
  job.cur_rows = path_rows_.data() + (odd ? block : 0);
  job.prev_mins = path_mins_.data() + (odd ? 0 : 3 * w);
  job.cur_mins = path_mins_.data() + (odd ? 3 * w : 0);
  job.horizontal = path_horizontal_.data();
  job.start = path_start_.data();
  job.pad_floor = pad_floor_.data();
  std::int16_t* sum = forward_sum_.data() + static_cast<std::size_t>(y) * w * padded_d_;
  job.sum_in = forward ? nullptr : sum;
  job.sum_out = forward ? sum : row_sum_.data();
  sgm_detail::KernelsOf(kernel_).pass_row(job);
}

void SgmMatcher::SelectRow(int y, int min_disparity) {
  const std::size_t at = static_cast<std::size_t>(y) * width_;
  sgm_detail::SelectRowJob job;
  job.sum = row_sum_.data();
  job.width = width_;
  job.min_disparity = min_disparity;
  job.num_d = num_d_;
  job.padded_d = padded_d_;
  job.uniqueness = options_.uniqueness;
  job.lr_max_diff = options_.lr_max_diff;
  job.window = right_window_.data();
  job.right = right_disparity_.data();
  job.disparity = disparity_.data() + at;
  job.confidence = confidence_.data() + at;
  sgm_detail::KernelsOf(kernel_).select_row(&job);
  num_valid_ += job.num_valid;
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
  padded_d_ = RoundUp(num_d_, kDisparityUnit);
  path_stride_ = padded_d_ + 2 * kLead;
  // Sentinels of this disparity count: around every path vector and in its padding lanes.
  for (std::size_t v = 0; v < 2 * 3 * static_cast<std::size_t>(width_); ++v) {
    std::int16_t* vec = path_rows_.data() + v * path_stride_ + kLead;
    vec[-1] = kBorder;
    vec[padded_d_] = kBorder;
  }
  for (int v = 0; v < 2; ++v) {
    std::int16_t* vec = path_horizontal_.data() + v * path_stride_ + kLead;
    vec[-1] = kBorder;
    vec[padded_d_] = kBorder;
  }
  for (int d = 0; d < padded_d_; ++d) pad_floor_[d] = d < num_d_ ? 0 : kBorder;
  CensusPair(left, right);
  for (int y = 0; y < height_; ++y) {
    CostRow(y, min_disparity);
    PassRow(y, true, y == 0, left);
  }
  num_valid_ = 0;
  for (int y = height_ - 1; y >= 0; --y) {
    PassRow(y, false, y == height_ - 1, left);
    SelectRow(y, min_disparity);
  }
  return core::Status::kOk;
}

}  // namespace swf::hazard
