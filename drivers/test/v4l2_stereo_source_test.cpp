// V4l2StereoSource against the scripted kernel: normal streaming, the errors a real driver
// produces, format negotiation, and resource accounting (no leaked fd, mapping or buffer).
#include "swf/drivers/v4l2_stereo_source.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "scripted_v4l2_kernel.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::drivers {
namespace {

using testing::KernelEvent;
using testing::ScriptedDevice;
using testing::ScriptedV4l2Kernel;

constexpr core::TimeNs kTimeout = 20 * core::kNsPerMs;

ScriptedDevice Device(const char* path, std::uint32_t width = 64, std::uint32_t height = 48,
                      std::uint32_t fourcc = V4L2_PIX_FMT_GREY) {
  ScriptedDevice d;
  d.path = path;
  d.width = width;
  d.height = height;
  d.formats = {fourcc};
  return d;
}

V4l2StereoOptions Options(PixelFormat format = PixelFormat::kGray8) {
  V4l2StereoOptions o;
  o.left.device = "/dev/video0";
  o.right.device = "/dev/video1";
  o.left.width = o.right.width = 64;
  o.left.height = o.right.height = 48;
  o.left.format = o.right.format = format;
  o.left.buffer_count = o.right.buffer_count = 4;
  return o;
}

// Every pixel the scripted kernel writes equals the frame's sequence number & 0xFF.
bool ImageIs(const core::ImageView<const std::uint8_t>& v, std::uint8_t value) {
  for (std::int32_t r = 0; r < v.height; ++r) {
    for (std::int32_t c = 0; c < v.width; ++c) {
      if (v.data[static_cast<std::size_t>(r) * v.stride + c] != value) return false;
    }
  }
  return true;
}

class V4l2Source : public ::testing::Test {
 protected:
  void AddPair(std::uint32_t fourcc = V4L2_PIX_FMT_GREY) {
    left_ = kernel_.AddDevice(Device("/dev/video0", 64, 48, fourcc));
    right_ = kernel_.AddDevice(Device("/dev/video1", 64, 48, fourcc));
  }
  void ConfigureAndStart(const V4l2StereoOptions& options = Options()) {
    ASSERT_EQ(source_.Configure(options), core::Status::kOk);
    ASSERT_EQ(source_.Start(), core::Status::kOk);
  }
  void ExpectNoLeaks() {
    source_.Stop();
    EXPECT_EQ(kernel_.OpenFds(), 0);
    EXPECT_EQ(kernel_.MappedBuffers(), 0);
  }
  ScriptedV4l2Kernel kernel_;
  V4l2StereoSource source_{kernel_};
  int left_ = -1;
  int right_ = -1;
};

TEST_F(V4l2Source, NormalStreamingServesPairedZeroCopyGrayFrames) {
  AddPair();
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  for (std::uint64_t i = 0; i < 10; ++i) {
    StereoPair pair;
    ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk) << source_.LastError();
    EXPECT_EQ(pair.seq, i);
    EXPECT_EQ(pair.dropped_before, 0u);
    EXPECT_EQ(pair.left.width, 64);
    EXPECT_EQ(pair.right.height, 48);
    EXPECT_EQ(pair.left_exposure_ns, pair.right_exposure_ns);
    EXPECT_EQ(pair.left_exposure_ns, 1'000'000'000 + static_cast<core::TimeNs>(i) * 50'000'000);
    EXPECT_TRUE(ImageIs(pair.left, static_cast<std::uint8_t>(i)));
    EXPECT_TRUE(ImageIs(pair.right, static_cast<std::uint8_t>(i)));
    EXPECT_EQ(source_.BuffersOutstanding(), 2);  // zero copy: the driver buffers are lent out
    source_.Release(pair);
    EXPECT_EQ(source_.BuffersOutstanding(), 0);
  }
  const SourceStats s = source_.Stats();
  EXPECT_EQ(s.pairs_served, 10u);
  EXPECT_EQ(s.frames_dropped + s.frames_rejected + s.pairing_failures + s.timeouts, 0u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, NoAllocationInNextAndReleaseAfterStart) {
  // Y16 takes the conversion path, a time shift takes the pairing-discard path.
  AddPair(V4L2_PIX_FMT_Y16);
  kernel_.Script(right_, 20, KernelEvent::kTimeShift, -50'000'000);
  kernel_.Script(left_, 30, KernelEvent::kErrorFlag);
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart(Options(PixelFormat::kGray16Le)));
  std::uint64_t allocations = 0;
  {
    swf::testing::AllocationScope scope;
    for (int i = 0; i < 100; ++i) {
      StereoPair pair;
      ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
      source_.Release(pair);
    }
    allocations = scope.Count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(source_.Stats().pairs_served, 100u);
  EXPECT_GE(source_.Stats().pairing_failures, 1u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, EagainAndEintrAreTransparent) {
  AddPair();
  kernel_.Script(left_, 2, KernelEvent::kEagain);
  kernel_.Script(right_, 4, KernelEvent::kEintr, 2);   // retried inside one dequeue
  kernel_.Script(right_, 7, KernelEvent::kEintr, 10);  // more than the retry bound
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  for (std::uint64_t i = 0; i < 10; ++i) {
    StereoPair pair;
    ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk) << source_.LastError();
    EXPECT_TRUE(ImageIs(pair.left, static_cast<std::uint8_t>(i)));
    EXPECT_TRUE(ImageIs(pair.right, static_cast<std::uint8_t>(i)));
    source_.Release(pair);
  }
  const SourceStats s = source_.Stats();
  EXPECT_EQ(s.frames_dropped + s.frames_rejected + s.pairing_failures + s.timeouts, 0u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, PollInterruptedBySignalIsRetried) {
  AddPair();
  kernel_.Script(left_, 0, KernelEvent::kEagain);  // two waits for the left frame
  kernel_.Script(left_, 1, KernelEvent::kEagain);
  kernel_.InjectPollEintr(2);
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  StereoPair pair;
  ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk) << source_.LastError();
  EXPECT_EQ(kernel_.PollEintrLeft(), 0);
  EXPECT_TRUE(ImageIs(pair.left, 0));
  source_.Release(pair);
  EXPECT_EQ(source_.Stats().timeouts, 0u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, ErrorFlaggedBufferIsRejectedAndStreamingContinues) {
  AddPair();
  kernel_.Script(left_, 3, KernelEvent::kErrorFlag);  // left frame 3 is corrupt
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  std::uint8_t expected[] = {0, 1, 2, 4, 5, 6};
  for (std::uint8_t frame : expected) {
    StereoPair pair;
    ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk) << source_.LastError();
    EXPECT_TRUE(ImageIs(pair.left, frame));
    EXPECT_TRUE(ImageIs(pair.right, frame));
    EXPECT_EQ(pair.dropped_before, frame == 4 ? 1u : 0u);
    source_.Release(pair);
  }
  const SourceStats s = source_.Stats();
  EXPECT_EQ(s.frames_rejected, 1u);
  EXPECT_EQ(s.pairing_failures, 1u);  // right frame 3 lost its partner
  EXPECT_EQ(source_.BuffersOutstanding(), 0);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, SingleEioIsTransientButPersistentEioStopsWithIoError) {
  AddPair();
  kernel_.Script(right_, 2, KernelEvent::kEio);
  for (int call = 6; call < 12; ++call) kernel_.Script(left_, call, KernelEvent::kEio);
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  core::Status status = core::Status::kOk;
  int served = 0;
  for (int i = 0; i < 20 && core::IsOk(status); ++i) {
    StereoPair pair;
    status = source_.Next(kTimeout, &pair);
    if (core::IsOk(status)) {
      ++served;
      source_.Release(pair);
    }
  }
  EXPECT_EQ(status, core::Status::kIoError);
  EXPECT_EQ(served, 6);  // frames 0..5; the single EIO on the right cost no pair
  EXPECT_NE(std::strstr(source_.LastError(), "/dev/video0"), nullptr) << source_.LastError();
  EXPECT_NE(std::strstr(source_.LastError(), "errno 5"), nullptr) << source_.LastError();
  EXPECT_EQ(source_.Stats().frames_rejected, 4u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, UnplugMidStreamGivesDeviceLostThenRecoversAfterReplug) {
  AddPair();
  kernel_.Script(right_, 5, KernelEvent::kUnplug);
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  StereoPair held;  // a pair the caller still holds when the camera vanishes
  ASSERT_EQ(source_.Next(kTimeout, &held), core::Status::kOk);
  core::Status status = core::Status::kOk;
  for (int i = 0; i < 10 && core::IsOk(status); ++i) {
    StereoPair pair;
    status = source_.Next(kTimeout, &pair);
    if (core::IsOk(status)) source_.Release(pair);
  }
  EXPECT_EQ(status, core::Status::kDeviceLost);
  EXPECT_NE(std::strstr(source_.LastError(), "/dev/video1"), nullptr) << source_.LastError();
  source_.Release(held);  // after the loss: must not crash
  ExpectNoLeaks();

  EXPECT_EQ(source_.Start(), core::Status::kDeviceLost);  // still unplugged
  EXPECT_EQ(kernel_.OpenFds(), 0);
  kernel_.Replug(right_);
  ASSERT_EQ(source_.Start(), core::Status::kOk) << source_.LastError();
  StereoPair pair;
  ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
  EXPECT_TRUE(ImageIs(pair.right, 0));
  source_.Release(pair);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, SFmtAnsweringAnotherConvertibleFormatIsConverted) {
  AddPair(V4L2_PIX_FMT_YUYV);  // asks GREY, the device only does YUYV
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart(Options(PixelFormat::kGray8)));
  for (std::uint8_t i = 0; i < 3; ++i) {
    StereoPair pair;
    ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
    EXPECT_TRUE(ImageIs(pair.left, i));
    EXPECT_TRUE(ImageIs(pair.right, i));
    EXPECT_EQ(source_.BuffersOutstanding(), 0);  // converted: driver buffers went back at once
    source_.Release(pair);
  }
  ExpectNoLeaks();
}

TEST_F(V4l2Source, SFmtAnsweringAnUnsupportedFormatFailsCleanly) {
  AddPair(V4L2_PIX_FMT_MJPEG);
  ASSERT_EQ(source_.Configure(Options()), core::Status::kOk);
  EXPECT_EQ(source_.Start(), core::Status::kUnsupported);
  EXPECT_NE(std::strstr(source_.LastError(), "open"), nullptr);
  StereoPair pair;
  EXPECT_EQ(source_.Next(kTimeout, &pair), core::Status::kNotConfigured);
  EXPECT_EQ(kernel_.OpenFds(), 0);
  EXPECT_EQ(kernel_.MappedBuffers(), 0);
}

TEST_F(V4l2Source, CamerasOfDifferentSizesAndFormats) {
  left_ = kernel_.AddDevice(Device("/dev/video0", 64, 48, V4L2_PIX_FMT_GREY));
  ScriptedDevice r = Device("/dev/video1", 32, 24, V4L2_PIX_FMT_Y16);
  r.row_padding_bytes = 6;
  right_ = kernel_.AddDevice(r);
  V4l2StereoOptions o = Options();
  o.right.format = PixelFormat::kGray16Le;
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart(o));
  StereoPair pair;
  ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
  EXPECT_EQ(pair.left.width, 64);
  EXPECT_EQ(pair.right.width, 32);
  EXPECT_EQ(pair.right.height, 24);
  EXPECT_EQ(pair.right.stride, 32);
  EXPECT_TRUE(ImageIs(pair.right, 0));
  source_.Release(pair);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, HoldingEveryPairSlotGivesFullNotABlock) {
  AddPair();
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  StereoPair a, b, c;
  ASSERT_EQ(source_.Next(kTimeout, &a), core::Status::kOk);
  ASSERT_EQ(source_.Next(kTimeout, &b), core::Status::kOk);
  EXPECT_EQ(source_.Next(kTimeout, &c), core::Status::kFull);
  source_.Release(a);
  source_.Release(a);  // a second release is ignored
  ASSERT_EQ(source_.Next(kTimeout, &c), core::Status::kOk);
  EXPECT_EQ(c.seq, 2u);
  source_.Release(b);
  source_.Release(c);
  EXPECT_EQ(source_.BuffersOutstanding(), 0);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, LostFramesAreCountedFromSequenceGaps) {
  AddPair();
  kernel_.Script(left_, 4, KernelEvent::kLoseFrames, 3);
  kernel_.Script(right_, 4, KernelEvent::kLoseFrames, 3);
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  for (int i = 0; i < 6; ++i) {
    StereoPair pair;
    ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
    EXPECT_EQ(pair.dropped_before, i == 4 ? 3u : 0u);
    EXPECT_TRUE(ImageIs(pair.left, static_cast<std::uint8_t>(i < 4 ? i : i + 3)));
    source_.Release(pair);
  }
  EXPECT_EQ(source_.Stats().frames_dropped, 6u);
  EXPECT_EQ(source_.Stats().pairing_failures, 0u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, PairsByTimestampAfterOneCameraSlips) {
  AddPair();
  // The right camera's clock jumps back one period: its frame 3 was exposed with left frame 2.
  kernel_.Script(right_, 3, KernelEvent::kTimeShift, -50'000'000);
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  for (int i = 0; i < 6; ++i) {
    StereoPair pair;
    ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
    EXPECT_EQ(pair.left_exposure_ns, pair.right_exposure_ns);
    source_.Release(pair);
  }
  EXPECT_EQ(source_.Stats().pairing_failures, 1u);
  ExpectNoLeaks();
}

// GIVEN a right camera whose exposures drift 10 ms (5x the 2 ms tolerance, a fifth of a period)
// behind the left's from its frame 2 to frame 4 THEN those frames are never paired (no pair
// leaves the source with exposures further apart than the tolerance), each refusal is counted,
// and pairing resumes when the cameras agree again.
TEST_F(V4l2Source, DesynchronizedFramesAreRefusedAndCounted) {
  AddPair();
  kernel_.Script(right_, 2, KernelEvent::kTimeShift, 10'000'000);
  kernel_.Script(right_, 5, KernelEvent::kTimeShift, -10'000'000);
  V4l2StereoOptions options = Options();
  options.left.buffer_count = options.right.buffer_count = 8;
  ASSERT_EQ(source_.Configure(options), core::Status::kOk);
  ASSERT_EQ(source_.Start(), core::Status::kOk);
  std::uint64_t served = 0;
  for (int i = 0; i < 8; ++i) {
    StereoPair pair;
    const core::Status s = source_.Next(kTimeout, &pair);
    if (s == core::Status::kTimeout) continue;
    ASSERT_EQ(s, core::Status::kOk) << source_.LastError();
    EXPECT_LE(std::abs(pair.left_exposure_ns - pair.right_exposure_ns), options.pair_tolerance_ns);
    ++served;
    source_.Release(pair);
  }
  // Right frames 2, 3, 4 are each refused against a left frame, and so are the left frames they
  // displaced: three left and three right frames, all counted, none served.
  EXPECT_EQ(source_.Stats().pairing_failures, 6u);
  EXPECT_EQ(served, source_.Stats().pairs_served);
  EXPECT_GE(served, 5u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, StalledCameraTimesOutAndResumes) {
  AddPair();
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  kernel_.SetStalled(right_, true);
  StereoPair pair;
  EXPECT_EQ(source_.Next(5 * core::kNsPerMs, &pair), core::Status::kTimeout);
  EXPECT_EQ(source_.Stats().timeouts, 1u);
  // The timeout names the camera the pair waits for, not its healthy partner.
  EXPECT_NE(std::strstr(source_.LastError(), "/dev/video1: no frame"), nullptr)
      << source_.LastError();
  EXPECT_EQ(std::strstr(source_.LastError(), "/dev/video0"), nullptr) << source_.LastError();
  kernel_.SetStalled(right_, false);
  ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
  EXPECT_TRUE(ImageIs(pair.left, 0));
  source_.Release(pair);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, ShortFrameIsRejected) {
  AddPair();
  kernel_.Script(left_, 1, KernelEvent::kShortFrame);
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart());
  for (std::uint8_t expected : {0, 2}) {
    StereoPair pair;
    ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
    EXPECT_TRUE(ImageIs(pair.left, expected));
    source_.Release(pair);
  }
  EXPECT_EQ(source_.Stats().frames_rejected, 1u);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, SideBySideDeviceIsSplitInPlace) {
  left_ = kernel_.AddDevice(Device("/dev/video0", 128, 48, V4L2_PIX_FMT_GREY));
  V4l2StereoOptions o = Options();
  o.side_by_side = true;
  o.left.width = 128;
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart(o));
  StereoPair pair;
  ASSERT_EQ(source_.Next(kTimeout, &pair), core::Status::kOk);
  EXPECT_EQ(pair.left.width, 64);
  EXPECT_EQ(pair.right.width, 64);
  EXPECT_EQ(pair.right.data, pair.left.data + 64);
  EXPECT_EQ(pair.left.stride, 128);
  EXPECT_EQ(source_.BuffersOutstanding(), 1);
  source_.Release(pair);
  EXPECT_EQ(source_.BuffersOutstanding(), 0);
  ExpectNoLeaks();
}

TEST_F(V4l2Source, ExposureAndGainControlsReachTheDevice) {
  AddPair();
  V4l2StereoOptions o = Options();
  o.left.exposure_100us = 42;
  ASSERT_NO_FATAL_FAILURE(ConfigureAndStart(o));
  EXPECT_EQ(kernel_.LastExposure(left_), 42);
  EXPECT_EQ(kernel_.LastExposure(right_), -1);
  source_.Stop();

  ScriptedV4l2Kernel kernel;
  ScriptedDevice d = Device("/dev/video0");
  d.has_exposure_control = false;
  kernel.AddDevice(d);
  kernel.AddDevice(Device("/dev/video1"));
  V4l2StereoSource source(kernel);
  ASSERT_EQ(source.Configure(o), core::Status::kOk);
  EXPECT_EQ(source.Start(), core::Status::kUnsupported);
  EXPECT_EQ(kernel.OpenFds(), 0);
}

TEST_F(V4l2Source, BadOptionsAreRejectedBeforeTouchingDevices) {
  AddPair();
  V4l2StereoOptions o = Options();
  o.left.buffer_count = 2;  // cannot lend two pairs and keep streaming
  EXPECT_EQ(source_.Configure(o), core::Status::kInvalidArgument);
  EXPECT_EQ(source_.Start(), core::Status::kNotConfigured);
  EXPECT_EQ(kernel_.OpenFds(), 0);
}

}  // namespace
}  // namespace swf::drivers
