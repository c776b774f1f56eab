#include "swf/image_io/image_io.hpp"

#include "files.hpp"

#include <stb_image.h>
#include <stb_image_write.h>
#include <zlib.h>

#include <cctype>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

namespace swf::image_io {

using internal::ReadBytes;

namespace {

// ---- image headers -----------------------------------------------------------------------------

std::uint32_t BigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

bool CheckDimensions(std::int64_t w, std::int64_t h, const std::string& name, std::string* error) {
  if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide || w * h > kMaxImagePixels) {
    *error = name + ": header says " + std::to_string(w) + " x " + std::to_string(h) +
             " px, outside the limits (1.." + std::to_string(kMaxImageSide) + " px a side, " +
             std::to_string(kMaxImagePixels) + " px in all)";
    return false;
  }
  return true;
}

constexpr std::uint8_t kPngSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};

bool IsPng(const std::uint8_t* d, std::size_t n) {
  return n >= 8 && std::memcmp(d, kPngSignature, 8) == 0;
}
bool IsJpeg(const std::uint8_t* d, std::size_t n) {
  return n >= 3 && d[0] == 0xFF && d[1] == 0xD8 && d[2] == 0xFF;
}
bool IsBinaryPnm(const std::uint8_t* d, std::size_t n) {
  return n >= 2 && d[0] == 'P' && (d[1] == '5' || d[1] == '6');
}

// Walks every chunk of a PNG: lengths inside the file, each chunk's CRC-32 (over type and data),
// IHDR first with dimensions inside the limits, IEND present. stb checks none of the CRCs, so a
// corrupt file would otherwise decode into wrong pixels.
bool CheckPng(const std::uint8_t* d, std::size_t n, const std::string& name, std::string* error) {
  std::size_t at = 8;
  bool first = true;
  while (true) {
    if (n - at < 12) {
      *error = name + ": PNG cut short at byte " + std::to_string(at) +
               (first ? " (no complete IHDR header)" : " (no IEND chunk)");
      return false;
    }
    const std::uint32_t length = BigEndian32(d + at);
    const std::uint8_t* type = d + at + 4;
    const std::string type_name(reinterpret_cast<const char*>(type), 4);
    for (char c : type_name) {
      if (!std::isalpha(static_cast<unsigned char>(c))) {
        *error = name + ": PNG chunk at byte " + std::to_string(at) + " has no valid type";
        return false;
      }
    }
    if (length > n - at - 12) {
      *error = name + ": PNG chunk " + type_name + " at byte " + std::to_string(at) + " claims " +
               std::to_string(length) + " bytes, past the end of the file (cut short?)";
      return false;
    }
    const uLong crc = crc32(crc32(0L, Z_NULL, 0), type, static_cast<uInt>(length + 4));
    if (crc != BigEndian32(type + 4 + length)) {
      *error = name + ": PNG chunk " + type_name + " at byte " + std::to_string(at) +
               " fails its CRC check (the file is corrupt)";
      return false;
    }
    if (first) {
      if (type_name != "IHDR" || length != 13) {
        *error = name + ": PNG does not start with a 13-byte IHDR chunk";
        return false;
      }
      if (!CheckDimensions(BigEndian32(type + 4), BigEndian32(type + 8), name, error)) return false;
      first = false;
    }
    at += 12 + static_cast<std::size_t>(length);
    if (type_name == "IEND") return true;
  }
}

// The image's size from its header (stb reads only the header), against the limits; PNGs get
// their chunks checked first and JPEGs must end with their end-of-image marker.
bool CheckHeader(const std::uint8_t* d, std::size_t n, const std::string& name, int* w, int* h,
                 std::string* error) {
  if (n > static_cast<std::size_t>(INT_MAX)) {
    *error = name + ": larger than " + std::to_string(INT_MAX) + " bytes";
    return false;
  }
  if (IsPng(d, n)) {
    if (!CheckPng(d, n, name, error)) return false;
  } else if (IsJpeg(d, n)) {
    // A JPEG cut short still decodes (the rest becomes grey); its end marker tells.
    if (n < 4 || d[n - 2] != 0xFF || d[n - 1] != 0xD9) {
      *error = name + ": JPEG cut short (does not end with the end-of-image marker FF D9)";
      return false;
    }
  } else if (IsBinaryPnm(d, n)) {
    // stb converts a 16-bit PPM's channels with its 8-bit routine and reads past its buffer
    // (found by image_decode_fuzz): 16-bit PGM/PPM is refused.
    if (stbi_is_16_bit_from_memory(d, static_cast<int>(n)) != 0) {
      *error = name + ": 16-bit PGM/PPM (maximum value above 255) is not supported";
      return false;
    }
  } else {
    *error = name + ": not a PNG, JPEG or binary PGM/PPM file (" + std::to_string(n) + " bytes)";
    return false;
  }
  int channels = 0;
  if (stbi_info_from_memory(d, static_cast<int>(n), w, h, &channels) == 0) {
    const char* why = stbi_failure_reason();
    *error = name + ": unreadable image header" +
             (why != nullptr && why[0] != '\0' ? std::string(" (") + why + ")" : std::string());
    return false;
  }
  return CheckDimensions(*w, *h, name, error);
}

