// The unit tests' counting policy for fsw/core's allocation interposer: every thread counts
// while a scope is open.
#include "swf/testing/allocation_counter.hpp"

#include <atomic>

#include "swf/core/allocation_interposer.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<std::uint64_t> g_count{0};
}  // namespace

namespace swf::core {
void NoteAllocation() {
  if (g_counting.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace swf::core

namespace swf::testing {
std::uint64_t AllocationsSinceStart() { return g_count.load(); }
void StartCountingAllocations() {
  g_count.store(0);
  g_counting.store(true);
}
std::uint64_t StopCountingAllocations() {
  g_counting.store(false);
  return g_count.load();
}
}  // namespace swf::testing
