#include "swf/frontend/harris.hpp"

#include <algorithm>
#include <cstring>

namespace swf::frontend {

using core::Status;

namespace {

// hs[i] = sum_{j=0..2R} p[i + j] for i in [0, n). R is a template parameter so the taps unroll
// into one vectorised expression per i (a runtime tap loop does not vectorise).
template <int R>
void BoxRow(const float* __restrict p, float* __restrict hs, int n) {
  for (int i = 0; i < n; ++i) {
    float s = p[i];
    for (int j = 1; j <= 2 * R; ++j) s += p[i + j];
    hs[i] = s;
  }
}

void BoxRow(int r, const float* p, float* hs, int n) {
  switch (r) {
    case 1: BoxRow<1>(p, hs, n); break;
    case 2: BoxRow<2>(p, hs, n); break;
    case 3: BoxRow<3>(p, hs, n); break;
    default: BoxRow<4>(p, hs, n); break;
  }
}

// Largest of v[0, n), in 8 independent lanes so it vectorises (max is exact: any order gives
// the same value).
float RowMax(const float* v, int n, float m) {
  float lane[8] = {m, m, m, m, m, m, m, m};
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    for (int j = 0; j < 8; ++j) lane[j] = lane[j] > v[i + j] ? lane[j] : v[i + j];
  }
  for (; i < n; ++i) lane[0] = lane[0] > v[i] ? lane[0] : v[i];
  for (int j = 1; j < 8; ++j) lane[0] = lane[0] > lane[j] ? lane[0] : lane[j];
  return lane[0];
}

}  // namespace

Status HarrisDetector::Configure(const HarrisOptions& options) {
  configured_ = false;
  if (options.window_radius < 1 || options.window_radius > 4 || !(options.k > 0.0f) ||
      !(options.quality_level >= 0.0f) || options.border_px < options.window_radius + 2 ||
      options.bucket_cols < 1 || options.bucket_rows < 1 ||
      options.bucket_cols * options.bucket_rows > kMaxBuckets || options.max_per_bucket < 1 ||
      options.max_per_bucket > kMaxCandidatesPerBucket || !(options.min_distance_px >= 0.0f)) {
    return Status::kInvalidArgument;
  }
  options_ = options;
  configured_ = true;
  return Status::kOk;
}

// One pass over the rows: gradient products of row yy, their horizontal box sums into the ring
// slot of row yy, and vertical running sums over the last 2r+1 rows, which give the structure
// tensor of row yy - r. All values are integers below 2^24 (products <= 255^2, at most 81 of
// them summed), so float arithmetic is exact and the running sums never drift; float rather
// than int32 because baseline x86-64 (SSE2) vectorises float multiplies but not int32 ones.
// Arrays are indexed from the first column of the area: products at column x0 - r + i, box sums
// and the tensor at column x0 + i.
float HarrisDetector::ComputeResponse(const GrayView& image, int x0, int x1, int y0, int y1) {
  const int r = options_.window_radius;
  const int side = 2 * r + 1;
  const int n = x1 - x0;
  const int np = n + 2 * r;
  const int px0 = x0 - r;
  const float k = options_.k;
  core::ImageView<float> resp = response_.View();
  for (int c = 0; c < 3; ++c) std::fill(vertical_[c], vertical_[c] + n, 0.0f);
  float max_response = 0.0f;
  for (int yy = y0 - r, row = 0; yy < y1 + r; ++yy, ++row) {
    const int slot = row % side;
    float* pxx = products_[0];
    float* pxy = products_[1];
    float* pyy = products_[2];
    const std::uint8_t* rm = image.Row(yy - 1) + px0;
    const std::uint8_t* rc = image.Row(yy) + px0;
    const std::uint8_t* rp = image.Row(yy + 1) + px0;
    for (int i = 0; i < np; ++i) {
      const float gx = static_cast<float>(rc[i + 1] - rc[i - 1]);
      const float gy = static_cast<float>(rp[i] - rm[i]);
      pxx[i] = gx * gx;
      pxy[i] = gx * gy;
      pyy[i] = gy * gy;
    }
    for (int c = 0; c < 3; ++c) {
      float* hs = ring_[c][slot];
      float* v = vertical_[c];
      if (row >= side) {
        for (int i = 0; i < n; ++i) v[i] -= hs[i];
      }
      BoxRow(r, products_[c], hs, n);
      for (int i = 0; i < n; ++i) v[i] += hs[i];
    }
    if (row >= side - 1) {
      float* out = resp.Row(yy - r) + x0;
      const float* a = vertical_[0];
      const float* b = vertical_[1];
      const float* c = vertical_[2];
      for (int i = 0; i < n; ++i) {
        const float fa = a[i];
        const float fb = b[i];
        const float fc = c[i];
        const float tr = fa + fc;
        out[i] = fa * fc - fb * fb - k * tr * tr;
      }
      max_response = RowMax(out, n, max_response);
    }
  }
  return max_response;
}

