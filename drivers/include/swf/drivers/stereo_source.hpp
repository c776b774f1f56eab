// StereoSource: the one interface through which the flight loop receives stereo pairs, whatever
// produces them (V4L2 cameras, GigE Vision cameras, the simulator, an LCM log). Depends on
// fsw/core only.
//
// Life cycle: construct -> Configure(options of the implementation) -> Start() -> repeatedly
// Next() / Release() -> Stop(). Images live in buffers the source owns (a fixed pool allocated
// before Start); a pair stays valid until it is released and must be released exactly once.
// Next() and Release() never allocate.
#pragma once

#include <cstdint>

#include "swf/core/image_view.hpp"
#include "swf/core/status.hpp"
#include "swf/core/time.hpp"

namespace swf::drivers {

struct StereoPair {
  // Read-only 8-bit gray images in buffers the source owns.
  core::ImageView<const std::uint8_t> left;
  core::ImageView<const std::uint8_t> right;
  core::TimeNs left_exposure_ns = 0;  // exposure time stamp (monotonic clock), nanoseconds
  core::TimeNs right_exposure_ns = 0;
  std::uint64_t seq = 0;             // +1 per pair served, starting at 0
  std::uint32_t dropped_before = 0;  // pairs lost between the previous pair and this one
  std::int32_t handle = -1;          // the source's buffer handle, for Release()
};

// Counters every source keeps (the flight process copies them into health_t).
struct SourceStats {
  std::uint64_t pairs_served = 0;
  std::uint64_t frames_dropped = 0;    // frames the source or the device lost
  std::uint64_t frames_rejected = 0;   // frames received but bad (incomplete, wrong size, ...)
  std::uint64_t pairing_failures = 0;  // frames with no partner within the pairing tolerance
  std::uint64_t timeouts = 0;
  std::uint64_t missing_packets = 0;  // GigE frames with packets missing (in frames_rejected too)
};

class StereoSource {
 public:
  virtual ~StereoSource() = default;

  // Starts acquisition. Everything the source needs is allocated before this returns.
  virtual core::Status Start() = 0;

  // Waits at most timeout_ns for the next pair. kOk fills *pair; kTimeout when none arrived;
  // kDeviceLost / kIoError when the device failed (the caller may Stop() and Start() again);
  // kEmpty when a finite source (log, scenario) has no more pairs.
  virtual core::Status Next(core::TimeNs timeout_ns, StereoPair* pair) = 0;

  // Returns the pair's buffers to the source.
  virtual void Release(const StereoPair& pair) = 0;

  virtual void Stop() = 0;

  virtual SourceStats Stats() const = 0;

  // A short static name for logs ("v4l2", "aravis", "sim", "log").
  virtual const char* Name() const = 0;

  // Why the last call failed, naming the device and the cause (never null; "" when the source
  // has nothing to say). Valid until the next call on the source.
  virtual const char* LastError() const { return ""; }
};

}  // namespace swf::drivers
