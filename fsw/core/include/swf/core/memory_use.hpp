// How much memory a flight process uses, measured by the process itself without allocating:
// each thread's stack high-water (by painting) and the process's resident memory and page faults
// (from the kernel). These are the figures a flight computer's memory budget is sized from: a
// thread's stack with margin over its high-water, and no page faults once the frame group runs
// (mlockall prefaults; a fault after start is a latency the frame group did not plan for).
#pragma once

#include <cstddef>
#include <cstdint>

namespace swf::core {

// The deepest a thread's stack was used between Paint() and Measure(), both called on that
// thread (Measure at the end of its body, while the stack is still its own). Paint() fills
// `depth` bytes below its own frame with a pattern; Measure() finds the lowest word no longer
// holding it. The figure counts from Paint's frame down, so frames above it (the thread's entry)
// are not in it; a stack that used (nearly) all of the painted region reports Saturated().
class StackWatermark {
 public:
  static constexpr std::size_t kDefaultDepth = 256 * 1024;

  void Paint(std::size_t depth = kDefaultDepth);
  void Measure();
  std::size_t HighWaterBytes() const { return high_water_; }
  std::size_t PaintedBytes() const { return depth_; }
  bool Measured() const { return measured_; }
  // The use reached the last KiB of the painted region: the true high-water may be deeper.
  bool Saturated() const { return measured_ && high_water_ + 1024 >= depth_; }

 private:
  std::uintptr_t origin_ = 0;  // Paint's frame: the high-water is measured from here
  std::uintptr_t bottom_ = 0;  // lowest painted address
  std::size_t depth_ = 0;      // origin_ - bottom_
  std::size_t high_water_ = 0;
  bool measured_ = false;
};

// The process's resident set and page-fault counts at one moment (Linux: /proc/self/statm,
// /proc/self/status and getrusage). Read without allocating, so a real-time thread may take it.
struct ProcessMemory {
  bool valid = false;
  std::int64_t resident_bytes = 0;
  std::int64_t peak_resident_bytes = 0;  // VmHWM: the most resident at any time so far
  std::int64_t minor_faults = 0;
  std::int64_t major_faults = 0;
};
ProcessMemory ReadProcessMemory();

}  // namespace swf::core
