// A scripted V4L2 kernel for tests: models the mmap streaming buffer cycle (REQBUFS, QUERYBUF,
// mmap, QBUF, STREAMON, DQBUF, STREAMOFF) of a few capture devices and injects the errors a real
// driver produces (EAGAIN, EINTR, EIO, V4L2_BUF_FLAG_ERROR, lost frames, unplug) at chosen
// dequeue calls. Frames are produced on demand: each DQBUF on a streaming device with a queued
// buffer fills the oldest queued buffer with the next frame (pixel value = sequence & 0xFF), so
// tests need no threads or sleeps. Never allocates after REQBUFS.
#pragma once

#include <linux/videodev2.h>

#include <cstdint>
#include <string>
#include <vector>

#include "swf/core/time.hpp"
#include "swf/drivers/v4l2_kernel.hpp"

namespace swf::drivers::testing {

enum class KernelEvent : std::uint8_t {
  kEagain,      // DQBUF: nothing ready
  kEintr,       // DQBUF: interrupted (arg times in a row)
  kEio,         // DQBUF: -EIO, no buffer taken
  kErrorFlag,   // DQBUF: a frame flagged V4L2_BUF_FLAG_ERROR
  kLoseFrames,  // the sensor lost arg frames before this one (sequence jumps)
  kShortFrame,  // bytesused is half the image
  kTimeShift,   // from this frame on, time stamps move by arg nanoseconds
  kUnplug,      // ENODEV from now on (poll reports POLLERR)
};

struct ScriptedDevice {
  std::string path;
  std::uint32_t width = 64;
  std::uint32_t height = 48;
  std::vector<std::uint32_t> formats = {V4L2_PIX_FMT_GREY};  // S_FMT answers formats[0] otherwise
  std::uint32_t row_padding_bytes = 0;
  core::TimeNs first_timestamp_ns = 1'000'000'000;
  core::TimeNs period_ns = 50'000'000;
  bool can_stream = true;
  bool has_exposure_control = true;
};

class ScriptedV4l2Kernel final : public V4l2Kernel {
 public:
  static constexpr int kFdBase = 100;

  // Adds a device; returns its id (index).
  int AddDevice(const ScriptedDevice& device);
  // Injects an event at the n-th (0-based) DQBUF call on a device.
  void Script(int device, int dqbuf_call, KernelEvent event, std::int64_t arg = 0);
  // A stalled device delivers nothing (poll times out, DQBUF says EAGAIN) until un-stalled.
  void SetStalled(int device, bool stalled) { devices_[device].stalled = stalled; }
  // The next n Poll() calls fail with EINTR (a signal arrived while waiting).
  void InjectPollEintr(int n) { poll_eintr_left_ = n; }
  int PollEintrLeft() const { return poll_eintr_left_; }
  // A device that was unplugged comes back (a fresh Open works again).
  void Replug(int device);

  int Open(const char* path) override;
  int Close(int fd) override;
  int Ioctl(int fd, unsigned long request, void* arg) override;
  int Map(int fd, std::size_t length, std::int64_t offset, void** address) override;
  int Unmap(void* address, std::size_t length) override;
  int Poll(pollfd* fds, int count, int timeout_ms) override;

  // Resources the driver under test still holds, for leak checks.
  int OpenFds() const;
  int MappedBuffers() const { return mapped_; }
  bool Streaming(int device) const { return devices_[device].streaming; }
  std::int32_t LastExposure(int device) const { return devices_[device].exposure; }
  int DqbufCalls(int device) const { return devices_[device].dqbuf_calls; }

 private:
  struct Scripted {
    int call;
    KernelEvent event;
    std::int64_t arg;
  };
  struct State {
    ScriptedDevice config;
    bool open = false;
    bool gone = false;
    bool streaming = false;
    bool stalled = false;
    std::uint32_t fourcc = 0;
    std::uint32_t stride = 0;
    std::uint32_t image_bytes = 0;
    std::vector<std::vector<std::uint8_t>> buffers;
    std::vector<int> state;  // 0 = user, 1 = queued
    std::vector<int> fifo;   // queued order (ring)
    std::size_t fifo_head = 0;
    std::size_t fifo_count = 0;
    std::uint32_t sequence = 0;
    core::TimeNs time_shift_ns = 0;
    int dqbuf_calls = 0;
    int eintr_left = 0;
    std::int32_t exposure = -1;
    std::vector<Scripted> script;
  };
  State* FromFd(int fd);
  int Dqbuf(State& d, v4l2_buffer* buf);
  void FillFrame(State& d, std::uint8_t* data, std::uint32_t value);

  std::vector<State> devices_;
  int mapped_ = 0;
  int poll_eintr_left_ = 0;
};

}  // namespace swf::drivers::testing
