// stereo_frame_t (messages/stereo_frame_t.lcm) as a stereo source receives it: the checks of a
// decoded frame's fields that the decoder cannot judge, and the pairs lost before a frame from its
// sequence number. One definition for the recorded frames (LogStereoSource) and the live ones
// (LcmStereoSource), so a log and the bus refuse and count the same frames the same way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "swf/core/time.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::drivers {

// Exposure times in microseconds that still fit in nanoseconds (core::TimeNs, int64).
inline constexpr std::int64_t kMaxFrameUtime =
    std::numeric_limits<std::int64_t>::max() / core::kNsPerUs;

// True when a decoded frame's fields are usable: a non-empty image, a non-negative seq and
// dropped_before, every time stamp in [0, kMaxFrameUtime] us. Otherwise false with the reason in
// `why` (NUL-terminated, at most `size` bytes). Never allocates (a receiving thread calls it).
bool CheckStereoFrameFields(const swf_msgs::stereo_frame_t& msg, char* why, std::size_t size);

// The pairs lost before a frame that comes `seq_gap` (>= 0) sequence numbers after the previous
// one (seq - previous - 1) and says itself that `announced` (>= 0) were lost before it (its
// dropped_before). A source that numbers its frames across its losses (the simulator) has the
// announced pairs inside the gap, one that numbers only what it sends beside it: the loss is the
// announced pairs plus the part of the gap they do not explain, *unannounced (lost on the way: a
// cut log, the network). Clamped to the int32 of StereoPair::dropped_before.
std::uint32_t PairsLostBefore(std::int64_t seq_gap, std::int32_t announced,
                              std::int64_t* unannounced);

}  // namespace swf::drivers
