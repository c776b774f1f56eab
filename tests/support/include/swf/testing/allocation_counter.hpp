// Counts heap allocations so tests can prove "no allocation after start" (STYLE.md, memory).
// Linking swf::test_support replaces the global operator new family and malloc/calloc/realloc
// of the test executable (fsw/core's allocation interposer, with this counter as its policy);
// every call is counted while a counting scope is open on any thread.
#pragma once

#include <cstdint>

namespace swf::testing {

// Number of allocations seen since the last Start().
std::uint64_t AllocationsSinceStart();

// Opens a counting scope: resets the count and starts counting.
void StartCountingAllocations();
// Closes it and returns the count.
std::uint64_t StopCountingAllocations();

// RAII form: `AllocationScope scope; ...; EXPECT_EQ(scope.Count(), 0u);`
class AllocationScope {
 public:
  AllocationScope() { StartCountingAllocations(); }
  ~AllocationScope() { (void)StopCountingAllocations(); }
  AllocationScope(const AllocationScope&) = delete;
  AllocationScope& operator=(const AllocationScope&) = delete;
  std::uint64_t Count() const { return AllocationsSinceStart(); }
};

}  // namespace swf::testing
