// Pairing of left and right frames by exposure time and detection of lost frames from device
// sequence numbers. Shared by every camera driver so they agree on what "a pair" and "a drop" mean.
#pragma once

#include <cstdint>

#include "swf/core/time.hpp"
#include "swf/drivers/stereo_source.hpp"

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

// The numbering of the pairs a camera driver serves and the frames lost between them (device
// sequence gaps, frames rejected or left without a partner), kept alike by every driver: what a
// side lost since the previous pair becomes the next pair's dropped_before.
class PairNumbering {
 public:
  // `frames` more of `side` (0 left, 1 right) that will be in no pair.
  void Lose(int side, std::uint32_t frames = 1) { lost_since_pair_[side] += frames; }
  // The side's stream restarts (Start()): nothing lost on it yet.
  void Restart(int side) { lost_since_pair_[side] = 0; }
  // Numbers a pair that is served: seq +1 per pair from 0, dropped_before the larger of the two
  // sides' losses since the previous pair; the losses start again from 0.
  void Number(StereoPair* pair);

 private:
  std::uint32_t lost_since_pair_[2] = {0, 0};
  std::uint64_t next_seq_ = 0;
};

// The first of `count` slots that is not in use (a pair slot of a driver: `in_use` set while the
// caller holds its pair), or -1 when the caller holds them all.
template <typename Slot>
std::int32_t FreeSlot(const Slot* slots, std::int32_t count) {
  for (std::int32_t i = 0; i < count; ++i) {
    if (!slots[i].in_use) return i;
  }
  return -1;
}

// Serves the pair filled from slot `index` (found by FreeSlot): numbered, the slot held until the
// caller releases the pair's handle, and one more pair served.
template <typename Slot>
void ServePair(std::int32_t index, Slot* slot, PairNumbering* numbering, SourceStats* stats,
               StereoPair* pair) {
  numbering->Number(pair);
  pair->handle = index;
  slot->in_use = true;
  ++stats->pairs_served;
}

}  // namespace swf::drivers
