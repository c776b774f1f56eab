// Minimal 8-bit grayscale PNG writer for swf-grab: stored (uncompressed) deflate blocks, so it
// needs neither libpng nor zlib. Files are ~1.0x the raw image size; fine for bench captures.
#pragma once

#include <cstdint>
#include <vector>

#include "swf/drivers/stereo_source.hpp"

namespace swf::drivers {

// Encodes the view as a PNG file image (appended to *out after clearing it).
void EncodeGrayPng(const core::ImageView<const std::uint8_t>& image,
                   std::vector<std::uint8_t>* out);

// Writes the view to path; false if the file cannot be written.
bool WriteGrayPng(const char* path, const core::ImageView<const std::uint8_t>& image);

std::uint32_t Crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace swf::drivers
