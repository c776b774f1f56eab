#include "swf/core/image_view.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace swf::core {
namespace {

TEST(ImageView, RowsAreStrideElementsApart) {
  std::uint16_t pixels[3 * 5] = {};
  const ImageView<std::uint16_t> view{pixels, 4, 3, 5};  // one padding element per row
  ASSERT_TRUE(view.Valid());
  view.At(2, 1) = 700;
  EXPECT_EQ(pixels[1 * 5 + 2], 700);
  EXPECT_EQ(view.Row(2), pixels + 10);
}

TEST(ImageView, MutableConvertsToReadOnlyOverTheSamePixels) {
  std::uint8_t pixels[2 * 3] = {1, 2, 3, 4, 5, 6};
  const ImageView<std::uint8_t> view{pixels, 3, 2, 3};
  const ImageView<const std::uint8_t> read_only = view;
  EXPECT_EQ(read_only.data, view.Const().data);
  EXPECT_EQ(read_only.At(1, 1), 5);
  EXPECT_EQ(read_only.stride, 3);
}

TEST(ImageView, InvalidWhenEmptyOrStrideShorterThanARow) {
  std::uint8_t pixels[4] = {};
  EXPECT_FALSE((ImageView<const std::uint8_t>{}).Valid());
  EXPECT_FALSE((ImageView<const std::uint8_t>{pixels, 4, 1, 3}).Valid());
  EXPECT_FALSE((ImageView<const std::uint8_t>{pixels, 0, 1, 4}).Valid());
  EXPECT_TRUE((ImageView<const std::uint8_t>{pixels, 4, 1, 4}).Valid());
}

}  // namespace
}  // namespace swf::core
