// The flight pipeline on source: v4l2 — swf-fsw's V4L2 source (MakeV4l2Source, the same factory
// swf-fsw uses over the Linux kernel) over drivers' scripted kernel, because this machine has no
// /dev/video devices. The scripted kernel's uniform frames get a texture seen by a stereo rig
// (right view = left view shifted by a fixed disparity, the scene sliding one pixel per frame),
// so the front end tracks and the filter estimates on real pixel data: 10 pairs in, 10 navigation
// outputs out, no allocation on the frame path after start, and an unplugged camera is a counted
// outage (coasted, published as CAMERA_OUTAGE) that ends when it is plugged back in, or that ends
// the run naming the device when it stays away beyond the outage limit.
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "block_texture.hpp"
#include "scripted_v4l2_kernel.hpp"
#include "swf/app/app.hpp"
#include "swf/app/config.hpp"
#include "swf/app/flight_loop.hpp"
#include "swf/app/hazard_stage.hpp"
#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/app/v4l2_source.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::app {
namespace {

using drivers::testing::KernelEvent;
using drivers::testing::ScriptedDevice;
using drivers::testing::ScriptedV4l2Kernel;

constexpr int kWidth = 256;
constexpr int kHeight = 192;
constexpr int kDisparityPx = 8;
constexpr double kFocalPx = 200.0;
constexpr double kBaselineM = 0.2;

// Forwards to the scripted kernel and paints every dequeued GREY frame with the textured scene
// (left or right view by device, shifted by the frame's sequence number). Allocates only while
// buffers are mapped (before start).
class TexturingKernel final : public drivers::V4l2Kernel {
 public:
  TexturingKernel(ScriptedV4l2Kernel* inner, std::string left_path)
      : inner_(inner), left_path_(std::move(left_path)) {}

  int Open(const char* path) override {
    const int fd = inner_->Open(path);
    if (fd >= 0) fds_.push_back({fd, left_path_ == path});
    return fd;
  }
  // A restarted source reopens its devices and gets the same fd numbers: forget the old ones.
  int Close(int fd) override {
    std::erase_if(fds_, [fd](const FdSide& s) { return s.fd == fd; });
    std::erase_if(offsets_, [fd](const Offset& o) { return o.fd == fd; });
    return inner_->Close(fd);
  }
  int Map(int fd, std::size_t length, std::int64_t offset, void** address) override {
    const int r = inner_->Map(fd, length, offset, address);
    if (r >= 0) maps_.push_back({fd, offset, static_cast<std::uint8_t*>(*address), length});
    return r;
  }
  int Unmap(void* address, std::size_t length) override {
    std::erase_if(maps_, [address](const Mapping& m) { return m.data == address; });
    return inner_->Unmap(address, length);
  }
  int Poll(pollfd* fds, int count, int timeout_ms) override {
    return inner_->Poll(fds, count, timeout_ms);
  }
  int Ioctl(int fd, unsigned long request, void* arg) override {
    const int r = inner_->Ioctl(fd, request, arg);
    if (r < 0) return r;
    if (request == VIDIOC_QUERYBUF) {
      const auto* b = static_cast<const v4l2_buffer*>(arg);
      offsets_.push_back({fd, b->index, static_cast<std::int64_t>(b->m.offset)});
    } else if (request == VIDIOC_DQBUF) {
      Paint(fd, *static_cast<const v4l2_buffer*>(arg));
    }
    return r;
  }

 private:
  struct FdSide {
    int fd;
    bool left;
  };
  struct Offset {
    int fd;
    std::uint32_t index;
    std::int64_t offset;
  };
  struct Mapping {
    int fd;
    std::int64_t offset;
    std::uint8_t* data;
    std::size_t length;
  };

  void Paint(int fd, const v4l2_buffer& b) {
    if ((b.flags & V4L2_BUF_FLAG_ERROR) != 0U) return;
    bool left = false;
    for (const FdSide& s : fds_) {
      if (s.fd == fd) left = s.left;
    }
    std::int64_t offset = -1;
    for (const Offset& o : offsets_) {
      if (o.fd == fd && o.index == b.index) offset = o.offset;
    }
    for (const Mapping& m : maps_) {
      if (m.fd != fd || m.offset != offset) continue;
      if (m.length < static_cast<std::size_t>(kWidth) * kHeight) return;
      const int shift = static_cast<int>(b.sequence) + (left ? 0 : kDisparityPx);
      for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x)
          m.data[y * kWidth + x] = swf::testing::BlockTexture(x + shift, y);
      }
      return;
    }
  }

  ScriptedV4l2Kernel* inner_;
  std::string left_path_;
  std::vector<FdSide> fds_;
  std::vector<Offset> offsets_;
  std::vector<Mapping> maps_;
};

