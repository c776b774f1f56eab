// Pairing of left and right frames by exposure time and detection of lost frames from device
// sequence numbers. Shared by every camera driver so they agree on what "a pair" and "a drop" mean.
#pragma once

#include <cstdint>

#include "swf/core/time.hpp"

namespace swf::drivers {

enum class PairDecision : std::uint8_t {
  kPair,          // the two frames were exposed together
  kDiscardLeft,   // the left frame is older than any right frame can match: drop it
  kDiscardRight,  // the right frame is older than any left frame can match: drop it
};

// Two frames pair when their exposure times differ by at most tolerance_ns. Otherwise the older
// one can never pair (frames arrive in exposure order on each side), so it is the one to drop.
PairDecision DecidePair(core::TimeNs left_ns, core::TimeNs right_ns, core::TimeNs tolerance_ns);

// Counts frames missing from a stream of device sequence numbers of a given bit width that wrap.
// GigE Vision block ids skip 0 when they wrap (0 is reserved), so that can be requested too.
class SequenceTracker {
 public:
  explicit SequenceTracker(int bits = 32, bool zero_is_invalid = false);

  // Frames lost between the previous observed sequence number and this one. A step backwards or a
  // jump beyond half the range means the device restarted its counter: counted as 0 and resynced.
  std::uint32_t Observe(std::uint64_t sequence);

  void Reset() { has_last_ = false; }

 private:
  std::uint64_t mask_;
  bool zero_is_invalid_;
  bool has_last_ = false;
  std::uint64_t last_ = 0;
};

}  // namespace swf::drivers
