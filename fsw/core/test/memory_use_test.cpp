#include "swf/core/memory_use.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <thread>

namespace swf::core {
namespace {

// Uses `bytes` of stack below its caller (a volatile array the compiler must keep whole).
__attribute__((noinline)) int UseStack(std::size_t bytes) {
  volatile char block[96 * 1024];
  const std::size_t n = bytes < sizeof block ? bytes : sizeof block;
  for (std::size_t i = 0; i < n; i += 64) block[sizeof block - 1 - i] = static_cast<char>(i);
  return block[sizeof block - 1];
}

// Paints, uses `bytes` of stack, measures: all on a fresh thread, as the flight threads do.
StackWatermark MeasureOnThread(std::size_t depth, std::size_t bytes) {
  StackWatermark w;
  std::thread t([&] {
    w.Paint(depth);
    (void)UseStack(bytes);
    w.Measure();
  });
  t.join();
  return w;
}

TEST(StackWatermark, FindsTheDeepestUseOfTheStack) {
  const StackWatermark shallow = MeasureOnThread(StackWatermark::kDefaultDepth, 0);
  const StackWatermark deep = MeasureOnThread(StackWatermark::kDefaultDepth, 64 * 1024);
  ASSERT_TRUE(shallow.Measured());
  ASSERT_TRUE(deep.Measured());
  EXPECT_FALSE(deep.Saturated());
  EXPECT_LT(shallow.HighWaterBytes(), 16u * 1024u);
  // The 64 KiB touched (every 64th byte), plus UseStack's frame above the touched part.
  EXPECT_GE(deep.HighWaterBytes(), 63u * 1024u);
  EXPECT_LE(deep.HighWaterBytes(), 128u * 1024u);
}

TEST(StackWatermark, SaysWhenTheStackWentBelowThePaint) {
  const StackWatermark w = MeasureOnThread(32 * 1024, 90 * 1024);
  ASSERT_TRUE(w.Measured());
  EXPECT_TRUE(w.Saturated());
  EXPECT_LE(w.HighWaterBytes(), w.PaintedBytes());
}

TEST(StackWatermark, UnpaintedIsNotMeasured) {
  StackWatermark w;
  w.Measure();
  EXPECT_FALSE(w.Measured());
  EXPECT_FALSE(w.Saturated());
}

TEST(ProcessMemory, CountsTheFaultsOfNewlyTouchedPages) {
  const ProcessMemory before = ReadProcessMemory();
  ASSERT_TRUE(before.valid);
  EXPECT_GT(before.resident_bytes, 0);
  EXPECT_GE(before.peak_resident_bytes, before.resident_bytes);
  constexpr std::size_t kBytes = 16u << 20;
  char* block = static_cast<char*>(std::malloc(kBytes));
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBytes);
  const ProcessMemory after = ReadProcessMemory();
  ASSERT_TRUE(after.valid);
  // One fault per 4 KiB page at most, fewer with larger pages; at least one per 2 MiB.
  EXPECT_GE(after.minor_faults - before.minor_faults, static_cast<std::int64_t>(kBytes >> 21));
  EXPECT_GE(after.peak_resident_bytes,
            before.resident_bytes + static_cast<std::int64_t>(kBytes / 2));
  EXPECT_EQ(block[kBytes - 1], 1);
  std::free(block);
}

}  // namespace
}  // namespace swf::core
