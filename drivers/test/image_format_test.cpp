#include "swf/drivers/image_format.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace swf::drivers {
namespace {

TEST(ImageFormat, Gray8HonoursSourceStride) {
  // GIVEN a 3x2 image with 2 padding bytes per row
  const std::uint8_t src[] = {1, 2, 3, 99, 99, 4, 5, 6};
  SourceImageDesc d{PixelFormat::kGray8, 3, 2, 5};
  std::uint8_t dst[6] = {};
  ASSERT_EQ(ConvertToGray8(d, src, sizeof(src), dst, 3), core::Status::kOk);
  EXPECT_EQ(std::vector<std::uint8_t>(dst, dst + 6), (std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6}));
}

TEST(ImageFormat, Y16KeepsTheHighByte) {
  const std::uint8_t src[] = {0x34, 0x12, 0xFF, 0xAB};  // little endian 0x1234, 0xABFF
  SourceImageDesc d{PixelFormat::kGray16Le, 2, 1, 4, 16};
  std::uint8_t dst[2] = {};
  ASSERT_EQ(ConvertToGray8(d, src, sizeof(src), dst, 2), core::Status::kOk);
  EXPECT_EQ(dst[0], 0x12);
  EXPECT_EQ(dst[1], 0xAB);
}

TEST(ImageFormat, Mono12ShiftsByFourAndSaturatesOutOfRangeSamples) {
  const std::uint8_t src[] = {0xFF, 0x0F, 0x00, 0x08, 0xFF, 0xFF};  // 4095, 2048, 65535 (bad)
  SourceImageDesc d{PixelFormat::kGray16Le, 3, 1, 6, 12};
  std::uint8_t dst[3] = {};
  ASSERT_EQ(ConvertToGray8(d, src, sizeof(src), dst, 3), core::Status::kOk);
  EXPECT_EQ(dst[0], 255);
  EXPECT_EQ(dst[1], 128);
  EXPECT_EQ(dst[2], 255);
}

TEST(ImageFormat, YuyvTakesLuma) {
  const std::uint8_t src[] = {10, 128, 20, 129, 30, 130, 40, 131};
  SourceImageDesc d{PixelFormat::kYuyv, 4, 1, 8};
  std::uint8_t dst[4] = {};
  ASSERT_EQ(ConvertToGray8(d, src, sizeof(src), dst, 4), core::Status::kOk);
  EXPECT_EQ(std::vector<std::uint8_t>(dst, dst + 4), (std::vector<std::uint8_t>{10, 20, 30, 40}));
}

TEST(ImageFormat, ShortBufferIsCorruptDataNotACrash) {
  std::vector<std::uint8_t> src(100);
  SourceImageDesc d{PixelFormat::kGray8, 10, 11, 10};
  std::vector<std::uint8_t> dst(110);
  EXPECT_EQ(ConvertToGray8(d, src.data(), src.size(), dst.data(), 10), core::Status::kCorruptData);
  EXPECT_EQ(RequiredBytes(d), 110u);
}

TEST(ImageFormat, MalformedDescriptionsAreRejected) {
  std::uint8_t buf[64] = {};
  EXPECT_EQ(ConvertToGray8({PixelFormat::kGray8, 0, 1, 1}, buf, 64, buf, 1),
            core::Status::kInvalidArgument);
  EXPECT_EQ(ConvertToGray8({PixelFormat::kYuyv, 3, 1, 6}, buf, 64, buf, 3),
            core::Status::kInvalidArgument);  // odd YUYV width
  EXPECT_EQ(ConvertToGray8({PixelFormat::kGray16Le, 4, 1, 4}, buf, 64, buf, 4),
            core::Status::kInvalidArgument);  // stride shorter than a row
  EXPECT_EQ(ConvertToGray8({PixelFormat::kGray8, 4, 1, 4}, nullptr, 64, buf, 4),
            core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::drivers
