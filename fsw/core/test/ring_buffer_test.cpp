#include "swf/core/ring_buffer.hpp"

#include <gtest/gtest.h>

namespace swf::core {
namespace {

TEST(RingBuffer, EmptyPopReportsEmpty) {
  RingBuffer<int, 2> r;
  int out = -1;
  EXPECT_EQ(r.Pop(&out), Status::kEmpty);
  EXPECT_EQ(out, -1);
}

TEST(RingBuffer, FifoOrderAcrossTheWrap) {
  RingBuffer<int, 3> r;
  int out = 0;
  for (int round = 0; round < 5; ++round) {
    ASSERT_EQ(r.Push(3 * round), Status::kOk);
    ASSERT_EQ(r.Push(3 * round + 1), Status::kOk);
    ASSERT_EQ(r.Pop(&out), Status::kOk);
    EXPECT_EQ(out, 3 * round);
    ASSERT_EQ(r.Pop(&out), Status::kOk);
    EXPECT_EQ(out, 3 * round + 1);
  }
  EXPECT_TRUE(r.empty());
}

TEST(RingBuffer, FullPushIsRefusedOverwriteDropsOldest) {
  RingBuffer<int, 3> r;
  ASSERT_EQ(r.Push(1), Status::kOk);
  ASSERT_EQ(r.Push(2), Status::kOk);
  ASSERT_EQ(r.Push(3), Status::kOk);
  EXPECT_EQ(r.Push(4), Status::kFull);
  EXPECT_EQ(r.front(), 1);
  EXPECT_TRUE(r.PushOverwrite(4));
  EXPECT_EQ(r.front(), 2);
  EXPECT_EQ(r.back(), 4);
  EXPECT_EQ(r[1], 3);
  EXPECT_EQ(r.size(), 3u);
  r.Clear();
  EXPECT_FALSE(r.PushOverwrite(9));
  EXPECT_EQ(r.front(), 9);
}

}  // namespace
}  // namespace swf::core
