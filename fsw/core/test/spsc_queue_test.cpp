#include "swf/core/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

namespace swf::core {
namespace {

TEST(SpscQueue, EmptyAndFullEdges) {
  SpscQueue<int, 2> q;
  int out = 0;
  EXPECT_EQ(q.TryPop(&out), Status::kEmpty);
  EXPECT_EQ(q.TryPush(1), Status::kOk);
  EXPECT_EQ(q.TryPush(2), Status::kOk);
  EXPECT_EQ(q.TryPush(3), Status::kFull);
  EXPECT_EQ(q.SizeApprox(), 2u);
  ASSERT_EQ(q.TryPop(&out), Status::kOk);
  EXPECT_EQ(out, 1);
  EXPECT_EQ(q.TryPush(3), Status::kOk);
  ASSERT_EQ(q.TryPop(&out), Status::kOk);
  EXPECT_EQ(out, 2);
  ASSERT_EQ(q.TryPop(&out), Status::kOk);
  EXPECT_EQ(out, 3);
  EXPECT_EQ(q.TryPop(&out), Status::kEmpty);
}

// GIVEN a producer thread pushing a counting sequence and retrying on kFull
// THEN the consumer sees every value exactly once, in order.
TEST(SpscQueue, TwoThreadsLoseAndReorderNothing) {
  constexpr std::uint64_t kCount = 200000;
  static SpscQueue<std::uint64_t, 64> q;
  std::thread producer([] {
    for (std::uint64_t i = 0; i < kCount; ++i) {
      while (q.TryPush(i) == Status::kFull) std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t value = 0;
  while (expected < kCount) {
    if (q.TryPop(&value) == Status::kOk) {
      ASSERT_EQ(value, expected);
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_EQ(q.TryPop(&value), Status::kEmpty);
}

}  // namespace
}  // namespace swf::core
