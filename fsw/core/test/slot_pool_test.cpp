#include "swf/core/slot_pool.hpp"

#include <gtest/gtest.h>

#include <set>
#include <thread>

namespace swf::core {
namespace {

TEST(SlotPool, HandsOutEverySlotOnceUntilReleased) {
  SlotPool<int, 4> pool;
  ASSERT_EQ(pool.Allocate(), Status::kOk);
  std::set<std::int32_t> taken;
  for (int k = 0; k < 4; ++k) {
    const std::int32_t i = pool.Acquire();
    ASSERT_GE(i, 0);
    EXPECT_TRUE(taken.insert(i).second) << "slot " << i << " handed out twice";
    pool[i] = 10 * i;
  }
  EXPECT_EQ(pool.Acquire(), -1);  // all with the consumer
  const std::int32_t back = *taken.begin();
  EXPECT_EQ(pool[back], 10 * back);
  pool.Release(back);
  EXPECT_EQ(pool.Acquire(), back);
}

// One producer and one consumer passing indices through a queue, as the flight process does:
// every value written is read intact and every slot comes back.
TEST(SlotPool, CarriesRecordsBetweenTwoThreads) {
  SlotPool<long, 8> pool;
  ASSERT_EQ(pool.Allocate(), Status::kOk);
  SpscQueue<std::int32_t, 16> filled;
  constexpr long kRecords = 100000;
  long sum = 0;
  std::thread consumer([&] {
    for (long n = 0; n < kRecords;) {
      std::int32_t i = -1;
      if (filled.TryPop(&i) != Status::kOk) continue;
      sum += pool[i];
      pool.Release(i);
      ++n;
    }
  });
  for (long v = 1; v <= kRecords;) {
    const std::int32_t i = pool.Acquire();
    if (i < 0) continue;
    pool[i] = v;
    while (filled.TryPush(i) != Status::kOk) {
    }
    ++v;
  }
  consumer.join();
  EXPECT_EQ(sum, kRecords * (kRecords + 1) / 2);
  for (int k = 0; k < 8; ++k) EXPECT_GE(pool.Acquire(), 0);
}

}  // namespace
}  // namespace swf::core
