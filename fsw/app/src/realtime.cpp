#include "swf/app/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace swf::app {

bool LockMemory(char* message, std::size_t n) {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    std::snprintf(message, n, "mlockall: memory locked");
    return true;
  }
  std::snprintf(message, n, "mlockall refused (%s): continuing with pageable memory",
                std::strerror(errno));
  return false;
}

bool MakeThreadRealtime(int priority, char* message, std::size_t n) {
  if (priority <= 0) {
    std::snprintf(message, n, "SCHED_FIFO not requested: normal scheduling");
    return false;
  }
  sched_param param{};
  param.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (rc == 0) {
    std::snprintf(message, n, "SCHED_FIFO priority %d", priority);
    return true;
  }
  std::snprintf(message, n,
                "SCHED_FIFO priority %d refused (%s): continuing with normal scheduling", priority,
                std::strerror(rc));
  return false;
}

void SleepUntil(core::TimeNs t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / core::kNsPerS);
  ts.tv_nsec = static_cast<long>(t_ns % core::kNsPerS);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

void Spin(core::TimeNs duration_ns) {
  const core::TimeNs end = core::MonotonicNs() + duration_ns;
  while (core::MonotonicNs() < end) {
  }
}

}  // namespace swf::app
