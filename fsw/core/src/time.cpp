#include "swf/core/time.hpp"

#include <ctime>

namespace swf::core {

TimeNs MonotonicNs() {
  timespec ts{};
  // CLOCK_MONOTONIC cannot fail with a valid pointer; a zero would show up as a timing outlier.
  (void)clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

}  // namespace swf::core