// Ties go to the later pixel in raster order (strict > before, >= after), which makes the choice
// deterministic. The comparisons are computed for a whole row into a mask (vectorised), and only
// the maxima are visited.
void HarrisDetector::CollectMaxima(int x0, int x1, int y0, int y1, float threshold) {
  const core::ImageView<float> resp = response_.View();
  const int cap = kMaxCandidatesPerBucket;
  const int n = x1 - x0;
  for (int y = y0; y < y1; ++y) {
    const float* rm = resp.Row(y - 1) + x0;
    const float* rc = resp.Row(y) + x0;
    const float* rp = resp.Row(y + 1) + x0;
    for (int i = 0; i < n; ++i) {
      const float v = rc[i];
      const float before = std::max(std::max(rm[i - 1], rm[i]), std::max(rm[i + 1], rc[i - 1]));
      const float after = std::max(std::max(rc[i + 1], rp[i - 1]), std::max(rp[i], rp[i + 1]));
      maxima_[i] = static_cast<std::uint8_t>((v > threshold) & (v >= before) & (v > after));
    }
    const int by = bucket_row_[y] * options_.bucket_cols;
    for (int i = 0; i < n; ++i) {
      if (i + 8 <= n) {
        std::uint64_t word = 0;
        std::memcpy(&word, maxima_ + i, sizeof(word));
        if (word == 0) {
          i += 7;
          continue;
        }
      }
      if (maxima_[i] == 0) continue;
      const float v = rc[i];
      const int x = x0 + i;
      Bucket& bucket = buckets_[by + bucket_col_[x]];
      // Insertion into a short list sorted by decreasing response.
      int pos = bucket.count;
      while (pos > 0 && bucket.candidates[pos - 1].response < v) --pos;
      if (pos >= cap) continue;
      const int last = std::min(bucket.count, cap - 1);
      for (int j = last; j > pos; --j) bucket.candidates[j] = bucket.candidates[j - 1];
      bucket.candidates[pos] = Corner{static_cast<float>(x), static_cast<float>(y), v};
      bucket.count = std::min(bucket.count + 1, cap);
    }
  }
}

int HarrisDetector::BucketOf(float x, float y) const {
  int bx = static_cast<int>(x) * options_.bucket_cols / width_;
  int by = static_cast<int>(y) * options_.bucket_rows / height_;
  bx = std::clamp(bx, 0, options_.bucket_cols - 1);
  by = std::clamp(by, 0, options_.bucket_rows - 1);
  return by * options_.bucket_cols + bx;
}

int HarrisDetector::BucketColBegin(int bx) const {
  return (bx * width_ + options_.bucket_cols - 1) / options_.bucket_cols;
}

int HarrisDetector::BucketRowBegin(int by) const {
  return (by * height_ + options_.bucket_rows - 1) / options_.bucket_rows;
}

