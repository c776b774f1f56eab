// One V4L2 capture device in mmap streaming mode with a fixed number of driver buffers. Used by
// V4l2StereoSource (two devices, or one side-by-side stereo device). All kernel calls go through
// a V4l2Kernel so tests can script the device.
#pragma once

#include <cstddef>
#include <cstdint>

#include "swf/core/status.hpp"
#include "swf/core/time.hpp"
#include "swf/drivers/image_format.hpp"
#include "swf/drivers/v4l2_kernel.hpp"

namespace swf::drivers {

struct V4l2CameraOptions {
  const char* device = "/dev/video0";
  std::int32_t width = 640;
  std::int32_t height = 480;
  PixelFormat format = PixelFormat::kGray8;  // requested; the driver may answer another one
  std::int32_t buffer_count = 4;             // driver buffers (VIDIOC_REQBUFS)
  std::int32_t exposure_100us = -1;          // V4L2_CID_EXPOSURE_ABSOLUTE; < 0 leaves it alone
  std::int32_t gain = -1;                    // V4L2_CID_GAIN; < 0 leaves it alone
};

// A dequeued driver buffer. Valid until Requeue(index).
struct V4l2Frame {
  std::int32_t index = -1;
  const std::uint8_t* data = nullptr;
  std::size_t bytes_used = 0;
  core::TimeNs timestamp_ns = 0;  // kernel time stamp (CLOCK_MONOTONIC) when the driver has one
  std::uint32_t sequence = 0;
  bool device_flagged_error = false;  // V4L2_BUF_FLAG_ERROR: the data is corrupt
};

class V4l2Camera {
 public:
  static constexpr std::int32_t kMaxBuffers = 16;

  explicit V4l2Camera(V4l2Kernel& kernel) : kernel_(&kernel) {}
  ~V4l2Camera() { Close(); }
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  // Opens the device, negotiates the format, sets controls, maps and queues the buffers.
  // kUnsupported when the device cannot stream or answers a format we cannot convert;
  // kDeviceLost when the node is missing; kIoError otherwise. Desc() tells what was negotiated.
  core::Status Open(const V4l2CameraOptions& options);
  core::Status StreamOn();

  // Non-blocking. kOk with a frame; kTimeout when none is ready (EAGAIN, or EINTR repeatedly);
  // kCorruptData when the driver reported EIO for this dequeue (no buffer was taken, streaming
  // goes on); kDeviceLost on ENODEV; kIoError for anything else.
  core::Status Dequeue(V4l2Frame* frame);
  core::Status Requeue(std::int32_t index);

  // Stops streaming, unmaps, frees the driver buffers and closes. Safe to call repeatedly and
  // after the device vanished.
  void Close();

  int Fd() const { return fd_; }
  bool Streaming() const { return streaming_; }
  const SourceImageDesc& Desc() const { return desc_; }
  // The last errno a kernel call returned (0 if none), for log lines.
  int LastErrno() const { return last_errno_; }
  std::int32_t QueuedCount() const;
  std::int32_t BufferCount() const { return buffer_count_; }

 private:
  core::Status OpenImpl(const V4l2CameraOptions& options);
  core::Status Fail(int negative_errno);

  struct Mapping {
    void* address = nullptr;
    std::size_t length = 0;
    bool queued = false;
  };

  V4l2Kernel* kernel_;
  int fd_ = -1;
  bool streaming_ = false;
  int last_errno_ = 0;
  SourceImageDesc desc_;
  Mapping buffers_[kMaxBuffers];
  std::int32_t buffer_count_ = 0;
};

}  // namespace swf::drivers
