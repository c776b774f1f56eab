// Test images for the front end's unit tests: the synthetic texture (exactly known geometry),
// owned 8-bit images and helpers to render and score them.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "swf/core/median.hpp"
#include "swf/frontend/harris.hpp"
#include "swf/frontend/image.hpp"
#include "swf/frontend/synthetic_texture.hpp"

namespace swf::frontend::testing {

// The texture lives in a header the benchmark shares (bench_frontend renders its pair from it).
using synthetic::Texture;

// An owned 8-bit image for tests (heap allocation is fine here: it happens before counting).
struct TestImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
  TestImage(int w, int h) : width(w), height(h), pixels(static_cast<std::size_t>(w) * h, 0) {}
  GrayView View() const { return GrayView{pixels.data(), width, height, width}; }
  MutableGrayView MutableView() { return MutableGrayView{pixels.data(), width, height, width}; }
};

// Renders pixel (x, y) = f(x, y), rounded and clamped to 8 bits.
template <typename F>
TestImage Render(int w, int h, F f) {
  TestImage img(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double v = std::round(f(static_cast<double>(x), static_cast<double>(y)));
      img.pixels[static_cast<std::size_t>(y) * w + x] =
          static_cast<std::uint8_t>(v < 0.0 ? 0.0 : (v > 255.0 ? 255.0 : v));
    }
  }
  return img;
}

// 1e9 for no values: a test's "too far" rather than NaN, which every comparison would pass over.
inline double Median(std::vector<double> v) {
  return v.empty() ? 1e9 : core::MedianInPlace(v.data(), v.size());
}

// Harris corners of a test image with the default options.
inline CornerList DetectCorners(const TestImage& img) {
  auto detector = std::make_unique<HarrisDetector>();
  EXPECT_EQ(detector->Configure(HarrisOptions{}), core::Status::kOk);
  CornerList corners;
  EXPECT_EQ(detector->Detect(img.View(), nullptr, 0, &corners), core::Status::kOk);
  return corners;
}

}  // namespace swf::frontend::testing
