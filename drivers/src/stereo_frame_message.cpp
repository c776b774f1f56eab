#include "swf/drivers/stereo_frame_message.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdio>

namespace swf::drivers {

bool CheckStereoFrameFields(const swf_msgs::stereo_frame_t& msg, char* why, std::size_t size) {
  if (msg.width <= 0 || msg.height <= 0) {
    std::snprintf(why, size, "empty image (%" PRId32 "x%" PRId32 ")", msg.width, msg.height);
    return false;
  }
  if (msg.seq < 0) {
    std::snprintf(why, size, "negative seq %" PRId64, msg.seq);
    return false;
  }
  if (msg.dropped_before < 0) {
    std::snprintf(why, size, "negative dropped_before %" PRId32, msg.dropped_before);
    return false;
  }
  for (const std::int64_t t : {msg.utime, msg.left_exposure_utime, msg.right_exposure_utime}) {
    if (t < 0 || t > kMaxFrameUtime) {
      std::snprintf(why, size, "exposure time %" PRId64 " us out of range", t);
      return false;
    }
  }
  if (size > 0) why[0] = '\0';
  return true;
}

std::uint32_t PairsLostBefore(std::int64_t seq_gap, std::int32_t announced,
                              std::int64_t* unannounced) {
  const std::int64_t told = std::max<std::int32_t>(announced, 0);
  *unannounced = std::max<std::int64_t>(0, seq_gap - told);
  // Both terms are at most INT64_MAX / 2 in practice (sequence numbers are non-negative int64),
  // but a hostile gap must not overflow: saturate before adding.
  const std::int64_t limit = std::numeric_limits<std::int32_t>::max();
  const std::int64_t lost = told + std::min(*unannounced, limit);
  return static_cast<std::uint32_t>(std::min(lost, limit));
}

}  // namespace swf::drivers
