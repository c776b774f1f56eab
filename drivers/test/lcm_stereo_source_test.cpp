// LcmStereoSource over real LCM UDP multicast. Before main() the process enters its own network
// namespace with only loopback and a multicast route on it (docs: RECIPES.md, LCM), so nothing
// sent here can leave the machine; a publisher in this process sends stereo_frame_t (and junk) on
// the channel the source subscribes to.
#include "swf/drivers/lcm_stereo_source.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm.h>

#include <chrono>
#include <cstdlib>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "swf/core/time.hpp"
#include "swf/testing/allocation_counter.hpp"
#include "swf/testing/encode.hpp"
#include "swf/testing/private_network.hpp"
#include "swf/testing/stereo_frame.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::drivers {
namespace {

using swf::testing::Encode;

// Before main(), while the process has a single thread.
const bool kIsolated = swf::testing::EnterPrivateNetwork("ip route add 239.0.0.0/8 dev lo");
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr const char* kChannel = "TEST_STEREO";
constexpr core::TimeNs kWait = 2 * core::kNsPerS;  // for a frame that was sent: generous

std::uint8_t LeftPixel(std::int64_t seq, std::size_t i) {
  return static_cast<std::uint8_t>((seq * 7 + static_cast<std::int64_t>(i)) & 0xff);
}
std::uint8_t RightPixel(std::int64_t seq, std::size_t i) {
  return static_cast<std::uint8_t>((seq * 13 + 3 * static_cast<std::int64_t>(i)) & 0xff);
}

// A raw pair numbered `seq`, exposed at 1 s + seq x 100 ms (right 20 us later).
swf_msgs::stereo_frame_t Frame(std::int64_t seq, std::int32_t width = 64,
                               std::int32_t height = 48) {
  swf_msgs::stereo_frame_t f = swf::testing::RawStereoFrame(width, height);
  f.seq = seq;
  f.left_exposure_utime = 1000000 + seq * 100000;
  f.right_exposure_utime = f.left_exposure_utime + 20;
  f.utime = f.left_exposure_utime;
  for (std::size_t i = 0; i < f.left.size(); ++i) {
    f.left[i] = LeftPixel(seq, i);
    f.right[i] = RightPixel(seq, i);
  }
  return f;
}

class LcmSource : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(kIsolated) << "cannot create a private network namespace (needs root or userns)";
    publisher_ = lcm_create(kUrl);
    ASSERT_NE(publisher_, nullptr);
  }
  void TearDown() override {
    source_.Stop();
    if (publisher_ != nullptr) lcm_destroy(publisher_);
  }

  LcmStereoOptions Options(std::int32_t buffers = 4) const {
    LcmStereoOptions o;
    o.url = kUrl;
    o.channel = kChannel;
    o.max_width = 64;
    o.max_height = 48;
    o.buffers = buffers;
    return o;
  }
  void StartSource(const LcmStereoOptions& o) {
    ASSERT_EQ(source_.Configure(o), core::Status::kOk) << source_.LastError();
    ASSERT_EQ(source_.Start(), core::Status::kOk) << source_.LastError();
  }
  void PublishBytes(const std::vector<std::uint8_t>& bytes) {
    ASSERT_EQ(lcm_publish(publisher_, kChannel, bytes.data(), static_cast<unsigned>(bytes.size())),
              0);
  }
  void Publish(const swf_msgs::stereo_frame_t& f) { PublishBytes(Encode(f)); }
  // Waits until the receiving thread has taken n messages in all (at most 5 s), then lets it
  // finish the last one.
  bool WaitReceived(std::uint64_t n) {
    for (int i = 0; i < 500 && source_.Detail().received < n; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return source_.Detail().received >= n;
  }
  // The next pair, which must be seq `seq` with its pixels and stamps intact; released.
  void ExpectPair(std::int64_t seq, std::uint32_t dropped_before = 0) {
    StereoPair p;
    ASSERT_EQ(source_.Next(kWait, &p), core::Status::kOk) << source_.LastError();
    EXPECT_EQ(p.seq, static_cast<std::uint64_t>(seq));
    EXPECT_EQ(p.dropped_before, dropped_before) << "seq " << seq;
    EXPECT_EQ(p.left_exposure_ns, (1000000 + seq * 100000) * core::kNsPerUs);
    EXPECT_EQ(p.right_exposure_ns, p.left_exposure_ns + 20 * core::kNsPerUs);
    ASSERT_EQ(p.left.width, 64);
    ASSERT_EQ(p.left.height, 48);
    EXPECT_EQ(p.left.stride, 64);
    bool intact = true;
    for (std::size_t i = 0; i < 64u * 48u; ++i) {
      intact =
          intact && p.left.data[i] == LeftPixel(seq, i) && p.right.data[i] == RightPixel(seq, i);
    }
    EXPECT_TRUE(intact) << "pixels of seq " << seq;
    source_.Release(p);
  }

  lcm_t* publisher_ = nullptr;
  LcmStereoSource source_;
};

