#include "scripted_v4l2_kernel.hpp"

#include <cerrno>
#include <cstring>

namespace swf::drivers::testing {

int ScriptedV4l2Kernel::AddDevice(const ScriptedDevice& device) {
  State s;
  s.config = device;
  s.script.reserve(64);
  devices_.push_back(std::move(s));
  return static_cast<int>(devices_.size()) - 1;
}

void ScriptedV4l2Kernel::Script(int device, int dqbuf_call, KernelEvent event, std::int64_t arg) {
  devices_[device].script.push_back(Scripted{dqbuf_call, event, arg});
}

void ScriptedV4l2Kernel::Replug(int device) {
  State& d = devices_[device];
  d.gone = false;
  d.script.clear();
}

ScriptedV4l2Kernel::State* ScriptedV4l2Kernel::FromFd(int fd) {
  const int i = fd - kFdBase;
  if (i < 0 || i >= static_cast<int>(devices_.size()) || !devices_[i].open) return nullptr;
  return &devices_[i];
}

int ScriptedV4l2Kernel::OpenFds() const {
  int n = 0;
  for (const State& d : devices_) n += d.open ? 1 : 0;
  return n;
}

int ScriptedV4l2Kernel::Open(const char* path) {
  for (std::size_t i = 0; i < devices_.size(); ++i) {
    State& d = devices_[i];
    if (d.config.path != path) continue;
    if (d.gone) return -ENOENT;
    if (d.open) return -EBUSY;
    d.open = true;
    d.streaming = false;
    d.buffers.clear();
    d.state.clear();
    d.fifo.clear();
    d.fifo_head = d.fifo_count = 0;
    d.sequence = 0;
    d.time_shift_ns = 0;
    d.dqbuf_calls = 0;
    d.eintr_left = 0;
    return kFdBase + static_cast<int>(i);
  }
  return -ENOENT;
}

int ScriptedV4l2Kernel::Close(int fd) {
  State* d = FromFd(fd);
  if (d == nullptr) return -EBADF;
  // Like the kernel: closing the last handle stops streaming and frees buffers not mapped.
  d->open = false;
  d->streaming = false;
  return 0;
}

int ScriptedV4l2Kernel::Map(int fd, std::size_t length, std::int64_t offset, void** address) {
  State* d = FromFd(fd);
  if (d == nullptr) return -EBADF;
  if (d->gone) return -ENODEV;
  const std::size_t index = static_cast<std::size_t>(offset) / 4096;
  if (index >= d->buffers.size() || length > d->buffers[index].size()) return -EINVAL;
  *address = d->buffers[index].data();
  ++mapped_;
  return 0;
}

int ScriptedV4l2Kernel::Unmap(void* address, std::size_t /*length*/) {
  if (address == nullptr) return -EINVAL;
  --mapped_;
  return 0;
}

int ScriptedV4l2Kernel::Poll(pollfd* fds, int count, int /*timeout_ms*/) {
  // No real waiting: a device with a queued buffer always has a frame "about to" arrive.
  if (poll_eintr_left_ > 0) {
    --poll_eintr_left_;
    return -EINTR;
  }
  int ready = 0;
  for (int i = 0; i < count; ++i) {
    fds[i].revents = 0;
    State* d = FromFd(fds[i].fd);
    if (d == nullptr) {
      fds[i].revents = POLLNVAL;
    } else if (d->gone) {
      fds[i].revents = POLLERR;
    } else if (d->streaming && !d->stalled && d->fifo_count > 0) {
      fds[i].revents = POLLIN;
    }
    ready += fds[i].revents != 0 ? 1 : 0;
  }
  return ready;
}

void ScriptedV4l2Kernel::FillFrame(State& d, std::uint8_t* data, std::uint32_t value) {
  const std::uint8_t v = static_cast<std::uint8_t>(value & 0xFF);
  for (std::uint32_t r = 0; r < d.config.height; ++r) {
    std::uint8_t* row = data + static_cast<std::size_t>(r) * d.stride;
    for (std::uint32_t c = 0; c < d.config.width; ++c) {
      switch (d.fourcc) {
        case V4L2_PIX_FMT_Y16:
          row[2 * c] = 0x34;  // low byte: must be dropped by the conversion
          row[2 * c + 1] = v;
          break;
        case V4L2_PIX_FMT_YUYV:
          row[2 * c] = v;
          row[2 * c + 1] = 128;
          break;
        default: row[c] = v; break;
      }
    }
  }
}

int ScriptedV4l2Kernel::Dqbuf(State& d, v4l2_buffer* buf) {
  if (d.eintr_left > 0) {
    --d.eintr_left;
    return -EINTR;
  }
  const int call = d.dqbuf_calls++;
  bool error_flag = false;
  bool short_frame = false;
  for (const Scripted& s : d.script) {
    if (s.call != call) continue;
    switch (s.event) {
      case KernelEvent::kEagain: return -EAGAIN;
      case KernelEvent::kEintr: d.eintr_left = static_cast<int>(s.arg) - 1; return -EINTR;
      case KernelEvent::kEio: return -EIO;
      case KernelEvent::kUnplug: d.gone = true; return -ENODEV;
      case KernelEvent::kErrorFlag: error_flag = true; break;
      case KernelEvent::kLoseFrames: d.sequence += static_cast<std::uint32_t>(s.arg); break;
      case KernelEvent::kShortFrame: short_frame = true; break;
      case KernelEvent::kTimeShift: d.time_shift_ns += s.arg; break;
    }
  }
  if (!d.streaming || d.stalled || d.fifo_count == 0) return -EAGAIN;
  const int index = d.fifo[d.fifo_head];
  d.fifo_head = (d.fifo_head + 1) % d.fifo.size();
  --d.fifo_count;
  d.state[index] = 0;
  const std::uint32_t seq = d.sequence++;
  FillFrame(d, d.buffers[index].data(), seq);
  const core::TimeNs t_ns = d.config.first_timestamp_ns + d.time_shift_ns +
                            static_cast<core::TimeNs>(seq) * d.config.period_ns;
  std::memset(buf, 0, sizeof(*buf));
  buf->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf->memory = V4L2_MEMORY_MMAP;
  buf->index = static_cast<std::uint32_t>(index);
  buf->sequence = seq;
  buf->bytesused = short_frame ? d.image_bytes / 2 : d.image_bytes;
  buf->length = static_cast<std::uint32_t>(d.buffers[index].size());
  buf->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_DONE |
               (error_flag ? V4L2_BUF_FLAG_ERROR : 0u);
  buf->timestamp.tv_sec = t_ns / core::kNsPerS;
  buf->timestamp.tv_usec = (t_ns % core::kNsPerS) / core::kNsPerUs;
  buf->m.offset = static_cast<std::uint32_t>(index) * 4096;
  return 0;
}

int ScriptedV4l2Kernel::Ioctl(int fd, unsigned long request, void* arg) {
  State* dp = FromFd(fd);
  if (dp == nullptr) return -EBADF;
  State& d = *dp;
  if (d.gone) return -ENODEV;
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* cap = static_cast<v4l2_capability*>(arg);
      std::memset(cap, 0, sizeof(*cap));
      std::strncpy(reinterpret_cast<char*>(cap->driver), "scripted", sizeof(cap->driver) - 1);
      cap->device_caps = V4L2_CAP_VIDEO_CAPTURE | (d.config.can_stream ? V4L2_CAP_STREAMING : 0u);
      cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_S_FMT: {
      if (!d.buffers.empty()) return -EBUSY;
      auto* f = static_cast<v4l2_format*>(arg);
      bool supported = false;
      for (std::uint32_t c : d.config.formats) supported = supported || c == f->fmt.pix.pixelformat;
      d.fourcc = supported ? f->fmt.pix.pixelformat : d.config.formats[0];
      const std::uint32_t bpp = d.fourcc == V4L2_PIX_FMT_GREY ? 1 : 2;
      d.stride = d.config.width * bpp + d.config.row_padding_bytes;
      d.image_bytes = d.stride * d.config.height;
      f->fmt.pix.pixelformat = d.fourcc;
      f->fmt.pix.width = d.config.width;  // a sensor answers its own size
      f->fmt.pix.height = d.config.height;
      f->fmt.pix.bytesperline = d.stride;
      f->fmt.pix.sizeimage = d.image_bytes;
      return 0;
    }
    case VIDIOC_S_CTRL: {
      auto* c = static_cast<v4l2_control*>(arg);
      if (!d.config.has_exposure_control &&
          (c->id == V4L2_CID_EXPOSURE_ABSOLUTE || c->id == V4L2_CID_EXPOSURE_AUTO)) {
        return -EINVAL;
      }
      if (c->id == V4L2_CID_EXPOSURE_ABSOLUTE) d.exposure = c->value;
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* r = static_cast<v4l2_requestbuffers*>(arg);
      if (d.streaming) return -EBUSY;
      if (r->count > 0 && mapped_ > 0 && !d.buffers.empty()) return -EBUSY;
      d.buffers.assign(r->count, std::vector<std::uint8_t>(d.image_bytes));
      d.state.assign(r->count, 0);
      d.fifo.assign(r->count, 0);
      d.fifo_head = d.fifo_count = 0;
      return 0;
    }
    case VIDIOC_QUERYBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= d.buffers.size()) return -EINVAL;
      b->length = static_cast<std::uint32_t>(d.buffers[b->index].size());
      b->m.offset = b->index * 4096;
      return 0;
    }
    case VIDIOC_QBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= d.buffers.size() || d.state[b->index] == 1) return -EINVAL;
      d.state[b->index] = 1;
      d.fifo[(d.fifo_head + d.fifo_count) % d.fifo.size()] = static_cast<int>(b->index);
      ++d.fifo_count;
      return 0;
    }
    case VIDIOC_DQBUF: return Dqbuf(d, static_cast<v4l2_buffer*>(arg));
    case VIDIOC_STREAMON: d.streaming = true; return 0;
    case VIDIOC_STREAMOFF:
      d.streaming = false;
      // STREAMOFF returns every queued buffer to the user.
      for (int& s : d.state) s = 0;
      d.fifo_head = d.fifo_count = 0;
      return 0;
    default: return -ENOTTY;
  }
}

}  // namespace swf::drivers::testing
