// A raw camera pair as the tests publish it over LCM: an unrectified stereo_frame_t of
// width x height with both images allocated, for the caller to number, stamp and fill.
#pragma once

#include <cstddef>
#include <cstdint>

#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::testing {

inline swf_msgs::stereo_frame_t RawStereoFrame(std::int32_t width, std::int32_t height) {
  swf_msgs::stereo_frame_t f{};
  f.rectified = false;
  f.width = width;
  f.height = height;
  f.num_bytes = width * height;
  f.left.resize(static_cast<std::size_t>(f.num_bytes));
  f.right.resize(f.left.size());
  return f;
}

}  // namespace swf::testing
