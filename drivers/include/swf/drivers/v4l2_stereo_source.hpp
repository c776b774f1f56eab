// StereoSource over V4L2: two capture devices, or one device that delivers the two views side by
// side in one frame. Pairs left and right frames by kernel time stamp within a tolerance, counts
// frames the kernel lost (sequence gaps), rejects corrupt frames and hands out 8-bit gray views.
//
// Copies: a GREY device's buffers are handed to the caller in place (the driver buffer stays
// dequeued until Release); Y16 and YUYV frames are converted into pair slots allocated at Start()
// and the driver buffer goes back to the kernel at once.
#pragma once

#include <cstdint>
#include <memory>

#include "swf/drivers/pairing.hpp"
#include "swf/drivers/stereo_source.hpp"
#include "swf/drivers/v4l2_camera.hpp"

namespace swf::drivers {

struct V4l2StereoOptions {
  V4l2CameraOptions left;
  V4l2CameraOptions right;    // ignored when side_by_side
  bool side_by_side = false;  // left.device delivers [left | right] in one frame of 2 x width
  core::TimeNs pair_tolerance_ns = 2 * core::kNsPerMs;
  std::int32_t max_pairs_held = 2;  // pairs the caller may hold at once (Next gives kFull beyond)
  // Consecutive EIO dequeues tolerated as transient before Next reports kIoError.
  std::int32_t max_consecutive_io_errors = 3;
};

class V4l2StereoSource final : public StereoSource {
 public:
  static constexpr std::int32_t kMaxPairsHeld = 8;

  explicit V4l2StereoSource(V4l2Kernel& kernel = LinuxV4l2Kernel());
  ~V4l2StereoSource() override;

  // Validates options (no device access). kInvalidArgument with LastError() on bad options.
  core::Status Configure(const V4l2StereoOptions& options);

  core::Status Start() override;
  core::Status Next(core::TimeNs timeout_ns, StereoPair* pair) override;
  void Release(const StereoPair& pair) override;
  void Stop() override;
  SourceStats Stats() const override { return stats_; }
  const char* Name() const override { return "v4l2"; }

  // The reason of the last failure (never null): device, call and errno, or the device that has
  // been silent when Next() timed out.
  const char* LastError() const override { return last_error_; }
  // Driver buffers currently dequeued and not yet returned (for tests and health).
  std::int32_t BuffersOutstanding() const;

 private:
  enum Side { kLeft = 0, kRight = 1 };
  struct Held {
    bool valid = false;
    V4l2Frame frame;
  };
  struct Slot {
    bool in_use = false;
    std::int32_t left_index = -1;  // driver buffers kept for a zero-copy pair, else -1
    std::int32_t right_index = -1;
    std::unique_ptr<std::uint8_t[]> left_gray;  // conversion targets, allocated by Start()
    std::unique_ptr<std::uint8_t[]> right_gray;
  };

  int SideCount() const { return options_.side_by_side ? 1 : 2; }
  V4l2Camera& Camera(int side) {
    return options_.side_by_side ? left_ : (side == 0 ? left_ : right_);
  }
  core::Status Error(core::Status status, const char* what, const V4l2Camera& camera);
  // Dequeues one frame for a side if one is ready; kOk also when nothing was ready.
  core::Status Fill(int side);
  void Discard(int side);
  core::Status WaitReadable(core::TimeNs remaining_ns);
  core::Status Emit(Slot& slot, std::int32_t slot_index, StereoPair* pair);
  // Names the device(s) silent the longest in LastError() when Next() times out.
  void NameSilentDevice();

  V4l2Kernel* kernel_;
  V4l2Camera left_;
  V4l2Camera right_;
  V4l2StereoOptions options_;
  bool configured_ = false;
  bool started_ = false;
  Held held_[2];
  SequenceTracker sequence_[2];
  PairNumbering numbering_;
  std::int32_t consecutive_io_errors_[2] = {0, 0};
  core::TimeNs last_frame_ns_[2] = {0, 0};  // when each side last dequeued anything
  Slot slots_[kMaxPairsHeld];
  SourceStats stats_;
  char last_error_[200] = "";
};

}  // namespace swf::drivers