TEST_F(LcmSource, PairsArriveIntactAndInOrder) {
  StartSource(Options());
  for (std::int64_t k = 0; k < 3; ++k) Publish(Frame(k));
  for (std::int64_t k = 0; k < 3; ++k) ASSERT_NO_FATAL_FAILURE(ExpectPair(k));
  // One at a time, as a camera process at its frame rate.
  for (std::int64_t k = 3; k < 8; ++k) {
    Publish(Frame(k));
    ASSERT_NO_FATAL_FAILURE(ExpectPair(k));
  }
  const SourceStats s = source_.Stats();
  EXPECT_EQ(s.pairs_served, 8u);
  EXPECT_EQ(s.frames_rejected, 0u);
  EXPECT_EQ(s.frames_dropped, 0u);
  EXPECT_EQ(source_.Detail().received, 8u);
  EXPECT_STREQ(source_.Name(), "lcm");
}

TEST_F(LcmSource, SequenceGapsAreDroppedPairsReportedOnTheNextPair) {
  StartSource(Options(8));
  // GIVEN 0, 1, then 4: two frames lost on the way; THEN 5 saying it follows one frame its
  // publisher lost (numbered across it: 6 never sent) and 7 follows 5.
  Publish(Frame(0));
  Publish(Frame(1));
  Publish(Frame(4));
  swf_msgs::stereo_frame_t seven = Frame(7);
  seven.dropped_before = 1;
  Publish(seven);
  // AND a publisher that numbers only what it sends: 8 announces 3 pairs its camera lost.
  swf_msgs::stereo_frame_t eight = Frame(8);
  eight.dropped_before = 3;
  Publish(eight);
  ASSERT_NO_FATAL_FAILURE(ExpectPair(0));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(1));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(4, 2));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(7, 2));  // 5 lost on the way and 6 announced
  ASSERT_NO_FATAL_FAILURE(ExpectPair(8, 3));
  const LcmStereoStats d = source_.Detail();
  EXPECT_EQ(d.sequence_gaps, 3u);  // 2, 3 and 5
  EXPECT_EQ(d.announced_drops, 4u);
  EXPECT_EQ(source_.Stats().frames_dropped, 7u);
  EXPECT_EQ(source_.Stats().frames_rejected, 0u);
}

