#include "swf/core/memory_use.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>

namespace swf::core {
namespace {

constexpr std::uint64_t kPaint = 0x5A5A'F00D'5A5A'F00DULL;
// Left unpainted below Paint's frame pointer: Paint's own locals and the painting loop's spills
// (well under 1 KiB at any optimization level) live there.
constexpr std::uintptr_t kFrameGap = 4096;
// Never painted above the stack's lowest address: the guard page and a margin.
constexpr std::uintptr_t kGuardMargin = 16384;

// The stack's lowest usable address for the calling thread, or 0 when unknown.
std::uintptr_t StackLow() {
  pthread_attr_t attr;
  if (pthread_getattr_np(pthread_self(), &attr) != 0) return 0;
  void* low = nullptr;
  std::size_t size = 0;
  const int rc = pthread_attr_getstack(&attr, &low, &size);
  (void)pthread_attr_destroy(&attr);
  return rc == 0 ? reinterpret_cast<std::uintptr_t>(low) : 0;
}

// Reads a small /proc file into buf (NUL-terminated) with plain syscalls: fopen would allocate.
bool ReadSmallFile(const char* path, char* buf, std::size_t size) {
  const int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  std::size_t used = 0;
  while (used + 1 < size) {
    const ssize_t n = read(fd, buf + used, size - 1 - used);
    if (n <= 0) break;
    used += static_cast<std::size_t>(n);
  }
  (void)close(fd);
  buf[used] = '\0';
  return used > 0;
}

// The number after `key` in /proc/self/status text (in kB there), or -1.
std::int64_t StatusField(const char* text, const char* key) {
  const char* at = std::strstr(text, key);
  if (at == nullptr) return -1;
  return std::strtoll(at + std::strlen(key), nullptr, 10);
}

}  // namespace

// The painting writes below the stack pointer on purpose; no sanitizer may see it as a bug.
__attribute__((noinline, no_sanitize("address", "undefined"))) void StackWatermark::Paint(
    std::size_t depth) {
  const std::uintptr_t frame = reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0));
  const std::uintptr_t top = (frame - kFrameGap) & ~std::uintptr_t{7};
  std::uintptr_t bottom = top > depth ? top - depth : 0;
  const std::uintptr_t low = StackLow();
  if (low == 0 || top <= low + kGuardMargin) return;  // unknown or too small a stack: no figure
  if (bottom < low + kGuardMargin) bottom = low + kGuardMargin;
  for (auto* p = reinterpret_cast<volatile std::uint64_t*>(bottom);
       p < reinterpret_cast<volatile std::uint64_t*>(top); ++p) {
    *p = kPaint;
  }
  origin_ = frame;
  bottom_ = bottom;
  depth_ = frame - bottom;
  measured_ = false;
}

__attribute__((noinline, no_sanitize("address", "undefined"))) void StackWatermark::Measure() {
  if (bottom_ == 0) return;
  const auto* p = reinterpret_cast<const volatile std::uint64_t*>(bottom_);
  const auto* top = reinterpret_cast<const volatile std::uint64_t*>(origin_ - kFrameGap);
  while (p < top && *p == kPaint) ++p;
  // Nothing below the gap was touched: the use is at most the gap.
  high_water_ = p < top ? origin_ - reinterpret_cast<std::uintptr_t>(p) : kFrameGap;
  measured_ = true;
}

ProcessMemory ReadProcessMemory() {
  ProcessMemory m;
  char text[4096];
  const long page = sysconf(_SC_PAGESIZE);
  if (!ReadSmallFile("/proc/self/statm", text, sizeof text) || page <= 0) return m;
  char* end = nullptr;
  (void)std::strtoll(text, &end, 10);  // total program size; resident follows
  m.resident_bytes = std::strtoll(end, nullptr, 10) * page;
  if (!ReadSmallFile("/proc/self/status", text, sizeof text)) return m;
  const std::int64_t hwm_kb = StatusField(text, "VmHWM:");
  if (hwm_kb < 0) return m;
  m.peak_resident_bytes = hwm_kb * 1024;
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return m;
  m.minor_faults = usage.ru_minflt;
  m.major_faults = usage.ru_majflt;
  m.valid = true;
  return m;
}

}  // namespace swf::core
