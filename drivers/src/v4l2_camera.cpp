#include "swf/drivers/v4l2_camera.hpp"

#include <linux/videodev2.h>

#include <cerrno>
#include <cstring>

namespace swf::drivers {
namespace {

// EINTR only means a signal arrived during the call: retry a few times, then let the caller's
// loop come back (bounded, so a signal storm cannot hang the flight loop).
constexpr int kEintrRetries = 4;

std::uint32_t FourccOf(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGray8: return V4L2_PIX_FMT_GREY;
    case PixelFormat::kGray16Le: return V4L2_PIX_FMT_Y16;
    case PixelFormat::kYuyv: return V4L2_PIX_FMT_YUYV;
  }
  return V4L2_PIX_FMT_GREY;
}

bool FormatOf(std::uint32_t fourcc, PixelFormat* format) {
  switch (fourcc) {
    case V4L2_PIX_FMT_GREY: *format = PixelFormat::kGray8; return true;
    case V4L2_PIX_FMT_Y16: *format = PixelFormat::kGray16Le; return true;
    case V4L2_PIX_FMT_YUYV: *format = PixelFormat::kYuyv; return true;
    default: return false;
  }
}

}  // namespace

core::Status V4l2Camera::Fail(int negative_errno) {
  last_errno_ = -negative_errno;
  if (last_errno_ == ENODEV || last_errno_ == ENOENT || last_errno_ == ENXIO) {
    return core::Status::kDeviceLost;
  }
  return core::Status::kIoError;
}

core::Status V4l2Camera::Open(const V4l2CameraOptions& options) {
  const core::Status status = OpenImpl(options);
  if (!core::IsOk(status)) {
    // Leave nothing half-open behind: a failed Open returns every buffer and the fd.
    const int saved_errno = last_errno_;
    Close();
    last_errno_ = saved_errno;
  }
  return status;
}

