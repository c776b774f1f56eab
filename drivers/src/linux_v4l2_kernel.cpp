#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

#include "swf/drivers/v4l2_kernel.hpp"

namespace swf::drivers {
namespace {

class LinuxKernel final : public V4l2Kernel {
 public:
  int Open(const char* path) override {
    const int fd = ::open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
    return fd < 0 ? -errno : fd;
  }
  int Close(int fd) override { return ::close(fd) < 0 ? -errno : 0; }
  int Ioctl(int fd, unsigned long request, void* arg) override {
    const int r = ::ioctl(fd, request, arg);
    return r < 0 ? -errno : r;
  }
  int Map(int fd, std::size_t length, std::int64_t offset, void** address) override {
    void* p = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
    if (p == MAP_FAILED) return -errno;
    *address = p;
    return 0;
  }
  int Unmap(void* address, std::size_t length) override {
    return ::munmap(address, length) < 0 ? -errno : 0;
  }
  int Poll(pollfd* fds, int count, int timeout_ms) override {
    const int r = ::poll(fds, static_cast<nfds_t>(count), timeout_ms);
    return r < 0 ? -errno : r;
  }
};

}  // namespace

V4l2Kernel& LinuxV4l2Kernel() {
  static LinuxKernel kernel;
  return kernel;
}

}  // namespace swf::drivers
