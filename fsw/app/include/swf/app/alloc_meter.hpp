// Heap allocations on the real-time threads after start, as the flight binary itself reports
// them (health_t.allocations_after_start). The counting hook (alloc_hook.cpp, the real-time
// policy of fsw/core's allocation interposer, both linked as objects into the executables only)
// counts the calls of malloc and operator new made by threads that called
// BeginRealtimeAllocationCounting(). Without the hook the count is -1
// ("not measured"); tests use tests/support's counter instead.
#pragma once

#include <cstdint>

namespace swf::app {

// Marks the calling thread as real-time from now on.
void BeginRealtimeAllocationCounting();
// Allocations made by marked threads since they were marked; -1 when not measured.
std::int64_t RealtimeAllocations();

}  // namespace swf::app
