#include "swf/core/static_vector.hpp"

#include <gtest/gtest.h>

#include "swf/core/assert.hpp"

namespace swf::core {
namespace {

struct Counted {
  static int alive;
  int value;
  explicit Counted(int v) : value(v) { ++alive; }
  Counted(const Counted& o) : value(o.value) { ++alive; }
  Counted& operator=(const Counted&) = default;
  ~Counted() { --alive; }
};
int Counted::alive = 0;

TEST(StaticVector, FillsToCapacityThenReportsFull) {
  StaticVector<int, 3> v;
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(v.push_back(1), Status::kOk);
  EXPECT_EQ(v.push_back(2), Status::kOk);
  EXPECT_EQ(v.push_back(3), Status::kOk);
  EXPECT_TRUE(v.full());
  EXPECT_EQ(v.push_back(4), Status::kFull);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[2], 3);
  EXPECT_EQ(v.back(), 3);
}

TEST(StaticVector, EraseKeepsOrderSwapEraseIsConstantTime) {
  StaticVector<int, 5> v;
  for (int i = 0; i < 5; ++i) ASSERT_EQ(v.push_back(i), Status::kOk);
  v.erase(1);  // 0 2 3 4
  ASSERT_EQ(v.size(), 4u);
  EXPECT_EQ(v[1], 2);
  EXPECT_EQ(v[3], 4);
  v.swap_erase(0);  // 4 2 3
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0], 4);
  EXPECT_EQ(v[1], 2);
  v.swap_erase(2);  // 4 2
  EXPECT_EQ(v.size(), 2u);
  EXPECT_EQ(v.back(), 2);
}

TEST(StaticVector, DestroysWhatItHolds) {
  Counted::alive = 0;
  {
    StaticVector<Counted, 4> v;
    ASSERT_EQ(v.emplace_back(1), Status::kOk);
    ASSERT_EQ(v.emplace_back(2), Status::kOk);
    StaticVector<Counted, 4> copy = v;
    EXPECT_EQ(Counted::alive, 4);
    copy.pop_back();
    EXPECT_EQ(Counted::alive, 3);
    v.clear();
    EXPECT_EQ(Counted::alive, 1);
    EXPECT_EQ(copy[0].value, 1);
  }
  EXPECT_EQ(Counted::alive, 0);
}

int g_asserts = 0;
void CountingHandler(const char*, const char*, int) { ++g_asserts; }

TEST(StaticVector, MisuseOnEmptyIsAnAssertionNotACrash) {
  const AssertHandler previous = SetAssertHandler(&CountingHandler);
  g_asserts = 0;
  StaticVector<int, 2> v;
  v.pop_back();
  v.erase(0);
  EXPECT_EQ(g_asserts, 2);
  EXPECT_TRUE(v.empty());
  (void)SetAssertHandler(previous);
}

}  // namespace
}  // namespace swf::core
