#include "swf/drivers/image_format.hpp"

#include <cstring>

namespace swf::drivers {

std::int32_t BytesPerPixel(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGray8: return 1;
    case PixelFormat::kGray16Le: return 2;
    case PixelFormat::kYuyv: return 2;
  }
  return 1;
}

std::size_t RequiredBytes(const SourceImageDesc& desc) {
  if (desc.width <= 0 || desc.height <= 0) return 0;
  const std::size_t row = static_cast<std::size_t>(desc.width) * BytesPerPixel(desc.format);
  return static_cast<std::size_t>(desc.stride_bytes) * (desc.height - 1) + row;
}

core::Status ConvertToGray8(const SourceImageDesc& desc, const std::uint8_t* src,
                            std::size_t src_bytes, std::uint8_t* dst,
                            std::int32_t dst_stride_bytes) {
  if (src == nullptr || dst == nullptr || desc.width <= 0 || desc.height <= 0 ||
      dst_stride_bytes < desc.width ||
      desc.stride_bytes < desc.width * BytesPerPixel(desc.format) ||
      (desc.format == PixelFormat::kYuyv && desc.width % 2 != 0) ||
      (desc.format == PixelFormat::kGray16Le &&
       (desc.significant_bits < 8 || desc.significant_bits > 16))) {
    return core::Status::kInvalidArgument;
  }
  if (src_bytes < RequiredBytes(desc)) return core::Status::kCorruptData;
  for (std::int32_t r = 0; r < desc.height; ++r) {
    const std::uint8_t* in = src + static_cast<std::size_t>(r) * desc.stride_bytes;
    std::uint8_t* out = dst + static_cast<std::size_t>(r) * dst_stride_bytes;
    switch (desc.format) {
      case PixelFormat::kGray8: std::memcpy(out, in, static_cast<std::size_t>(desc.width)); break;
      case PixelFormat::kGray16Le: {
        const int shift = desc.significant_bits - 8;
        if (shift == 8) {
          // Full 16-bit samples (V4L2 Y16, Mono16): the high byte, a plain strided copy.
          for (std::int32_t c = 0; c < desc.width; ++c) out[c] = in[2 * c + 1];
          break;
        }
        for (std::int32_t c = 0; c < desc.width; ++c) {
          // Assembled byte by byte: device buffers need not be 2-byte aligned.
          const unsigned v =
              static_cast<unsigned>(in[2 * c]) | (static_cast<unsigned>(in[2 * c + 1]) << 8);
          // Out-of-range samples (bits above significant_bits) saturate instead of wrapping.
          const unsigned g = v >> shift;
          out[c] = static_cast<std::uint8_t>(g > 255u ? 255u : g);
        }
        break;
      }
      case PixelFormat::kYuyv:
        // Y0 U Y1 V: luma is every other byte.
        for (std::int32_t c = 0; c < desc.width; ++c) out[c] = in[2 * c];
        break;
    }
  }
  return core::Status::kOk;
}

}  // namespace swf::drivers