frontend::CameraCalibration Calibration(double x_m) {
  frontend::CameraCalibration c;
  c.width = kWidth;
  c.height = kHeight;
  c.fx = kFocalPx;
  c.fy = kFocalPx;
  c.cx = kWidth / 2.0;
  c.cy = kHeight / 2.0;
  c.body_T_camera.t = Eigen::Vector3d(x_m, 0.0, 0.0);
  return c;
}

class NavCollector : public OutputObserver {
 public:
  void OnNav(const NavRecord& r) override { navs.push_back(r.nav); }
  std::vector<NavOutput> navs;
};

struct V4l2Rig : FlightParts {
  FswConfig config;
  ScriptedV4l2Kernel scripted;
  std::unique_ptr<TexturingKernel> kernel;
  std::unique_ptr<drivers::V4l2StereoSource> source;
  NavCollector navs;
  FlightLoop loop;
  int left_device = -1;

  V4l2Rig() {
    std::string error;
    EXPECT_TRUE(ParseConfig(
        "source: v4l2\ncamera.left: /dev/video0\ncamera.right: /dev/video1\n"
        "camera.left_calibration: left.yaml\ncamera.right_calibration: right.yaml\n"
        "camera.format: grey\ncamera.buffers: 4\ncamera.pair_tolerance_ms: 2\ninitial: position\n",
        "test", &config, &error))
        << error;
    ScriptedDevice d;
    d.width = kWidth;
    d.height = kHeight;
    d.path = "/dev/video0";
    left_device = scripted.AddDevice(d);
    d.path = "/dev/video1";
    d.first_timestamp_ns += 300'000;  // the right camera's shutter 0.3 ms later
    scripted.AddDevice(d);
    kernel = std::make_unique<TexturingKernel>(&scripted, "/dev/video0");
    source = MakeV4l2Source(config, kWidth, kHeight, *kernel, &error);
    EXPECT_NE(source, nullptr) << error;

    PipelineOptions po;
    po.rectify = true;
    po.left_calibration = Calibration(0.0);
    po.right_calibration = Calibration(kBaselineM);
    po.width_px = kWidth;
    po.height_px = kHeight;
    po.frontend.harris.bucket_cols = po.width_px / 40;
    po.frontend.harris.bucket_rows = po.height_px / 40;
    po.frontend.max_tracks = 100;
    po.frontend.stereo.max_disparity = 64;
    po.swf.window_size = 5;
    hazard::HazardMapperOptions ho;
    ho.max_disparities = 64;
    EXPECT_EQ(AssembleFlightParts(po, ho, OutputOptions{}, this, &error), core::Status::kOk)
        << error;  // no LCM, no log: the outputs are only drained
    output.AddObserver(&navs);
    LoopOptions lo;
    lo.rate_hz = 20.0;
    lo.pacing = Pacing::kLockstep;
    lo.hazard_every = 5;
    lo.acquire_timeout_ns = core::kNsPerS / 10;
    // In cycles at 20 Hz (Step() counts cycles, not clock time): restart 5 cycles after a
    // silence, retry every 2, give up after 20.
    lo.restart_after_ns = core::kNsPerS / 4;
    lo.restart_interval_ns = core::kNsPerS / 10;
    lo.max_outage_ns = core::kNsPerS;
    EXPECT_EQ(
        loop.Configure(lo, pipeline.get(), source.get(), channels.get(), nullptr, hazard.get()),
        core::Status::kOk);
  }
};

// GIVEN swf-fsw's V4L2 source over two scripted GREY cameras WHEN the frame group runs 10 cycles
// (allocations counted around each) THEN 10 pairs go in, 10 navigation outputs come out with a
// finite estimate, nothing was dropped and not one allocation happened after start.
TEST(AppV4l2Test, TenPairsInTenNavsOutWithoutAllocation) {
  V4l2Rig rig;
  ASSERT_NE(rig.source, nullptr);
  ASSERT_EQ(rig.source->Start(), core::Status::kOk) << rig.source->LastError();
  std::uint64_t allocations = 0;
  for (int i = 0; i < 10; ++i) {
    core::Status s;
    {
      testing::AllocationScope scope;
      s = rig.loop.Step();
      allocations += scope.Count();
    }
    rig.output.DrainOnce();
    ASSERT_EQ(s, core::Status::kOk) << "cycle " << i << ": " << rig.source->LastError();
  }
  rig.source->Stop();
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(rig.loop.Counters().frames, 10);
  EXPECT_EQ(rig.loop.Counters().frames_dropped, 0);
  EXPECT_EQ(rig.loop.Counters().stage_errors, 0);
  EXPECT_EQ(rig.loop.Counters().outputs_dropped, 0);
  ASSERT_EQ(rig.navs.navs.size(), 10U);
  for (const NavOutput& nav : rig.navs.navs) {
    for (double p : nav.position_world_m) EXPECT_TRUE(std::isfinite(p));
  }
  EXPECT_GT(rig.pipeline->NumLandmarks(), 20);
}

