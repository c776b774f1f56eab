// Images of the front end: 8-bit grey views (core::ImageView), fixed-capacity owned images,
// bilinear sampling and a 2x pyramid. 8-bit grey pixels; coordinates are pixel centres (x right, y
// down, (0,0) is the centre of the top-left pixel).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "swf/core/image_view.hpp"
#include "swf/core/status.hpp"
#include "swf/frontend/config.hpp"

namespace swf::frontend {

// 8-bit grey views, the front end's images.
using GrayView = core::ImageView<const std::uint8_t>;
using MutableGrayView = core::ImageView<std::uint8_t>;

// An image with storage inside the object (kCapacity pixels) and a runtime size.
template <typename T, std::size_t kCapacity = kMaxPixels>
class Image {
 public:
  // kInvalidArgument when the size is not positive or exceeds the capacity.
  core::Status Resize(int width, int height) {
    if (width <= 0 || height <= 0 ||
        static_cast<std::size_t>(width) * static_cast<std::size_t>(height) > kCapacity) {
      return core::Status::kInvalidArgument;
    }
    width_ = width;
    height_ = height;
    return core::Status::kOk;
  }
  int Width() const { return width_; }
  int Height() const { return height_; }
  core::ImageView<T> View() { return {pixels_.data(), width_, height_, width_}; }
  core::ImageView<const T> View() const { return {pixels_.data(), width_, height_, width_}; }
  // Copies a view of the same size (call Resize first).
  void CopyFrom(const core::ImageView<const T>& src) {
    for (int y = 0; y < height_; ++y) {
      std::memcpy(pixels_.data() + static_cast<std::size_t>(y) * width_, src.Row(y),
                  sizeof(T) * static_cast<std::size_t>(width_));
    }
  }

