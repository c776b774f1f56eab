// The flight binary's real-time allocation meter (alloc_hook.cpp), linked here exactly as into
// swf-fsw: it must count what a marked thread allocates (else the 0 that health_t and
// summary.json report after start would prove nothing) and ignore unmarked threads (the output
// thread's LCM and file I/O).
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <thread>
#include <vector>

#include "swf/app/alloc_meter.hpp"

namespace swf::app {
namespace {

// Published through a volatile so the compiler cannot elide an allocation it sees whole.
void* volatile g_sink = nullptr;

TEST(AllocMeter, CountsMarkedThreadsOnly) {
  const std::int64_t start = RealtimeAllocations();
  ASSERT_GE(start, 0) << "the counting hook is not linked in";
  // An unmarked thread allocates: not counted.
  std::thread other([] {
    auto v = std::make_unique<std::vector<double>>(100);
    g_sink = v->data();
    g_sink = std::malloc(32);
    std::free(g_sink);
  });
  other.join();
  EXPECT_EQ(RealtimeAllocations(), start);
  // A marked thread: operator new, malloc, calloc and realloc all count.
  std::int64_t during = 0;
  std::thread realtime([&during] {
    BeginRealtimeAllocationCounting();
    const std::int64_t before = RealtimeAllocations();
    auto owned = std::make_unique<int>(7);
    g_sink = owned.get();
    g_sink = std::malloc(16);
    std::free(g_sink);
    g_sink = std::calloc(4, 4);
    g_sink = std::realloc(g_sink, 64);
    std::free(g_sink);
    during = RealtimeAllocations() - before;
  });
  realtime.join();
  EXPECT_EQ(during, 4);
}

}  // namespace
}  // namespace swf::app
