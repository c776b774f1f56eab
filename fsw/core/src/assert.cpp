#include "swf/core/assert.hpp"

#include <atomic>
#include <cstdio>
#include <cstdlib>

namespace swf::core {
namespace {

void DefaultAssertHandler(const char* expression, const char* file, int line) {
  std::fprintf(stderr, "SWF_ASSERT failed: %s at %s:%d\n", expression, file, line);
  std::abort();
}

std::atomic<AssertHandler> g_handler{&DefaultAssertHandler};

}  // namespace

AssertHandler SetAssertHandler(AssertHandler handler) {
  return g_handler.exchange(handler != nullptr ? handler : &DefaultAssertHandler);
}

void AssertFailed(const char* expression, const char* file, int line) {
  g_handler.load()(expression, file, line);
}

}  // namespace swf::core
