// Monotonic time for scheduling and stage timing. Never used inside numerical computations
// (results must not depend on the clock). Timestamps are int64 nanoseconds.
#pragma once

#include <cstdint>

namespace swf::core {

using TimeNs = std::int64_t;

constexpr TimeNs kNsPerUs = 1000;
constexpr TimeNs kNsPerMs = 1000 * 1000;
constexpr TimeNs kNsPerS = 1000 * 1000 * 1000;

// CLOCK_MONOTONIC in nanoseconds: never jumps, unrelated to wall time.
TimeNs MonotonicNs();

constexpr double NsToMs(TimeNs t_ns) { return static_cast<double>(t_ns) / 1e6; }
constexpr std::int64_t NsToUs(TimeNs t_ns) { return t_ns / kNsPerUs; }

// Measures one interval: construct (or Restart) then ElapsedNs.
class Stopwatch {
 public:
  Stopwatch() : start_ns_(MonotonicNs()) {}
  void Restart() { start_ns_ = MonotonicNs(); }
  TimeNs ElapsedNs() const { return MonotonicNs() - start_ns_; }

 private:
  TimeNs start_ns_;
};

}  // namespace swf::core
