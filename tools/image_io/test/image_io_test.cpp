// image_io's refusals: every bad file is refused before anything large is allocated, with a
// reason that names the file (a huge header, a corrupt or cut-short PNG, an unsupported format,
// a hostile .flo header, a calibration with out-of-range values), and good files still decode.
#include "swf/image_io/image_io.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace swf::image_io {
namespace {

std::string TempPath(const std::string& name) {
  return ::testing::TempDir() + "image_io_test_" + std::to_string(getpid()) + "_" + name;
}

std::vector<std::uint8_t> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteAll(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

// A 4 x 3 grey-looking RGB PNG written by SavePng (pixel value 10 * row + column).
std::vector<std::uint8_t> SmallPng() {
  RgbImage rgb;
  rgb.width = 4;
  rgb.height = 3;
  for (int v = 0; v < 3; ++v)
    for (int u = 0; u < 4; ++u)
      for (int c = 0; c < 3; ++c) rgb.pixels.push_back(static_cast<std::uint8_t>(10 * v + u));
  const std::string path = TempPath("small.png");
  std::string error;
  EXPECT_TRUE(SavePng(path, rgb, &error)) << error;
  return ReadAll(path);
}

void PutBigEndian32(std::uint32_t v, std::uint8_t* p) {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}

long MaxRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

TEST(ImageIo, DecodesPngPixels) {
  const std::string path = TempPath("good.png");
  WriteAll(path, SmallPng());
  GrayImage image;
  std::string error;
  ASSERT_TRUE(LoadGray(path, &image, &error)) << error;
  ASSERT_EQ(image.width, 4);
  ASSERT_EQ(image.height, 3);
  EXPECT_EQ(image.pixels[2 * 4 + 3], 23);
  int w = 0;
  int h = 0;
  ASSERT_TRUE(ReadImageSize(path, &w, &h, &error)) << error;
  EXPECT_EQ(w, 4);
  EXPECT_EQ(h, 3);
}

// GIVEN a valid PNG whose IHDR says 30000 x 30000 (with a correct CRC) WHEN it is loaded THEN it
// is refused from the header, naming the file and the limit, and the process never grows by
// the gigabytes the decoder would have reserved (1.76 GB before the header check).
TEST(ImageIo, RefusesHugeDimensionsBeforeDecoding) {
  std::vector<std::uint8_t> png = SmallPng();
  std::uint8_t* ihdr = png.data() + 8;  // length, "IHDR", 13 bytes of data, CRC
  PutBigEndian32(30000, ihdr + 8);
  PutBigEndian32(30000, ihdr + 12);
  PutBigEndian32(static_cast<std::uint32_t>(crc32(0L, ihdr + 4, 17)), ihdr + 21);
  const std::string path = TempPath("huge.png");
  WriteAll(path, png);
  const long rss_before_kb = MaxRssKb();
  GrayImage image;
  std::string error;
  EXPECT_FALSE(LoadGray(path, &image, &error));
  EXPECT_EQ(error, path +
                       ": header says 30000 x 30000 px, outside the limits (1..16384 px a "
                       "side, 67108864 px in all)");
  EXPECT_LT(MaxRssKb() - rss_before_kb, 64 * 1024);
}

// GIVEN a PNG with one byte of its image data flipped WHEN it is loaded THEN the chunk's CRC
// check refuses it, naming the file and the chunk (stb decodes such a file into wrong pixels).
TEST(ImageIo, RefusesAPngFailingItsCrc) {
  std::vector<std::uint8_t> png = SmallPng();
  const std::size_t idat = 8 + 25;  // after the signature and IHDR
  ASSERT_EQ(std::memcmp(png.data() + idat + 4, "IDAT", 4), 0);
  png[idat + 10] ^= 0x01;
  const std::string path = TempPath("crc.png");
  WriteAll(path, png);
  GrayImage image;
  std::string error;
  EXPECT_FALSE(LoadGray(path, &image, &error));
  EXPECT_EQ(error, path + ": PNG chunk IDAT at byte 33 fails its CRC check (the file is corrupt)");
}

// GIVEN a PNG cut inside its header, or after its data WHEN it is loaded THEN the reason says so
// (a truncated header used to give an empty reason).
TEST(ImageIo, RefusesACutShortPngWithAReason) {
  const std::vector<std::uint8_t> png = SmallPng();
  const std::string header_path = TempPath("cut_header.png");
  WriteAll(header_path, {png.begin(), png.begin() + 16});
  GrayImage image;
  std::string error;
  EXPECT_FALSE(LoadGray(header_path, &image, &error));
  EXPECT_EQ(error, header_path + ": PNG cut short at byte 8 (no complete IHDR header)");
  WriteAll(header_path, {png.begin(), png.begin() + 24});
  EXPECT_FALSE(LoadGray(header_path, &image, &error));
  EXPECT_EQ(error, header_path +
                       ": PNG chunk IHDR at byte 8 claims 13 bytes, past the end of the file (cut "
                       "short?)");
  const std::string tail_path = TempPath("cut_tail.png");
  WriteAll(tail_path, {png.begin(), png.end() - 12});  // without IEND
  EXPECT_FALSE(LoadGray(tail_path, &image, &error));
  EXPECT_NE(error.find(tail_path + ": PNG cut short at byte"), std::string::npos) << error;
  EXPECT_NE(error.find("no IEND chunk"), std::string::npos) << error;
}

TEST(ImageIo, RefusesOtherFormatsDirectoriesAndMissingFiles) {
  const std::string bmp = TempPath("x.bmp");
  WriteAll(bmp, std::vector<std::uint8_t>(64, 'B'));
  GrayImage image;
  std::string error;
  EXPECT_FALSE(LoadGray(bmp, &image, &error));
  EXPECT_EQ(error, bmp + ": not a PNG, JPEG or binary PGM/PPM file (64 bytes)");
  EXPECT_FALSE(LoadGray(::testing::TempDir(), &image, &error));
  EXPECT_EQ(error, ::testing::TempDir() + ": not a regular file");
  EXPECT_FALSE(LoadGray(TempPath("missing.png"), &image, &error));
  EXPECT_EQ(error, TempPath("missing.png") + ": cannot open (no such file)");
}

// GIVEN a .flo header claiming 100000 x 100000 and no data WHEN it is loaded THEN it is refused
// by the limits before the 80 GB buffer is reserved; a header that disagrees with the file's
// size is refused too.
TEST(ImageIo, RefusesHostileFloHeaders) {
  auto flo = [](std::int32_t w, std::int32_t h, std::size_t values) {
    std::vector<std::uint8_t> bytes(12 + 4 * values, 0);
    const float magic = 202021.25f;
    std::memcpy(bytes.data(), &magic, 4);
    std::memcpy(bytes.data() + 4, &w, 4);
    std::memcpy(bytes.data() + 8, &h, 4);
    return bytes;
  };
  FlowField flow;
  std::string error;
  const std::vector<std::uint8_t> huge = flo(100000, 100000, 0);
  EXPECT_FALSE(DecodeFlo(huge.data(), huge.size(), "huge.flo", &flow, &error));
  EXPECT_NE(error.find("huge.flo: header says 100000 x 100000 px, outside the limits"),
            std::string::npos)
      << error;
  const std::vector<std::uint8_t> short_data = flo(2, 2, 7);
  EXPECT_FALSE(DecodeFlo(short_data.data(), short_data.size(), "short.flo", &flow, &error));
  EXPECT_EQ(error, "short.flo: 40 bytes, a 2 x 2 .flo file has 44 (truncated or padded)");
  const std::vector<std::uint8_t> good = flo(2, 2, 8);
  EXPECT_TRUE(DecodeFlo(good.data(), good.size(), "good.flo", &flow, &error)) << error;
  EXPECT_EQ(flow.uv.size(), 8u);
}

constexpr const char* kEurocYaml =
    "T_BS:\n  data: [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]\n"
    "resolution: [752, 480]\nintrinsics: [458.654, 457.296, 367.215, 248.375]\n"
    "distortion_coefficients: [-0.28, 0.07, 0.0002, 0.00002]\n";

std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  text.replace(text.find(from), from.size(), to);
  return text;
}

// GIVEN calibrations with values no camera has WHEN parsed THEN each is refused naming the file
// and the field (a resolution of 1e300 used to be cast to int: undefined behaviour).
TEST(ImageIo, CalibrationRefusesOutOfRangeValues) {
  frontend::CameraCalibration c;
  std::string error;
  ASSERT_TRUE(ParseCalibration(kEurocYaml, "cam0.yaml", &c, &error)) << error;
  EXPECT_EQ(c.width, 752);
  EXPECT_DOUBLE_EQ(c.k1, -0.28);
  struct Case {
    std::string from, to, expect;
  };
  const Case cases[] = {
      {"[752, 480]", "[1e300, 480]", "cam0.yaml: resolution 1e+300 x 480 is not whole pixels"},
      {"[752, 480]", "[752.5, 480]", "cam0.yaml: resolution 752.5 x 480 is not whole pixels"},
      {"0, 1, 0, 0,", "0, 2, 0, 0,", "cam0.yaml: T_BS's 3x3 block is not a rotation"},
      {"0, 0, 0, 1]", "0, 0, 1, 1]", "cam0.yaml: T_BS's last row is not 0 0 0 1"},
      {"[458.654,", "[-458.654,", "cam0.yaml: focal lengths must be positive"},
  };
  for (const Case& k : cases) {
    EXPECT_FALSE(ParseCalibration(Replaced(kEurocYaml, k.from, k.to), "cam0.yaml", &c, &error))
        << k.to;
    EXPECT_EQ(error.rfind(k.expect, 0), 0u) << error;
  }
}

}  // namespace
}  // namespace swf::image_io