TEST_F(LcmSource, GarbageAndTruncatedMessagesAreRejectedAndTheStreamGoesOn) {
  StartSource(Options(8));
  Publish(Frame(0));
  const std::vector<std::uint8_t> junk = {1, 2, 3, 4, 5};
  PublishBytes(junk);
  std::vector<std::uint8_t> cut = Encode(Frame(1));
  cut.resize(cut.size() - 10);
  PublishBytes(cut);
  PublishBytes(Encode(swf_msgs::nav_state_t{}));  // another type on the channel
  std::vector<std::uint8_t> negative = Encode(Frame(1));
  negative[8 + 86 + 8] = 0xff;  // num_bytes -> negative
  PublishBytes(negative);
  PublishBytes({});  // empty message
  Publish(Frame(1));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(0));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(1));
  const LcmStereoStats d = source_.Detail();
  EXPECT_EQ(d.received, 7u);
  EXPECT_EQ(d.undecodable, 5u);
  EXPECT_EQ(source_.Stats().frames_rejected, 5u);
  EXPECT_EQ(source_.Stats().frames_dropped, 0u);
  // The cause reaches LastError() with the next timeout, naming the channel.
  StereoPair p;
  ASSERT_EQ(source_.Next(50 * core::kNsPerMs, &p), core::Status::kTimeout);
  const std::string e = source_.LastError();
  EXPECT_NE(e.find("lcm TEST_STEREO: no frame within 50 ms"), std::string::npos) << e;
  EXPECT_NE(e.find("7 messages received, 5 rejected"), std::string::npos) << e;
  EXPECT_NE(e.find("does not decode"), std::string::npos) << e;
}

TEST_F(LcmSource, FramesOfTheWrongSizeFlagOrOrderAreRejected) {
  LcmStereoOptions o = Options(8);
  o.exact_size = true;
  StartSource(o);
  Publish(Frame(0));
  Publish(Frame(1, 65, 48));  // wider than the buffers: refused before it is decoded
  Publish(Frame(2, 64, 49));  // taller
  Publish(Frame(3, 32, 24));  // fits, but not the camera's size
  swf_msgs::stereo_frame_t rectified = Frame(4);
  rectified.rectified = true;  // the consumer rectifies: a rectified frame would be rectified twice
  Publish(rectified);
  swf_msgs::stereo_frame_t stale = Frame(5);
  stale.left_exposure_utime = 1000000;  // the exposure of frame 0
  Publish(stale);
  Publish(Frame(0));  // frame 0 again: a repeated number
  swf_msgs::stereo_frame_t bad_time = Frame(6);
  bad_time.right_exposure_utime = -5;
  Publish(bad_time);
  Publish(Frame(7));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(0));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(7, 6));  // 1..6 never served
  const LcmStereoStats d = source_.Detail();
  EXPECT_EQ(d.received, 9u);
  EXPECT_EQ(d.wrong_size, 3u);
  EXPECT_EQ(d.wrong_rectification, 1u);
  EXPECT_EQ(d.out_of_order, 2u);
  EXPECT_EQ(d.bad_fields, 1u);
  EXPECT_EQ(source_.Stats().frames_rejected, 7u);
  // The numbers 1..6 arrived (and were refused): not lost on the way.
  EXPECT_EQ(d.sequence_gaps, 0u);
  EXPECT_EQ(source_.Stats().frames_dropped, 0u);
}

TEST_F(LcmSource, TimeoutWithoutPublisher) {
  StartSource(Options());
  StereoPair p;
  const core::TimeNs t0 = core::MonotonicNs();
  EXPECT_EQ(source_.Next(200 * core::kNsPerMs, &p), core::Status::kTimeout);
  const core::TimeNs waited = core::MonotonicNs() - t0;
  EXPECT_GE(waited, 190 * core::kNsPerMs);
  EXPECT_LT(waited, 2 * core::kNsPerS);
  EXPECT_EQ(source_.Next(0, &p), core::Status::kTimeout);  // a poll does not wait
  EXPECT_EQ(source_.Stats().timeouts, 2u);
  EXPECT_NE(std::string(source_.LastError()).find("lcm TEST_STEREO: no frame"), std::string::npos);
}

