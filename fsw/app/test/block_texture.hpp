// The textured plane the camera-source tests show their cameras (v4l2_test's scripted kernel,
// lcm_stereo_publisher): random gray blocks of 6 px, corners everywhere and unambiguous along the
// epipolar lines.
#pragma once

#include <cstdint>

namespace swf::testing {

inline std::uint8_t BlockTexture(int x, int y) {
  std::uint32_t h = static_cast<std::uint32_t>((x + 4096) / 6) * 73856093U ^
                    static_cast<std::uint32_t>((y + 4096) / 6) * 19349663U;
  h ^= h >> 13;
  h *= 0x5bd1e995U;
  h ^= h >> 15;
  return static_cast<std::uint8_t>(40 + (h % 176));
}

}  // namespace swf::testing
