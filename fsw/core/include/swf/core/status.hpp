// Status: the result of every flight-code call that can fail for a reason other than a software
// bug. Bugs are SWF_ASSERT (assert.hpp); numerical health is reported as fault bits by the owner.
#pragma once

#include <cstdint>

namespace swf::core {

enum class [[nodiscard]] Status : std::uint8_t{
    kOk = 0,
    kInvalidArgument,   // a caller passed a value outside the documented range
    kNotConfigured,     // Configure() was not called, or failed
    kFull,              // a fixed-capacity container or pool has no free slot
    kEmpty,             // nothing to take
    kTimeout,           // a bounded wait expired without data
    kNotConverged,      // an iterative solve hit its iteration bound before its tolerance
    kNumericalFailure,  // a factorization or inversion failed (not positive definite, NaN, ...)
    kCorruptData,       // input from outside failed validation (message, log record, image)
    kIoError,           // the OS refused an I/O call (errno is in the caller's log line)
    kDeviceLost,        // a device disappeared (ENODEV, camera gone)
    kUnsupported,       // a valid request this build or device cannot serve
};

// A static string for logs and telemetry; never null.
const char* ToString(Status status);

// Convenience for `if (IsOk(s))` where a status is tested rather than propagated.
constexpr bool IsOk(Status status) { return status == Status::kOk; }

}  // namespace swf::core