// GIVEN the same rig WHEN the left camera is unplugged at its 5th dequeue (ENODEV) and plugged
// back in 6 cycles later THEN the frame group goes on: every missed cycle publishes a coasted
// output flagged CAMERA_OUTAGE and not VALID, the source is restarted (its first attempts fail
// while the device is away), the fault names /dev/video0, and pairs flow again after the replug.
TEST(AppV4l2Test, UnpluggedCameraIsACountedOutageThatRecovers) {
  V4l2Rig rig;
  ASSERT_NE(rig.source, nullptr);
  rig.scripted.Script(rig.left_device, 4, KernelEvent::kUnplug);
  ASSERT_EQ(rig.source->Start(), core::Status::kOk) << rig.source->LastError();
  int frames = 0;
  int missed = 0;
  for (int i = 0; i < 20; ++i) {
    if (missed == 6) rig.scripted.Replug(rig.left_device);
    const core::Status s = rig.loop.Step();
    rig.output.DrainOnce();
    if (s == core::Status::kOk) {
      ++frames;
    } else {
      ASSERT_EQ(s, core::Status::kTimeout) << rig.loop.SourceFault();
      ++missed;
    }
  }
  rig.source->Stop();
  const LoopCounters& c = rig.loop.Counters();
  EXPECT_EQ(c.camera_outages, 1);
  EXPECT_EQ(c.source_recoveries, 1);
  EXPECT_EQ(c.cycles_missed, missed);
  EXPECT_GE(missed, 6);
  EXPECT_LE(missed, 8);  // at most one retry interval after the replug
  EXPECT_EQ(c.cycles_coasted, missed);
  EXPECT_GE(c.source_restarts, 2);
  EXPECT_EQ(frames + missed, 20);
  EXPECT_NE(std::strstr(rig.loop.SourceFault(), "/dev/video0"), nullptr) << rig.loop.SourceFault();
  ASSERT_EQ(rig.navs.navs.size(), 20U);
  int outage_outputs = 0;
  for (const NavOutput& nav : rig.navs.navs) {
    if ((nav.integrity_flags & estimator::kFlagCameraOutage) == 0) continue;
    ++outage_outputs;
    EXPECT_NE(nav.status, static_cast<std::int8_t>(estimator::NavIntegrity::kValid));
  }
  EXPECT_EQ(outage_outputs, missed);
  // The first frame after the outage is estimated from images again.
  EXPECT_EQ(rig.navs.navs.back().integrity_flags & estimator::kFlagCameraOutage, 0);
  EXPECT_EQ(rig.scripted.OpenFds(), 0);
  EXPECT_EQ(rig.scripted.MappedBuffers(), 0);
}

// GIVEN the same rig WHEN the left camera is unplugged and never comes back THEN the frame group
// coasts for max_outage (20 cycles) and then ends with kDeviceLost, the fault naming the device.
TEST(AppV4l2Test, CameraLostBeyondTheOutageLimitEndsTheRunNamingIt) {
  V4l2Rig rig;
  ASSERT_NE(rig.source, nullptr);
  rig.scripted.Script(rig.left_device, 4, KernelEvent::kUnplug);
  ASSERT_EQ(rig.source->Start(), core::Status::kOk) << rig.source->LastError();
  core::Status s = core::Status::kOk;
  int cycles = 0;
  for (; cycles < 100 && s != core::Status::kDeviceLost; ++cycles) {
    s = rig.loop.Step();
    rig.output.DrainOnce();
  }
  rig.source->Stop();
  EXPECT_EQ(s, core::Status::kDeviceLost);
  EXPECT_EQ(rig.loop.Counters().cycles_missed, 21);  // 20 coasted, the 21st ends the run
  EXPECT_EQ(rig.loop.Counters().frames, 4);
  EXPECT_NE(std::strstr(rig.loop.SourceFault(), "/dev/video0"), nullptr) << rig.loop.SourceFault();
  EXPECT_EQ(rig.scripted.OpenFds(), 0);
  EXPECT_EQ(rig.scripted.MappedBuffers(), 0);
}

}  // namespace
}  // namespace swf::app
