#include "swf/frontend/harris.hpp"

#include <algorithm>

namespace swf::frontend {

using core::Status;

namespace {

// hs[x] = sum_{d=-R..R} p[x+d] for x in [R, w-R), 0 elsewhere. R is a template parameter so the
// taps unroll into one vectorised expression per x (a runtime tap loop does not vectorise).
template <int R>
void BoxRow(const float* __restrict p, float* __restrict hs, int w) {
  for (int x = 0; x < R; ++x) hs[x] = 0.0f;
  for (int x = w - R; x < w; ++x) hs[x] = 0.0f;
  for (int x = R; x < w - R; ++x) {
    float s = p[x - R];
    for (int d = 1 - R; d <= R; ++d) s += p[x + d];
    hs[x] = s;
  }
}

void BoxRow(int r, const float* p, float* hs, int w) {
  switch (r) {
    case 1: BoxRow<1>(p, hs, w); break;
    case 2: BoxRow<2>(p, hs, w); break;
    case 3: BoxRow<3>(p, hs, w); break;
    default: BoxRow<4>(p, hs, w); break;
  }
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
void HarrisDetector::ComputeResponse(const GrayView& image) {
  const int w = image.width;
  const int h = image.height;
  const int r = options_.window_radius;
  const int side = 2 * r + 1;
  const float k = options_.k;
  ImageView<float> resp = response_.View();
  for (int c = 0; c < 3; ++c) std::fill(vertical_[c], vertical_[c] + w, 0.0f);
  for (int yy = 0; yy < h; ++yy) {
    const int slot = yy % side;
    if (yy >= side) {
      for (int c = 0; c < 3; ++c) {
        float* v = vertical_[c];
        const float* old = ring_[c][slot];
        for (int x = 0; x < w; ++x) v[x] -= old[x];
      }
    }
    float* pxx = products_[0];
    float* pxy = products_[1];
    float* pyy = products_[2];
    if (yy == 0 || yy == h - 1) {
      for (int c = 0; c < 3; ++c) std::fill(products_[c], products_[c] + w, 0.0f);
    } else {
      const std::uint8_t* rm = image.Row(yy - 1);
      const std::uint8_t* rc = image.Row(yy);
      const std::uint8_t* rp = image.Row(yy + 1);
      pxx[0] = pxy[0] = pyy[0] = 0.0f;
      pxx[w - 1] = pxy[w - 1] = pyy[w - 1] = 0.0f;
      for (int x = 1; x < w - 1; ++x) {
        const float gx = static_cast<float>(rc[x + 1] - rc[x - 1]);
        const float gy = static_cast<float>(rp[x] - rm[x]);
        pxx[x] = gx * gx;
        pxy[x] = gx * gy;
        pyy[x] = gy * gy;
      }
    }
    for (int c = 0; c < 3; ++c) {
      float* hs = ring_[c][slot];
      BoxRow(r, products_[c], hs, w);
      float* v = vertical_[c];
      for (int x = 0; x < w; ++x) v[x] += hs[x];
    }
    if (yy >= side - 1) {
      float* out = resp.Row(yy - r);
      const float* a = vertical_[0];
      const float* b = vertical_[1];
      const float* c = vertical_[2];
      for (int x = 0; x < w; ++x) {
        const float fa = a[x];
        const float fb = b[x];
        const float fc = c[x];
        const float tr = fa + fc;
        out[x] = fa * fc - fb * fb - k * tr * tr;
      }
    }
  }
  for (int y = 0; y < r && y < h; ++y) std::fill(resp.Row(y), resp.Row(y) + w, 0.0f);
  for (int y = std::max(0, h - r); y < h; ++y) std::fill(resp.Row(y), resp.Row(y) + w, 0.0f);
}

int HarrisDetector::BucketOf(float x, float y) const {
  int bx = static_cast<int>(x) * options_.bucket_cols / width_;
  int by = static_cast<int>(y) * options_.bucket_rows / height_;
  bx = std::clamp(bx, 0, options_.bucket_cols - 1);
  by = std::clamp(by, 0, options_.bucket_rows - 1);
  return by * options_.bucket_cols + bx;
}

Status HarrisDetector::Detect(const GrayView& image, const Point2f* occupied,
                              std::size_t num_occupied, CornerList* corners) {
  corners->clear();
  if (!configured_) return Status::kNotConfigured;
  if (!image.Valid() || image.width < 2 * options_.border_px + 3 ||
      image.height < 2 * options_.border_px + 3) {
    return Status::kInvalidArgument;
  }
  if (image.width > kMaxImageWidth) return Status::kInvalidArgument;
  if (Status s = response_.Resize(image.width, image.height); s != Status::kOk) return s;
  width_ = image.width;
  height_ = image.height;
  ComputeResponse(image);

  const ImageView<float> resp = response_.View();
  const int border = options_.border_px;
  float max_response = 0.0f;
  for (int y = border; y < height_ - border; ++y) {
    const float* row = resp.Row(y);
    for (int x = border; x < width_ - border; ++x) max_response = std::max(max_response, row[x]);
  }
  if (!(max_response > 0.0f)) return Status::kOk;  // a blank image has no corners
  const float threshold = options_.quality_level * max_response;

  const int num_buckets = options_.bucket_cols * options_.bucket_rows;
  for (int b = 0; b < num_buckets; ++b) {
    buckets_[b].count = 0;
    buckets_[b].occupied = 0;
  }
  for (std::size_t i = 0; i < num_occupied; ++i) {
    if (occupied[i].x < 0.0f || occupied[i].y < 0.0f || occupied[i].x >= width_ ||
        occupied[i].y >= height_) {
      continue;
    }
    ++buckets_[BucketOf(occupied[i].x, occupied[i].y)].occupied;
  }

  // 3x3 non-maximum suppression; ties go to the later pixel in raster order (strict > before,
  // >= after), which makes the choice deterministic.
  const int cap = kMaxCandidatesPerBucket;
  for (int y = border; y < height_ - border; ++y) {
    const float* rm = resp.Row(y - 1);
    const float* rc = resp.Row(y);
    const float* rp = resp.Row(y + 1);
    for (int x = border; x < width_ - border; ++x) {
      const float v = rc[x];
      if (v <= threshold) continue;
      if (!(v >= rm[x - 1] && v >= rm[x] && v >= rm[x + 1] && v >= rc[x - 1] && v > rc[x + 1] &&
            v > rp[x - 1] && v > rp[x] && v > rp[x + 1])) {
        continue;
      }
      Bucket& bucket = buckets_[BucketOf(static_cast<float>(x), static_cast<float>(y))];
      // Insertion into a short list sorted by decreasing response.
      int pos = bucket.count;
      while (pos > 0 && bucket.candidates[pos - 1].response < v) --pos;
      if (pos >= cap) continue;
      const int last = std::min(bucket.count, cap - 1);
      for (int i = last; i > pos; --i) bucket.candidates[i] = bucket.candidates[i - 1];
      bucket.candidates[pos] = Corner{static_cast<float>(x), static_cast<float>(y), v};
      bucket.count = std::min(bucket.count + 1, cap);
    }
  }

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
