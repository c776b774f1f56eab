// The seam between the V4L2 driver and the kernel. Every system call the driver makes goes
// through this interface so tests can script the kernel (this machine has no video devices and
// cannot load vivid or v4l2loopback). Calls return >= 0 on success and -errno on failure, so a
// fake never has to touch the thread's errno.
#pragma once

#include <poll.h>

#include <cstddef>
#include <cstdint>

namespace swf::drivers {

class V4l2Kernel {
 public:
  virtual ~V4l2Kernel() = default;
  // Opens a capture node read-write and non-blocking: returns the fd.
  virtual int Open(const char* path) = 0;
  virtual int Close(int fd) = 0;
  virtual int Ioctl(int fd, unsigned long request, void* arg) = 0;
  // Maps a driver buffer (offset from VIDIOC_QUERYBUF) shared read-write into *address.
  virtual int Map(int fd, std::size_t length, std::int64_t offset, void** address) = 0;
  virtual int Unmap(void* address, std::size_t length) = 0;
  // Returns the number of ready fds, 0 on timeout.
  virtual int Poll(pollfd* fds, int count, int timeout_ms) = 0;
};

// The real kernel (open/ioctl/mmap/poll on /dev/video*). A process-wide object without state.
V4l2Kernel& LinuxV4l2Kernel();

}  // namespace swf::drivers
