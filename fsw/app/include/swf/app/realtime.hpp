// Real-time knobs of the flight process: memory locking, SCHED_FIFO and sleeping to absolute
// deadlines. Each attempt reports what happened in plain words; refusal is not fatal (the
// process continues with normal scheduling and says so).
#pragma once

#include <cstddef>

#include "swf/core/time.hpp"

namespace swf::app {

// mlockall(MCL_CURRENT | MCL_FUTURE). Writes a one-line result into message (size n).
bool LockMemory(char* message, std::size_t n);
// SCHED_FIFO at `priority` for the calling thread (priority 0: leave it alone).
bool MakeThreadRealtime(int priority, char* message, std::size_t n);
// Sleeps until the CLOCK_MONOTONIC time t_ns (TIMER_ABSTIME; retries on EINTR).
void SleepUntil(core::TimeNs t_ns);
// Busy-waits for duration_ns (fault injection: a stage that computes too long).
void Spin(core::TimeNs duration_ns);

}  // namespace swf::app
