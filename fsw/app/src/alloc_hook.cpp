// The flight binaries' counting policy for fsw/core's allocation interposer: only threads
// marked real-time are counted, so the output thread's LCM and file I/O do not hide a
// real-time allocation or raise a false one.
#include <atomic>
#include <cstdint>

#include "swf/app/alloc_meter.hpp"
#include "swf/core/allocation_interposer.hpp"

namespace {
thread_local bool t_realtime = false;
std::atomic<std::int64_t> g_realtime_allocations{0};
}  // namespace

namespace swf::core {
void NoteAllocation() {
  if (t_realtime) g_realtime_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace swf::core

namespace swf::app {
void BeginRealtimeAllocationCounting() { t_realtime = true; }
std::int64_t RealtimeAllocations() { return g_realtime_allocations.load(); }
}  // namespace swf::app
