#include "png_writer.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace swf::drivers {
namespace {

std::uint32_t Get32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return (std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) |
         (std::uint32_t{b[at + 2]} << 8) | b[at + 3];
}

TEST(PngWriter, Crc32MatchesTheStandardCheckValue) {
  const char* check = "123456789";
  EXPECT_EQ(Crc32(reinterpret_cast<const std::uint8_t*>(check), 9), 0xCBF43926u);
}

TEST(PngWriter, WritesHeaderStoredPixelsAndEnd) {
  // GIVEN a 3x2 view with a padded stride
  const std::uint8_t pixels[] = {1, 2, 3, 0, 4, 5, 6, 0};
  const core::ImageView<const std::uint8_t> view{pixels, 3, 2, 4};
  std::vector<std::uint8_t> png;
  EncodeGrayPng(view, &png);
  ASSERT_GT(png.size(), 8u + 25u + 12u);
  EXPECT_EQ(std::memcmp(png.data(), "\x89PNG\r\n\x1a\n", 8), 0);
  EXPECT_EQ(Get32(png, 8), 13u);
  EXPECT_EQ(std::memcmp(png.data() + 12, "IHDR", 4), 0);
  EXPECT_EQ(Get32(png, 16), 3u);
  EXPECT_EQ(Get32(png, 20), 2u);
  EXPECT_EQ(Get32(png, 8 + 8 + 13), Crc32(png.data() + 12, 17));
  // IDAT: zlib header, one final stored block holding filter byte + row, twice.
  const std::size_t idat = 8 + 25;
  EXPECT_EQ(std::memcmp(png.data() + idat + 4, "IDAT", 4), 0);
  const std::uint8_t expected_block[] = {0x78, 0x01, 1, 8, 0, 0xF7, 0xFF, 0, 1, 2, 3, 0, 4, 5, 6};
  EXPECT_EQ(std::memcmp(png.data() + idat + 8, expected_block, sizeof(expected_block)), 0);
  // The file ends with the fixed IEND chunk.
  const std::uint8_t iend[] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
  EXPECT_EQ(std::memcmp(png.data() + png.size() - 12, iend, 12), 0);
}

}  // namespace
}  // namespace swf::drivers
