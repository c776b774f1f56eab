// SWF_ASSERT: guards software invariants only (never sensor data or hardware results, which are
// Status values). The handler is replaceable so a flight build can log and safe the vehicle and a
// test can observe the failure. The expression is evaluated in every build type.
#pragma once

namespace swf::core {

// Called with the failing expression's text and location. Must not return normally in flight
// builds; the default prints to stderr and calls std::abort().
using AssertHandler = void (*)(const char* expression, const char* file, int line);

// Installs a handler and returns the previous one. Passing nullptr restores the default.
AssertHandler SetAssertHandler(AssertHandler handler);

// Invokes the installed handler. If a (test) handler returns, execution continues after the
// assertion, so callers must not rely on it for memory safety beyond the check itself.
void AssertFailed(const char* expression, const char* file, int line);

}  // namespace swf::core

#define SWF_ASSERT(condition)                                    \
  do {                                                           \
    if (!(condition)) [[unlikely]] {                             \
      ::swf::core::AssertFailed(#condition, __FILE__, __LINE__); \
    }                                                            \
  } while (false)