TEST_F(LcmSource, FullPoolDropsAndCountsAndACallerHoldingEveryBufferGetsFull) {
  StartSource(Options(2));
  for (std::int64_t k = 0; k < 4; ++k) Publish(Frame(k));
  ASSERT_TRUE(WaitReceived(4));
  EXPECT_EQ(source_.Detail().pool_full, 2u);  // 2 and 3: both buffers queued
  StereoPair a;
  StereoPair b;
  ASSERT_EQ(source_.Next(kWait, &a), core::Status::kOk);
  ASSERT_EQ(source_.Next(kWait, &b), core::Status::kOk);
  EXPECT_EQ(a.seq, 0u);
  EXPECT_EQ(b.seq, 1u);
  StereoPair c;
  EXPECT_EQ(source_.Next(kWait, &c), core::Status::kFull);
  source_.Release(a);
  source_.Release(a);  // twice: ignored
  source_.Release(b);
  Publish(Frame(4));
  ASSERT_NO_FATAL_FAILURE(ExpectPair(4, 2));  // 2 and 3 dropped here
  EXPECT_EQ(source_.Stats().frames_dropped, 2u);
}

TEST_F(LcmSource, NextAndReleaseDoNotAllocate) {
  StartSource(Options(8));
  std::uint64_t allocations = 0;
  std::uint64_t receive_allocations = 0;
  std::uint64_t served = 0;
  std::int64_t seq = 0;
  std::vector<std::vector<std::uint8_t>> encoded;
  for (int k = 0; k < 80; ++k) encoded.push_back(Encode(Frame(k)));
  for (int round = 0; round < 10; ++round) {
    {
      // Receiving (LCM and this source's handler) is measured, not required: LCM is not ours.
      swf::testing::AllocationScope scope;
      for (int k = 0; k < 8; ++k) {
        const std::vector<std::uint8_t>& bytes = encoded[static_cast<std::size_t>(seq + k)];
        ASSERT_EQ(
            lcm_publish(publisher_, kChannel, bytes.data(), static_cast<unsigned>(bytes.size())),
            0);
      }
      ASSERT_TRUE(WaitReceived(static_cast<std::uint64_t>(seq + 8)));
      receive_allocations += scope.Count();
    }
    // GIVEN eight received pairs and the receiver idle WHEN they are taken and released THEN
    // nothing allocates.
    swf::testing::AllocationScope scope;
    for (int k = 0; k < 8; ++k) {
      StereoPair p;
      if (source_.Next(kWait, &p) != core::Status::kOk) break;
      served += p.seq == static_cast<std::uint64_t>(seq) ? 1 : 0;
      ++seq;
      source_.Release(p);
    }
    allocations += scope.Count();
  }
  EXPECT_EQ(served, 80u);
  EXPECT_EQ(allocations, 0u);
  std::printf("allocations while receiving 80 pairs (publisher, LCM, handler): %llu\n",
              static_cast<unsigned long long>(receive_allocations));
}

TEST_F(LcmSource, StopThenStartAgain) {
  StartSource(Options());
  Publish(Frame(0));
  StereoPair held;
  ASSERT_EQ(source_.Next(kWait, &held), core::Status::kOk);
  source_.Stop();
  Publish(Frame(1));  // nobody listening
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(source_.Detail().received, 1u);
  StereoPair p;
  EXPECT_EQ(source_.Next(0, &p), core::Status::kNotConfigured);
  ASSERT_EQ(source_.Start(), core::Status::kOk) << source_.LastError();
  // A pair held across the restart stays valid and is released as usual.
  EXPECT_EQ(held.left.data[5], LeftPixel(0, 5));
  source_.Release(held);
  // The publisher restarted its numbering meanwhile (time goes on): followed, nothing counted.
  swf_msgs::stereo_frame_t again = Frame(0);
  again.left_exposure_utime += 10000000;
  again.right_exposure_utime += 10000000;
  again.utime = again.left_exposure_utime;
  Publish(again);
  Publish(Frame(2));
  ASSERT_EQ(source_.Next(kWait, &p), core::Status::kOk) << source_.LastError();
  EXPECT_EQ(p.seq, 0u);
  EXPECT_EQ(p.left_exposure_ns, 11000000 * core::kNsPerUs);
  EXPECT_EQ(p.dropped_before, 0u);
  source_.Release(p);
  // Frame 2 is older than the restarted frame 0 (exposure behind): refused.
  EXPECT_EQ(source_.Next(200 * core::kNsPerMs, &p), core::Status::kTimeout);
  EXPECT_EQ(source_.Detail().out_of_order, 1u);
  // Every buffer is usable again after the restart.
  source_.Stop();
  ASSERT_EQ(source_.Start(), core::Status::kOk);
  for (std::int64_t k = 3; k < 7; ++k) Publish(Frame(k));
  for (std::int64_t k = 3; k < 7; ++k) ASSERT_NO_FATAL_FAILURE(ExpectPair(k));
}

