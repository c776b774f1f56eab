#include "png_writer.hpp"

#include <cstdio>
#include <string>

#include "swf/cli/cli.hpp"

namespace swf::drivers {
namespace {

void Put32(std::vector<std::uint8_t>* out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8)
    out->push_back(static_cast<std::uint8_t>(v >> shift));
}

void Chunk(std::vector<std::uint8_t>* out, const char type[4],
           const std::vector<std::uint8_t>& data) {
  Put32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t type_at = out->size();
  out->insert(out->end(), type, type + 4);
  out->insert(out->end(), data.begin(), data.end());
  Put32(out, Crc32(out->data() + type_at, data.size() + 4));
}

}  // namespace

std::uint32_t Crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc) {
  // Bitwise CRC-32 (ISO-HDLC, as PNG specifies); speed is irrelevant for a grab tool.
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void EncodeGrayPng(const core::ImageView<const std::uint8_t>& image,
                   std::vector<std::uint8_t>* out) {
  out->clear();
  const std::uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  out->insert(out->end(), signature, signature + 8);
  std::vector<std::uint8_t> header;
  Put32(&header, static_cast<std::uint32_t>(image.width));
  Put32(&header, static_cast<std::uint32_t>(image.height));
  header.insert(header.end(),
                {8, 0, 0, 0, 0});  // 8-bit, grayscale, deflate, filter 0, no interlace
  Chunk(out, "IHDR", header);

  // Raw scanlines, each prefixed by filter type 0.
  std::vector<std::uint8_t> raw;
  raw.reserve(static_cast<std::size_t>(image.width + 1) * image.height);
  for (std::int32_t r = 0; r < image.height; ++r) {
    raw.push_back(0);
    const std::uint8_t* row = image.data + static_cast<std::size_t>(r) * image.stride;
    raw.insert(raw.end(), row, row + image.width);
  }
  // zlib stream of stored blocks (at most 65535 bytes each) and the Adler-32 of the raw data.
  std::vector<std::uint8_t> z = {0x78, 0x01};
  std::size_t at = 0;
  do {
    const std::size_t n = raw.size() - at > 65535 ? 65535 : raw.size() - at;
    const bool last = at + n == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<std::uint8_t>(n & 0xFF));
    z.push_back(static_cast<std::uint8_t>(n >> 8));
    z.push_back(static_cast<std::uint8_t>(~n & 0xFF));
    z.push_back(static_cast<std::uint8_t>((~n >> 8) & 0xFF));
    z.insert(z.end(), raw.begin() + static_cast<std::ptrdiff_t>(at),
             raw.begin() + static_cast<std::ptrdiff_t>(at + n));
    at += n;
  } while (at < raw.size());
  std::uint32_t a = 1, b = 0;
  for (std::uint8_t v : raw) {
    a = (a + v) % 65521u;
    b = (b + a) % 65521u;
  }
  Put32(&z, (b << 16) | a);
  Chunk(out, "IDAT", z);
  Chunk(out, "IEND", {});
}

bool WriteGrayPng(const char* path, const core::ImageView<const std::uint8_t>& image) {
  std::vector<std::uint8_t> bytes;
  EncodeGrayPng(image, &bytes);
  // Whole or not at all (a grab stopped by a signal leaves no truncated PNG).
  std::string error;
  return cli::WriteFileAtomically(
      path, std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()), &error);
}

}  // namespace swf::drivers