bool Decode(const std::uint8_t* d, std::size_t n, const std::string& name, bool channel0,
            GrayImage* image, std::string* error) {
  int header_w = 0;
  int header_h = 0;
  if (!CheckHeader(d, n, name, &header_w, &header_h, error)) return false;
  int w = 0;
  int h = 0;
  int channels = 0;
  stbi_uc* data =
      stbi_load_from_memory(d, static_cast<int>(n), &w, &h, &channels, channel0 ? 0 : 1);
  if (data == nullptr) {
    const char* why = stbi_failure_reason();
    *error = name + ": cannot decode the image data" +
             (why != nullptr && why[0] != '\0' ? std::string(" (") + why + ")" : std::string());
    return false;
  }
  if (w != header_w || h != header_h || channels < 1) {
    stbi_image_free(data);
    *error = name + ": decoded size differs from its header";
    return false;
  }
  image->Resize(w, h);
  const int stride = channel0 ? channels : 1;
  for (std::size_t i = 0; i < image->pixels.size(); ++i) image->pixels[i] = data[i * stride];
  stbi_image_free(data);
  return true;
}

bool Load(const std::string& path, GrayImage* image, std::string* error, bool channel0) {
  std::vector<std::uint8_t> bytes;
  if (!ReadBytes(path, kMaxImageFileBytes, &bytes, error)) return false;
  return Decode(bytes.data(), bytes.size(), path, channel0, image, error);
}

}  // namespace

bool LoadGray(const std::string& path, GrayImage* image, std::string* error) {
  return Load(path, image, error, false);
}

bool LoadChannel0(const std::string& path, GrayImage* image, std::string* error) {
  return Load(path, image, error, true);
}

bool DecodeGray(const std::uint8_t* data, std::size_t size, const std::string& name,
                GrayImage* image, std::string* error) {
  return Decode(data, size, name, false, image, error);
}

bool DecodeChannel0(const std::uint8_t* data, std::size_t size, const std::string& name,
                    GrayImage* image, std::string* error) {
  return Decode(data, size, name, true, image, error);
}

bool ReadImageSize(const std::string& path, int* width, int* height, std::string* error) {
  std::vector<std::uint8_t> bytes;
  if (!ReadBytes(path, kMaxImageFileBytes, &bytes, error)) return false;
  return CheckHeader(bytes.data(), bytes.size(), path, width, height, error);
}

bool SavePng(const std::string& path, const RgbImage& image, std::string* error) {
  if (stbi_write_png(path.c_str(), image.width, image.height, 3, image.pixels.data(),
                     image.width * 3) == 0) {
    *error = path + ": cannot write PNG";
    return false;
  }
  return true;
}

bool FlowField::Known(int x, int y) const {
  const float u = U(x, y);
  const float v = V(x, y);
  return std::isfinite(u) && std::isfinite(v) && std::fabs(u) < 1e9f && std::fabs(v) < 1e9f;
}

bool DecodeFlo(const std::uint8_t* data, std::size_t size, const std::string& name, FlowField* flow,
               std::string* error) {
  constexpr std::size_t kHeaderBytes = 12;  // magic, width, height
  float magic = 0.0f;
  std::int32_t w = 0;
  std::int32_t h = 0;
  if (size >= kHeaderBytes) {
    std::memcpy(&magic, data, 4);
    std::memcpy(&w, data + 4, 4);
    std::memcpy(&h, data + 8, 4);
  }
  if (size < kHeaderBytes || magic != 202021.25f) {
    *error = name + ": not a Middlebury .flo file";
    return false;
  }
  if (!CheckDimensions(w, h, name, error)) return false;
  const std::size_t values = 2 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  if (size - kHeaderBytes != values * sizeof(float)) {
    *error = name + ": " + std::to_string(size) + " bytes, a " + std::to_string(w) + " x " +
             std::to_string(h) + " .flo file has " +
             std::to_string(kHeaderBytes + values * sizeof(float)) + " (truncated or padded)";
    return false;
  }
  flow->width = w;
  flow->height = h;
  flow->uv.resize(values);
  std::memcpy(flow->uv.data(), data + kHeaderBytes, values * sizeof(float));
  return true;
}

bool LoadFlo(const std::string& path, FlowField* flow, std::string* error) {
  std::vector<std::uint8_t> bytes;
  if (!ReadBytes(path, kMaxImageFileBytes, &bytes, error)) return false;
  return DecodeFlo(bytes.data(), bytes.size(), path, flow, error);
}

}  // namespace swf::image_io
