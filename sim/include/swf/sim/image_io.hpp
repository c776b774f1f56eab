// Image files for the simulator and its tools: reading the orbital imagery (PGM, JPG, PNG through
// stb_image) and writing PNG (stb_image_write). Not for flight code.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/core/status.hpp"

namespace swf::sim {

struct GrayImage {
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::vector<std::uint8_t> pixels;  // row-major, width * height
  std::uint8_t At(std::int32_t x, std::int32_t y) const { return pixels[y * width + x]; }
};

// Reads any format stb_image reads, converted to 8-bit gray. kIoError when the file cannot be
// read, kCorruptData when it cannot be decoded.
core::Status ReadGrayImage(const std::string& path, GrayImage* image);

// Writes 8-bit gray (channels 1) or RGB (channels 3) pixels, rows stride_bytes apart.
core::Status WritePng(const std::string& path, const std::uint8_t* pixels, std::int32_t width,
                      std::int32_t height, std::int32_t channels, std::int32_t stride_bytes);

}  // namespace swf::sim
