// Pixel formats the drivers accept from cameras and their conversion to the 8-bit gray images the
// flight loop consumes. Pure functions on caller-owned memory: no allocation, no OS.
#pragma once

#include <cstddef>
#include <cstdint>

#include "swf/core/status.hpp"

namespace swf::drivers {

enum class PixelFormat : std::uint8_t {
  kGray8,     // V4L2 GREY, GenICam Mono8: used in place, no copy
  kGray16Le,  // V4L2 Y16 (16 significant bits), GenICam Mono10/12/16 unpacked (LSB aligned)
  kYuyv,      // V4L2 YUYV 4:2:2: the Y samples are the gray image
};

// Layout of one image as the device delivers it.
struct SourceImageDesc {
  PixelFormat format = PixelFormat::kGray8;
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::int32_t stride_bytes = 0;       // bytes from one row to the next in the device buffer
  std::int32_t significant_bits = 16;  // kGray16Le only: 16 for Y16, 12 for Mono12, ...
};

// Bytes one pixel takes in the device buffer (YUYV: 2 per pixel on average).
std::int32_t BytesPerPixel(PixelFormat format);

// Smallest device buffer that holds the described image.
std::size_t RequiredBytes(const SourceImageDesc& desc);

// Converts a device image to 8-bit gray (dst row r at dst + r * dst_stride_bytes). Keeps the most
// significant 8 bits of deeper pixels. kCorruptData when the device delivered fewer bytes than
// the layout needs (a short or truncated frame), kInvalidArgument for a malformed description.
core::Status ConvertToGray8(const SourceImageDesc& desc, const std::uint8_t* src,
                            std::size_t src_bytes, std::uint8_t* dst,
                            std::int32_t dst_stride_bytes);

}  // namespace swf::drivers