core::Status V4l2Camera::OpenImpl(const V4l2CameraOptions& options) {
  Close();
  last_errno_ = 0;
  if (options.buffer_count < 2 || options.buffer_count > kMaxBuffers || options.width <= 0 ||
      options.height <= 0) {
    return core::Status::kInvalidArgument;
  }
  const int fd = kernel_->Open(options.device);
  if (fd < 0) return Fail(fd);
  fd_ = fd;

  v4l2_capability cap{};
  int r = kernel_->Ioctl(fd_, VIDIOC_QUERYCAP, &cap);
  if (r < 0) return Fail(r);
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0 || (caps & V4L2_CAP_STREAMING) == 0) {
    return core::Status::kUnsupported;
  }

  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(options.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(options.height);
  fmt.fmt.pix.pixelformat = FourccOf(options.format);
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  r = kernel_->Ioctl(fd_, VIDIOC_S_FMT, &fmt);
  if (r < 0) return Fail(r);
  // S_FMT may answer another format or size than asked: take what we can convert, refuse the rest.
  PixelFormat actual;
  if (!FormatOf(fmt.fmt.pix.pixelformat, &actual) || fmt.fmt.pix.width == 0 ||
      fmt.fmt.pix.height == 0 || fmt.fmt.pix.width > 16384 || fmt.fmt.pix.height > 16384) {
    return core::Status::kUnsupported;
  }
  desc_.format = actual;
  desc_.width = static_cast<std::int32_t>(fmt.fmt.pix.width);
  desc_.height = static_cast<std::int32_t>(fmt.fmt.pix.height);
  const std::int32_t min_stride = desc_.width * BytesPerPixel(actual);
  desc_.stride_bytes = static_cast<std::int32_t>(fmt.fmt.pix.bytesperline) < min_stride
                           ? min_stride
                           : static_cast<std::int32_t>(fmt.fmt.pix.bytesperline);
  desc_.significant_bits = 16;

  // Controls are best effort on the auto mode (not every sensor has one) but an explicit value the
  // device refuses is a configuration error the operator must see.
  if (options.exposure_100us >= 0) {
    v4l2_control manual{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL};
    (void)kernel_->Ioctl(fd_, VIDIOC_S_CTRL, &manual);
    v4l2_control exposure{V4L2_CID_EXPOSURE_ABSOLUTE, options.exposure_100us};
    r = kernel_->Ioctl(fd_, VIDIOC_S_CTRL, &exposure);
    if (r < 0) return r == -EINVAL ? (last_errno_ = EINVAL, core::Status::kUnsupported) : Fail(r);
  }
  if (options.gain >= 0) {
    v4l2_control gain{V4L2_CID_GAIN, options.gain};
    r = kernel_->Ioctl(fd_, VIDIOC_S_CTRL, &gain);
    if (r < 0) return r == -EINVAL ? (last_errno_ = EINVAL, core::Status::kUnsupported) : Fail(r);
  }

  v4l2_requestbuffers req{};
  req.count = static_cast<std::uint32_t>(options.buffer_count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  r = kernel_->Ioctl(fd_, VIDIOC_REQBUFS, &req);
  if (r < 0) return Fail(r);
  // The driver may grant fewer (or more) buffers; fewer than two cannot stream.
  if (req.count < 2) return core::Status::kUnsupported;
  buffer_count_ = req.count > static_cast<std::uint32_t>(kMaxBuffers)
                      ? kMaxBuffers
                      : static_cast<std::int32_t>(req.count);
  for (std::int32_t i = 0; i < buffer_count_; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = static_cast<std::uint32_t>(i);
    r = kernel_->Ioctl(fd_, VIDIOC_QUERYBUF, &buf);
    if (r < 0) return Fail(r);
    void* address = nullptr;
    r = kernel_->Map(fd_, buf.length, buf.m.offset, &address);
    if (r < 0) return Fail(r);
    buffers_[i].address = address;
    buffers_[i].length = buf.length;
    if (buf.length < RequiredBytes(desc_)) return core::Status::kUnsupported;
  }
  for (std::int32_t i = 0; i < buffer_count_; ++i) {
    const core::Status s = Requeue(i);
    if (!core::IsOk(s)) return s;
  }
  return core::Status::kOk;
}

core::Status V4l2Camera::StreamOn() {
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  const int r = kernel_->Ioctl(fd_, VIDIOC_STREAMON, &type);
  if (r < 0) return Fail(r);
  streaming_ = true;
  return core::Status::kOk;
}

core::Status V4l2Camera::Dequeue(V4l2Frame* frame) {
  if (fd_ < 0 || !streaming_) return core::Status::kNotConfigured;
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  int r = -EINTR;
  for (int attempt = 0; attempt < kEintrRetries && r == -EINTR; ++attempt) {
    r = kernel_->Ioctl(fd_, VIDIOC_DQBUF, &buf);
  }
  if (r == -EAGAIN || r == -EINTR) return core::Status::kTimeout;
  if (r == -EIO) {
    last_errno_ = EIO;
    return core::Status::kCorruptData;
  }
  if (r < 0) return Fail(r);
  // Never trust the index the kernel (or a misbehaving driver) hands back.
  if (buf.index >= static_cast<std::uint32_t>(buffer_count_) || !buffers_[buf.index].queued) {
    last_errno_ = 0;
    return core::Status::kCorruptData;
  }
  Mapping& m = buffers_[buf.index];
  m.queued = false;
  frame->index = static_cast<std::int32_t>(buf.index);
  frame->data = static_cast<const std::uint8_t*>(m.address);
  frame->bytes_used = buf.bytesused > m.length ? m.length : buf.bytesused;
  frame->sequence = buf.sequence;
  frame->device_flagged_error = (buf.flags & V4L2_BUF_FLAG_ERROR) != 0;
  if ((buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    frame->timestamp_ns = static_cast<core::TimeNs>(buf.timestamp.tv_sec) * core::kNsPerS +
                          static_cast<core::TimeNs>(buf.timestamp.tv_usec) * core::kNsPerUs;
  } else {
    // No usable kernel stamp (TIMESTAMP_COPY/UNKNOWN): the dequeue time is the best we have.
    frame->timestamp_ns = core::MonotonicNs();
  }
  return core::Status::kOk;
}

core::Status V4l2Camera::Requeue(std::int32_t index) {
  if (fd_ < 0 || index < 0 || index >= buffer_count_) return core::Status::kInvalidArgument;
  if (buffers_[index].queued) return core::Status::kOk;
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  buf.index = static_cast<std::uint32_t>(index);
  int r = -EINTR;
  for (int attempt = 0; attempt < kEintrRetries && r == -EINTR; ++attempt) {
    r = kernel_->Ioctl(fd_, VIDIOC_QBUF, &buf);
  }
  if (r < 0) return Fail(r);
  buffers_[index].queued = true;
  return core::Status::kOk;
}

std::int32_t V4l2Camera::QueuedCount() const {
  std::int32_t n = 0;
  for (std::int32_t i = 0; i < buffer_count_; ++i) n += buffers_[i].queued ? 1 : 0;
  return n;
}

void V4l2Camera::Close() {
  if (fd_ < 0) return;
  // Errors are ignored on the way down: the device may already be gone, and every resource must
  // be returned regardless.
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)kernel_->Ioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (std::int32_t i = 0; i < buffer_count_; ++i) {
    if (buffers_[i].address != nullptr)
      (void)kernel_->Unmap(buffers_[i].address, buffers_[i].length);
    buffers_[i] = Mapping{};
  }
  if (buffer_count_ > 0) {
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    req.count = 0;
    (void)kernel_->Ioctl(fd_, VIDIOC_REQBUFS, &req);
  }
  buffer_count_ = 0;
  (void)kernel_->Close(fd_);
  fd_ = -1;
}

}  // namespace swf::drivers
