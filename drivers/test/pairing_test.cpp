#include "swf/drivers/pairing.hpp"

#include <gtest/gtest.h>

namespace swf::drivers {
namespace {

TEST(DecidePair, WithinToleranceOnEitherSidePairs) {
  EXPECT_EQ(DecidePair(1000, 1500, 500), PairDecision::kPair);
  EXPECT_EQ(DecidePair(1500, 1000, 500), PairDecision::kPair);
}

TEST(DecidePair, TheOlderFrameIsDiscarded) {
  EXPECT_EQ(DecidePair(1000, 1501, 500), PairDecision::kDiscardLeft);
  EXPECT_EQ(DecidePair(1501, 1000, 500), PairDecision::kDiscardRight);
}

TEST(SequenceTracker, CountsGapsAndNotTheFirstFrame) {
  SequenceTracker t(32);
  EXPECT_EQ(t.Observe(7), 0u);
  EXPECT_EQ(t.Observe(8), 0u);
  EXPECT_EQ(t.Observe(11), 2u);
}

TEST(SequenceTracker, WrapsAt32Bits) {
  SequenceTracker t(32);
  (void)t.Observe(0xFFFFFFFEu);
  EXPECT_EQ(t.Observe(0xFFFFFFFFu), 0u);
  EXPECT_EQ(t.Observe(1), 1u);  // 0 was lost
}

TEST(SequenceTracker, GigEBlockIdsSkipZeroWhenWrapping) {
  SequenceTracker t(16, /*zero_is_invalid=*/true);
  (void)t.Observe(65534);
  EXPECT_EQ(t.Observe(65535), 0u);
  EXPECT_EQ(t.Observe(1), 0u);  // 65535 -> 1 is consecutive for GigE Vision
  EXPECT_EQ(t.Observe(4), 2u);
}

TEST(SequenceTracker, RestartIsResyncNotAHugeDrop) {
  SequenceTracker t(32);
  (void)t.Observe(1000);
  EXPECT_EQ(t.Observe(3), 0u);
  EXPECT_EQ(t.Observe(5), 1u);
}

}  // namespace
}  // namespace swf::drivers
