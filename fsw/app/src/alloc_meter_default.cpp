// Weak defaults for binaries without the counting hook: nothing is measured.
#include "swf/app/alloc_meter.hpp"

namespace swf::app {

__attribute__((weak)) void BeginRealtimeAllocationCounting() {}
__attribute__((weak)) std::int64_t RealtimeAllocations() { return -1; }

}  // namespace swf::app
