// Harris corner detector with non-maximum suppression and spatial bucketing.
//
// Response (Harris & Stephens 1988): with the structure tensor summed over a (2r+1)^2 box,
//   M = sum [Ix^2  IxIy; IxIy  Iy^2],   R = det(M) - k trace(M)^2,
// and central-difference gradients Ix = I(x+1) - I(x-1) (twice the usual scale: integers, so the
// box sums are exact and the response is computed in one streaming pass over the rows). A
// corner is a 3x3 local maximum of R above quality_level * max(R). Bucketing: the image is divided
// into a grid and each cell keeps its strongest corners (at most max_per_bucket, minus the tracks
// already in it), so the features cover the whole image instead of clustering on the most textured
// region, which keeps the estimator's geometry well conditioned.
//
// Only the buckets that still have a quota are searched: the response is computed over runs of
// such buckets along each bucket row (plus the few pixels of margin the window needs), so a frame
// whose tracks already fill most cells costs a fraction of a full pass. max(R) is then the
// strongest response of the searched area. The response of a pixel does not depend on the area
// it is computed in (integer sums, exact in float), so the corners of a bucket are the same
// whichever other buckets are searched.
#pragma once

#include <cstddef>
#include <cstdint>

#include "swf/core/static_vector.hpp"
#include "swf/core/status.hpp"
#include "swf/frontend/config.hpp"
#include "swf/frontend/image.hpp"

namespace swf::frontend {

struct Corner {
  float x = 0.0f;  // pixel column
  float y = 0.0f;  // pixel row
  float response = 0.0f;
};

using CornerList = core::StaticVector<Corner, kMaxCorners>;

struct Point2f {
  float x = 0.0f;
  float y = 0.0f;
};

struct HarrisOptions {
  float k = 0.04f;
  int window_radius = 2;           // structure tensor box: (2r+1)^2 pixels
  float quality_level = 0.00001f;  // threshold relative to the strongest searched response
  int border_px = 12;              // no corners closer than this to the edge
  int bucket_cols = 16;
  int bucket_rows = 12;
  int max_per_bucket = 2;
  float min_distance_px = 8.0f;  // between corners of one bucket and to occupied points
};

class HarrisDetector {
 public:
  // Validates the options (kInvalidArgument).
  core::Status Configure(const HarrisOptions& options);

  // Detects corners in `image`. `occupied` are points already tracked: they count against their
  // bucket's quota and repel new corners closer than min_distance_px. Output is ordered by bucket
  // (row-major) and by decreasing response inside a bucket. Never allocates.
  core::Status Detect(const GrayView& image, const Point2f* occupied, std::size_t num_occupied,
                      CornerList* corners);

  // The response image of the last call (for tests and plots): valid only around the buckets
  // that were searched (all of them when no bucket was full).
  core::ImageView<const float> Response() const { return response_.View(); }

 private:
  struct Bucket {
    int count = 0;     // candidates held
    int occupied = 0;  // tracks already in the cell
    Corner candidates[kMaxCandidatesPerBucket];
  };

  // Response for rows [y0, y1) and columns [x0, x1) (the caller keeps a margin of r + 1 to the
  // image edge); returns the largest response written.
  float ComputeResponse(const GrayView& image, int x0, int x1, int y0, int y1);
  // 3x3 non-maximum suppression over rows [y0, y1) and columns [x0, x1); local maxima above
  // `threshold` go into their bucket's candidate list.
  void CollectMaxima(int x0, int x1, int y0, int y1, float threshold);
  // Pixel bounds [begin, end) of bucket column bx / bucket row by.
  int BucketColBegin(int bx) const;
  int BucketRowBegin(int by) const;
  int BucketOf(float x, float y) const;

  HarrisOptions options_{};
  bool configured_ = false;
  static constexpr int kMaxWindow = 2 * 4 + 1;
  // Horizontal box sums of the last (2r+1) rows (a ring) and their vertical running sums.
  float ring_[3][kMaxWindow][kMaxImageWidth] = {};
  float vertical_[3][kMaxImageWidth] = {};
  float products_[3][kMaxImageWidth] = {};
  std::uint8_t maxima_[kMaxImageWidth] = {};
  std::int16_t bucket_col_[kMaxImageWidth] = {};  // bucket column of each pixel column
  std::int16_t bucket_row_[kMaxImageHeight] = {};
  bool needed_[kMaxBuckets] = {};
  Image<float> response_;
  Bucket buckets_[kMaxBuckets];
  int width_ = 0;
  int height_ = 0;
};

}  // namespace swf::frontend
