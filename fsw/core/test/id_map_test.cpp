#include "swf/core/id_map.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>

namespace swf::core {
namespace {

TEST(IdMap, FindsWhatWasInsertedAndForgetsWhatWasErased) {
  IdMap<4> map;
  map.Clear();
  EXPECT_EQ(map.Find(7), -1);
  map.Insert(7, 0);
  map.Insert(-3, 1);
  map.Insert(1LL << 40, 2);
  EXPECT_EQ(map.size(), 3);
  EXPECT_EQ(map.Find(7), 0);
  EXPECT_EQ(map.Find(-3), 1);
  EXPECT_EQ(map.Find(1LL << 40), 2);
  map.Insert(7, 3);  // replaces
  EXPECT_EQ(map.Find(7), 3);
  EXPECT_EQ(map.size(), 3);
  map.Erase(-3);
  map.Erase(99);  // absent: nothing happens
  EXPECT_EQ(map.Find(-3), -1);
  EXPECT_EQ(map.size(), 2);
  map.Clear();
  EXPECT_EQ(map.Find(7), -1);
  EXPECT_EQ(map.size(), 0);
}

// Random churn at full capacity against std::map: backward-shift deletion must keep every
// remaining key reachable through wrapped clusters, long after the table was first filled.
TEST(IdMap, StaysExactUnderLongChurnAtFullCapacity) {
  constexpr int kCapacity = 64;
  IdMap<kCapacity> map;
  map.Clear();
  std::map<std::int64_t, int> reference;
  std::mt19937_64 rng(42);
  std::int64_t next_id = 0;
  for (int step = 0; step < 200000; ++step) {
    const bool insert = reference.size() < kCapacity && (reference.empty() || rng() % 2 == 0);
    if (insert) {
      const std::int64_t id = next_id++;  // tracker ids grow
      const int value = static_cast<int>(rng() % 1000);
      map.Insert(id, value);
      reference[id] = value;
    } else {
      auto it = reference.begin();
      std::advance(it, static_cast<long>(rng() % reference.size()));
      map.Erase(it->first);
      reference.erase(it);
    }
    if (step % 997 == 0) {
      ASSERT_EQ(map.size(), static_cast<int>(reference.size()));
      for (const auto& [id, value] : reference) ASSERT_EQ(map.Find(id), value) << "id " << id;
      ASSERT_EQ(map.Find(next_id), -1);
    }
  }
}

}  // namespace
}  // namespace swf::core
