#include "swf/core/time.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace swf::core {
namespace {

TEST(Time, MonotonicNeverGoesBackAndMeasuresASleep) {
  TimeNs previous = MonotonicNs();
  for (int i = 0; i < 1000; ++i) {
    const TimeNs now = MonotonicNs();
    ASSERT_GE(now, previous);
    previous = now;
  }
  Stopwatch watch;
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_GE(watch.ElapsedNs(), 5 * kNsPerMs);
  EXPECT_DOUBLE_EQ(NsToMs(2500000), 2.5);
  EXPECT_EQ(NsToUs(2500000), 2500);
}

}  // namespace
}  // namespace swf::core