TEST_F(LcmSource, BadOptionsAreRefusedNamingTheOption) {
  LcmStereoOptions o = Options(1);
  EXPECT_EQ(source_.Configure(o), core::Status::kInvalidArgument);
  EXPECT_NE(std::string(source_.LastError()).find("buffers 1"), std::string::npos);
  o = Options();
  o.max_width = 0;
  EXPECT_EQ(source_.Configure(o), core::Status::kInvalidArgument);
  EXPECT_NE(std::string(source_.LastError()).find("image size"), std::string::npos);
  o = Options();
  o.channel = "";
  EXPECT_EQ(source_.Configure(o), core::Status::kInvalidArgument);
  EXPECT_EQ(source_.Start(), core::Status::kNotConfigured);
  o = Options();
  o.url = "nosuchprovider://x";
  ASSERT_EQ(source_.Configure(o), core::Status::kOk);
  EXPECT_EQ(source_.Start(), core::Status::kIoError);
  EXPECT_NE(std::string(source_.LastError()).find("cannot open LCM at 'nosuchprovider://x'"),
            std::string::npos)
      << source_.LastError();
}

// Mutated frames on the bus (seeded): every message is served with usable fields or counted, and
// nothing crashes. The decoder itself is fuzzed by messages_decode_fuzz (the bounded overload
// included).
TEST_F(LcmSource, MutatedMessagesAreServedOrCounted) {
  StartSource(Options());
  std::mt19937 rng(17);
  const std::vector<std::uint8_t> good = Encode(Frame(3, 16, 12));
  std::uint64_t served = 0;
  constexpr int kMessages = 300;
  for (int k = 0; k < kMessages; ++k) {
    std::vector<std::uint8_t> m = good;
    switch (rng() % 4) {
      case 0: m.resize(rng() % m.size()); break;  // truncated
      case 1: m[rng() % m.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8)); break;
      case 2: m[8 + rng() % 120] = static_cast<std::uint8_t>(rng()); break;  // header fields
      default: m.push_back(static_cast<std::uint8_t>(rng())); break;         // trailing byte
    }
    PublishBytes(m);
    // At a camera's pace: a burst of hundreds overflows the loopback socket on a loaded machine.
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    StereoPair p;
    while (source_.Next(0, &p) == core::Status::kOk) {
      EXPECT_LE(p.left.width, 64);
      EXPECT_LE(p.left.height, 48);
      EXPECT_GE(p.left.width * p.left.height, 1);
      ++served;
      source_.Release(p);
    }
  }
  // Loopback UDP may still lose some under load: the invariant below holds for what arrived.
  ASSERT_TRUE(WaitReceived(kMessages / 2)) << source_.Detail().received;
  StereoPair p;
  while (source_.Next(100 * core::kNsPerMs, &p) == core::Status::kOk) {
    ++served;
    source_.Release(p);
  }
  const LcmStereoStats d = source_.Detail();
  const SourceStats s = source_.Stats();
  EXPECT_EQ(d.received, served + s.frames_rejected + d.pool_full);
  EXPECT_GT(s.frames_rejected, 0u);
}

}  // namespace
}  // namespace swf::drivers
