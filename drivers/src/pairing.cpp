#include "swf/drivers/pairing.hpp"

namespace swf::drivers {

PairDecision DecidePair(core::TimeNs left_ns, core::TimeNs right_ns, core::TimeNs tolerance_ns) {
  const core::TimeNs dt = left_ns - right_ns;
  if (dt <= tolerance_ns && -dt <= tolerance_ns) return PairDecision::kPair;
  return dt < 0 ? PairDecision::kDiscardLeft : PairDecision::kDiscardRight;
}

SequenceTracker::SequenceTracker(int bits, bool zero_is_invalid)
    : mask_(bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1),
      zero_is_invalid_(zero_is_invalid) {}

std::uint32_t SequenceTracker::Observe(std::uint64_t sequence) {
  sequence &= mask_;
  if (!has_last_) {
    has_last_ = true;
    last_ = sequence;
    return 0;
  }
  std::uint64_t step = (sequence - last_) & mask_;
  // Wrapping past the top skips the reserved 0, which is one step that is not a lost frame.
  if (zero_is_invalid_ && sequence < last_ && step > 0) --step;
  last_ = sequence;
  if (step == 0 || step > mask_ / 2) return 0;  // repeat or restart: resync, count nothing
  const std::uint64_t lost = step - 1;
  return lost > 0xFFFFFFFFull ? 0xFFFFFFFFu : static_cast<std::uint32_t>(lost);
}

void PairNumbering::Number(StereoPair* pair) {
  pair->seq = next_seq_++;
  pair->dropped_before =
      lost_since_pair_[0] > lost_since_pair_[1] ? lost_since_pair_[0] : lost_since_pair_[1];
  lost_since_pair_[0] = lost_since_pair_[1] = 0;
}

}  // namespace swf::drivers