Status HarrisDetector::Detect(const GrayView& image, const Point2f* occupied,
                              std::size_t num_occupied, CornerList* corners) {
  corners->clear();
  if (!configured_) return Status::kNotConfigured;
  if (!image.Valid() || image.width < 2 * options_.border_px + 3 ||
      image.height < 2 * options_.border_px + 3) {
    return Status::kInvalidArgument;
  }
  if (image.width > kMaxImageWidth || image.height > kMaxImageHeight) {
    return Status::kInvalidArgument;
  }
  if (Status s = response_.Resize(image.width, image.height); s != Status::kOk) return s;
  width_ = image.width;
  height_ = image.height;
  const int cols = options_.bucket_cols;
  const int rows = options_.bucket_rows;
  for (int x = 0; x < width_; ++x) bucket_col_[x] = static_cast<std::int16_t>(x * cols / width_);
  for (int y = 0; y < height_; ++y) bucket_row_[y] = static_cast<std::int16_t>(y * rows / height_);

  const int num_buckets = cols * rows;
  for (int b = 0; b < num_buckets; ++b) {
    buckets_[b].count = 0;
    buckets_[b].occupied = 0;
  }
  for (std::size_t i = 0; i < num_occupied; ++i) {
    if (!(occupied[i].x >= 0.0f && occupied[i].y >= 0.0f && occupied[i].x < width_ &&
          occupied[i].y < height_)) {
      continue;
    }
    ++buckets_[BucketOf(occupied[i].x, occupied[i].y)].occupied;
  }
  int num_needed = 0;
  for (int b = 0; b < num_buckets; ++b) {
    needed_[b] = buckets_[b].occupied < options_.max_per_bucket;
    num_needed += needed_[b] ? 1 : 0;
  }
  if (num_needed == 0) return Status::kOk;

  // Search areas: the whole interior when every bucket is searched, else runs of needed buckets
  // along each bucket row, clipped to the border. The response is computed one pixel beyond
  // each area for the 3x3 suppression.
  const int border = options_.border_px;
  struct Area {
    int x0, x1, y0, y1;
  };
  float max_response = 0.0f;
  auto clip = [&](Area a) {
    return Area{std::max(a.x0, border), std::min(a.x1, width_ - border), std::max(a.y0, border),
                std::min(a.y1, height_ - border)};
  };
  auto for_each_area = [&](auto&& f) {
    if (num_needed == num_buckets) {
      f(Area{border, width_ - border, border, height_ - border});
      return;
    }
    for (int by = 0; by < rows; ++by) {
      for (int bx = 0; bx < cols;) {
        if (!needed_[by * cols + bx]) {
          ++bx;
          continue;
        }
        int end = bx;
        while (end < cols && needed_[by * cols + end]) ++end;
        const Area a = clip(Area{BucketColBegin(bx), BucketColBegin(end), BucketRowBegin(by),
                                 BucketRowBegin(by + 1)});
        if (a.x0 < a.x1 && a.y0 < a.y1) f(a);
        bx = end;
      }
    }
  };
  for_each_area([&](const Area& a) {
    max_response =
        std::max(max_response, ComputeResponse(image, a.x0 - 1, a.x1 + 1, a.y0 - 1, a.y1 + 1));
  });
  if (!(max_response > 0.0f)) return Status::kOk;  // a blank image has no corners
  const float threshold = options_.quality_level * max_response;
  for_each_area([&](const Area& a) { CollectMaxima(a.x0, a.x1, a.y0, a.y1, threshold); });

  const float min_d2 = options_.min_distance_px * options_.min_distance_px;
  for (int b = 0; b < num_buckets; ++b) {
    const Bucket& bucket = buckets_[b];
    const std::size_t first = corners->size();
    int quota = options_.max_per_bucket - bucket.occupied;
    for (int i = 0; i < bucket.count && quota > 0; ++i) {
      const Corner& c = bucket.candidates[i];
      bool far = true;
      for (std::size_t j = first; j < corners->size() && far; ++j) {
        const float dx = (*corners)[j].x - c.x;
        const float dy = (*corners)[j].y - c.y;
        far = dx * dx + dy * dy >= min_d2;
      }
      for (std::size_t j = 0; j < num_occupied && far; ++j) {
        const float dx = occupied[j].x - c.x;
        const float dy = occupied[j].y - c.y;
        far = dx * dx + dy * dy >= min_d2;
      }
      if (!far) continue;
      if (corners->push_back(c) != Status::kOk) return Status::kFull;
      --quota;
    }
  }
  return Status::kOk;
}

}  // namespace swf::frontend
