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
  float quality_level = 0.00001f;  // threshold relative to the strongest response of the image
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

  // The response image of the last call (for tests and plots).
  ImageView<const float> Response() const { return response_.View(); }

 private:
  struct Bucket {
    int count = 0;     // candidates held
    int occupied = 0;  // tracks already in the cell
    Corner candidates[kMaxCandidatesPerBucket];
  };

  void ComputeResponse(const GrayView& image);
  int BucketOf(float x, float y) const;

  HarrisOptions options_{};
  bool configured_ = false;
  static constexpr int kMaxWindow = 2 * 4 + 1;
  // Horizontal box sums of the last (2r+1) rows (a ring) and their vertical running sums.
  float ring_[3][kMaxWindow][kMaxImageWidth] = {};
  float vertical_[3][kMaxImageWidth] = {};
  float products_[3][kMaxImageWidth] = {};
  Image<float> response_;
  Bucket buckets_[kMaxBuckets];
  int width_ = 0;
  int height_ = 0;
};

}  // namespace swf::frontend
