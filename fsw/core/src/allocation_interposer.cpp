// glibc lets an executable interpose malloc and friends; the real allocator stays reachable
// through the __libc_* entry points. operator new is replaced as the standard allows.
//
// Under AddressSanitizer (the debug preset) nothing is interposed: ASan must own the allocator
// to track every block, and an executable that replaced malloc with glibc's crashed during
// ASan's own start-up. ASan instead calls a hook on every allocation it serves (malloc, calloc,
// realloc, operator new), on the allocating thread, which counts the same events.
#include "swf/core/allocation_interposer.hpp"

#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define SWF_COUNT_THROUGH_ASAN_HOOKS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SWF_COUNT_THROUGH_ASAN_HOOKS 1
#endif
#endif

#ifdef SWF_COUNT_THROUGH_ASAN_HOOKS
// Exported by the sanitizer runtime (sanitizer/allocator_interface.h, not shipped by GCC 12).
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*,
                                                                             std::size_t),
                                                         void (*free_hook)(const volatile void*));

namespace {
void OnAsanMalloc(const volatile void* /*p*/, std::size_t /*size*/) { swf::core::NoteAllocation(); }
void OnAsanFree(const volatile void* /*p*/) {}
// Installed before main, so it also sees allocations of static constructors that run later.
[[maybe_unused]] const int g_hooks_installed =
    __sanitizer_install_malloc_and_free_hooks(OnAsanMalloc, OnAsanFree);
}  // namespace

#else

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* p);
}

using swf::core::NoteAllocation;

extern "C" {
void* malloc(std::size_t size) {
  NoteAllocation();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  NoteAllocation();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  NoteAllocation();
  return __libc_realloc(p, size);
}
void free(void* p) { __libc_free(p); }
}

void* operator new(std::size_t size) {
  NoteAllocation();
  void* p = __libc_malloc(size == 0 ? 1 : size);
  if (p == nullptr) std::abort();
  return p;
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  NoteAllocation();
  return __libc_malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void* operator new(std::size_t size, std::align_val_t align) {
  NoteAllocation();
  void* p = __libc_memalign(static_cast<std::size_t>(align), size == 0 ? 1 : size);
  if (p == nullptr) std::abort();
  return p;
}
void* operator new[](std::size_t size, std::align_val_t align) { return operator new(size, align); }
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  NoteAllocation();
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
