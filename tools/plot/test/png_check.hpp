// What a drawn plot must be (tools/plot's tests): a PNG that decodes, of the canvas size drawn,
// and not blank: its grey levels vary (a plot of axes, text and data has a standard deviation of
// tens of grey levels; a blank or single-colour canvas has none).
#pragma once

#include <cmath>
#include <string>

#include "swf/image_io/image_io.hpp"

namespace swf::plot::test {

struct PngStats {
  bool decoded = false;
  std::string error;
  int width = 0;
  int height = 0;
  double gray_stddev = 0.0;
};

inline PngStats StatsOf(const std::string& path) {
  PngStats stats;
  image_io::GrayImage image;
  stats.decoded = image_io::LoadGray(path, &image, &stats.error);
  if (!stats.decoded) return stats;
  stats.width = image.width;
  stats.height = image.height;
  double sum = 0.0, sum2 = 0.0;
  for (std::uint8_t v : image.pixels) {
    sum += v;
    sum2 += static_cast<double>(v) * v;
  }
  const double n = static_cast<double>(image.pixels.size());
  stats.gray_stddev = n > 0 ? std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n))) : 0.0;
  return stats;
}

}  // namespace swf::plot::test
