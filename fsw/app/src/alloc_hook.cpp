// The flight binary's allocation counter: glibc lets an executable interpose malloc and its
// relatives (the real allocator stays reachable through __libc_*), and operator new is
// replaceable. Only threads marked real-time are counted, so the output thread's LCM and file
// I/O do not hide a real-time allocation or raise a false one.
// Under AddressSanitizer nothing is interposed (ASan must own the allocator; interposing glibc's
// crashed programs during ASan's start-up): ASan's allocation hook, which runs on the allocating
// thread, counts instead (same scheme as tests/support's counter).
#include <atomic>
#include <cstdlib>
#include <new>

#include "swf/app/alloc_meter.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define SWF_COUNT_THROUGH_ASAN_HOOKS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SWF_COUNT_THROUGH_ASAN_HOOKS 1
#endif
#endif

#ifndef SWF_COUNT_THROUGH_ASAN_HOOKS
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* p);
}
#endif

namespace {
thread_local bool t_realtime = false;
std::atomic<std::int64_t> g_realtime_allocations{0};

inline void Note() {
  if (t_realtime) g_realtime_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

namespace swf::app {
void BeginRealtimeAllocationCounting() { t_realtime = true; }
std::int64_t RealtimeAllocations() { return g_realtime_allocations.load(); }
}  // namespace swf::app

#ifdef SWF_COUNT_THROUGH_ASAN_HOOKS
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*,
                                                                             std::size_t),
                                                         void (*free_hook)(const volatile void*));

namespace {
void OnAsanMalloc(const volatile void* /*p*/, std::size_t /*size*/) { Note(); }
void OnAsanFree(const volatile void* /*p*/) {}
[[maybe_unused]] const int g_hooks_installed =
    __sanitizer_install_malloc_and_free_hooks(OnAsanMalloc, OnAsanFree);
}  // namespace
#else
extern "C" {
void* malloc(std::size_t size) {
  Note();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  Note();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  Note();
  return __libc_realloc(p, size);
}
void free(void* p) { __libc_free(p); }
}

void* operator new(std::size_t size) {
  Note();
  void* p = __libc_malloc(size == 0 ? 1 : size);
  if (p == nullptr) std::abort();
  return p;
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  Note();
  return __libc_malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void* operator new(std::size_t size, std::align_val_t align) {
  Note();
  void* p = __libc_memalign(static_cast<std::size_t>(align), size == 0 ? 1 : size);
  if (p == nullptr) std::abort();
  return p;
}
void* operator new[](std::size_t size, std::align_val_t align) { return operator new(size, align); }
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  Note();
  return __libc_memalign(static_cast<std::size_t>(align), size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, std::align_val_t align, const std::nothrow_t& t) noexcept {
  return operator new(size, align, t);
}
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
#endif  // SWF_COUNT_THROUGH_ASAN_HOOKS