 private:
  std::array<T, kCapacity> pixels_{};
  int width_ = 0;
  int height_ = 0;
};

// True when bilinear sampling at (x, y) with a margin of `margin` pixels stays inside the image.
inline bool InsideForSampling(const GrayView& image, float x, float y, float margin) {
  return x >= margin && y >= margin && x < static_cast<float>(image.width - 1) - margin &&
         y < static_cast<float>(image.height - 1) - margin;
}

// Bilinear interpolation at (x, y) in the cell whose top-left pixel is (x0, y0), with
// x0 <= x <= x0 + 1 and y0 <= y <= y0 + 1: the arithmetic of SampleBilinear and
// SampleBilinearClamped (SampleGrid performs the same operations per grid pixel).
inline float SampleInCell(const GrayView& image, int x0, int y0, float x, float y) {
  const float ax = x - static_cast<float>(x0);
  const float ay = y - static_cast<float>(y0);
  const std::uint8_t* r0 = image.Row(y0) + x0;
  const std::uint8_t* r1 = r0 + image.stride;
  const float top = static_cast<float>(r0[0]) + ax * static_cast<float>(r0[1] - r0[0]);
  const float bottom = static_cast<float>(r1[0]) + ax * static_cast<float>(r1[1] - r1[0]);
  return top + ay * (bottom - top);
}

// Bilinear interpolation; the caller guarantees 0 <= x < width-1 and 0 <= y < height-1.
inline float SampleBilinear(const GrayView& image, float x, float y) {
  return SampleInCell(image, static_cast<int>(x), static_cast<int>(y), x, y);
}

// Samples the (2r+1)^2 grid of pixels centred at (x, y) into out (row-major). All samples share
// one set of bilinear weights, so this is several times cheaper than SampleBilinear per pixel and
// gives bit-identical values. The caller guarantees InsideForSampling(image, x, y, r).
inline void SampleGrid(const GrayView& image, float x, float y, int r, float* out) {
  const int x0 = static_cast<int>(x);
  const int y0 = static_cast<int>(y);
  const float ax = x - static_cast<float>(x0);
  const float ay = y - static_cast<float>(y0);
  const int side = 2 * r + 1;
  for (int j = 0; j < side; ++j) {
    const std::uint8_t* r0 = image.Row(y0 - r + j) + (x0 - r);
    const std::uint8_t* r1 = r0 + image.stride;
    float* o = out + j * side;
    for (int i = 0; i < side; ++i) {
      const float top = static_cast<float>(r0[i]) + ax * static_cast<float>(r0[i + 1] - r0[i]);
      const float bottom = static_cast<float>(r1[i]) + ax * static_cast<float>(r1[i + 1] - r1[i]);
      o[i] = top + ay * (bottom - top);
    }
  }
}

// Bilinear interpolation with the border replicated: any (x, y) is valid. Used on coarse pyramid
// levels, where a patch near the border would otherwise be lost before the fine levels see it.
inline float SampleBilinearClamped(const GrayView& image, float x, float y) {
  const float max_x = static_cast<float>(image.width - 1);
  const float max_y = static_cast<float>(image.height - 1);
  x = x < 0.0f ? 0.0f : (x > max_x ? max_x : x);
  y = y < 0.0f ? 0.0f : (y > max_y ? max_y : y);
  int x0 = static_cast<int>(x);
  int y0 = static_cast<int>(y);
  x0 = x0 > image.width - 2 ? image.width - 2 : x0;
  y0 = y0 > image.height - 2 ? image.height - 2 : y0;
  return SampleInCell(image, x0, y0, x, y);
}

// Halves an image with a [1 2 1]/4 x [1 2 1]/4 low-pass (rounded). dst is resized to
// (width+1)/2 x (height+1)/2.
template <std::size_t kCapacity>
core::Status Downsample2x(const GrayView& src, Image<std::uint8_t, kCapacity>* dst) {
  const int w = (src.width + 1) / 2;
  const int h = (src.height + 1) / 2;
  if (core::Status s = dst->Resize(w, h); s != core::Status::kOk) return s;
  MutableGrayView out = dst->View();
  for (int y = 0; y < h; ++y) {
    const int sy = 2 * y;
    const std::uint8_t* rm = src.Row(sy > 0 ? sy - 1 : 0);
    const std::uint8_t* rc = src.Row(sy);
    const std::uint8_t* rp = src.Row(sy + 1 < src.height ? sy + 1 : src.height - 1);
    std::uint8_t* o = out.Row(y);
    for (int x = 0; x < w; ++x) {
      const int sx = 2 * x;
      const int xm = sx > 0 ? sx - 1 : 0;
      const int xp = sx + 1 < src.width ? sx + 1 : src.width - 1;
      const int col_m = rm[xm] + 2 * rc[xm] + rp[xm];
      const int col_c = rm[sx] + 2 * rc[sx] + rp[sx];
      const int col_p = rm[xp] + 2 * rc[xp] + rp[xp];
      o[x] = static_cast<std::uint8_t>((col_m + 2 * col_c + col_p + 8) >> 4);
    }
  }
  return core::Status::kOk;
}

// A Gaussian-like image pyramid; level 0 is a copy of the input.
class Pyramid {
 public:
  // levels in [1, kMaxPyramidLevels].
  core::Status Build(const GrayView& image, int levels) {
    if (levels < 1 || levels > kMaxPyramidLevels || !image.Valid()) {
      return core::Status::kInvalidArgument;
    }
    if (core::Status s = levels_[0].Resize(image.width, image.height); s != core::Status::kOk) {
      return s;
    }
    levels_[0].CopyFrom(image);
    num_levels_ = 1;
    for (int l = 1; l < levels; ++l) {
      if (levels_[l - 1].Width() < 16 || levels_[l - 1].Height() < 16) break;
      if (core::Status s = Downsample2x(levels_[l - 1].View().Const(), &levels_[l]);
          s != core::Status::kOk) {
        return s;
      }
      ++num_levels_;
    }
    return core::Status::kOk;
  }
  int NumLevels() const { return num_levels_; }
  GrayView Level(int l) const { return levels_[l].View(); }

 private:
  std::array<Image<std::uint8_t>, kMaxPyramidLevels> levels_{};
  int num_levels_ = 0;
};

}  // namespace swf::frontend
