#include "swf/testing/allocation_counter.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <vector>

namespace swf::testing {
namespace {

// Published through a volatile so the compiler cannot elide a malloc/free pair it can see whole.
void* volatile g_sink = nullptr;

// The counter must see every kind of allocation, or a zero from it would prove nothing.
TEST(AllocationCounter, SeesNewMallocAndContainers) {
  AllocationScope scope;
  EXPECT_EQ(scope.Count(), 0u);
  auto owned = std::make_unique<int>(3);
  EXPECT_EQ(scope.Count(), 1u);
  g_sink = std::malloc(16);
  EXPECT_EQ(scope.Count(), 2u);
  std::free(g_sink);
  std::vector<double> v(10);
  g_sink = v.data();
  EXPECT_EQ(scope.Count(), 3u);
  g_sink = std::calloc(4, 4);
  g_sink = std::realloc(g_sink, 64);
  std::free(g_sink);
  EXPECT_EQ(scope.Count(), 5u);
  EXPECT_EQ(*owned, 3);
}

TEST(AllocationCounter, CountsNothingOutsideAScope) {
  StartCountingAllocations();
  EXPECT_EQ(StopCountingAllocations(), 0u);
  auto owned = std::make_unique<int>(4);
  EXPECT_EQ(AllocationsSinceStart(), 0u);
}

}  // namespace
}  // namespace swf::testing
