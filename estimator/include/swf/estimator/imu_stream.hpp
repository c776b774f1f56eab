// ImuStreamChecker: the gate every IMU sample passes before it is integrated. A real sensor
// stream arrives reordered, repeated, with holes and with clipped values; none of that may crash
// or block the frame group, and each kind is counted for health_t. What it does with each:
//   out of order   (time before the last sample's)        dropped: its place has been integrated
//   duplicate      (same time as the last sample)          dropped: nothing new
//   invalid        (VALID flag clear or a non-finite value) dropped
//   saturated      (flag set, or |axis| >= the range)      dropped: the clipped value is wrong
//   gap            (more than max_gap_periods periods since the last sample, or a jump in seq)
//                   accepted and marked: the integrator bridges the hole by holding the signal
//                   (PreintegrateInterval counts the stretched step), the caller may degrade
// Dropped samples leave a hole of one period that the integrator bridges the same way. The
// samples that pass have strictly increasing times, which PreintegrateInterval requires.
//
// Flight code: no allocation, constant work per sample.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "swf/core/status.hpp"
#include "swf/estimator/imu_preintegration.hpp"

namespace swf::estimator {

enum class ImuSampleVerdict : std::uint8_t {
  kAccepted = 0,
  kAcceptedAfterGap,  // accepted; samples are missing before it
  kDroppedOutOfOrder,
  kDroppedDuplicate,
  kDroppedInvalid,
  kDroppedSaturated,
};

constexpr bool IsAccepted(ImuSampleVerdict v) {
  return v == ImuSampleVerdict::kAccepted || v == ImuSampleVerdict::kAcceptedAfterGap;
}

template <typename S>
struct ImuStreamOptions {
  std::int64_t nominal_period_us = 5000;  // 1 / rate (200 Hz)
  // A step longer than this many nominal periods means samples were lost.
  int max_gap_periods = 3;
  // Ranges of the sensor (0: trust the flags only). A value at the range is taken as clipped.
  S gyro_range_radps = S(0);
  S accel_range_mps2 = S(0);

  bool Valid() const {
    return nominal_period_us > 0 && max_gap_periods >= 1 && gyro_range_radps >= S(0) &&
           accel_range_mps2 >= S(0);
  }
};

// Counts since Configure(); each sample lands in exactly one of accepted or a dropped kind.
struct ImuStreamCounts {
  std::int64_t accepted = 0;
  std::int64_t out_of_order = 0;
  std::int64_t duplicated = 0;
  std::int64_t invalid = 0;
  std::int64_t saturated = 0;
  std::int64_t gaps = 0;             // accepted samples that followed a hole
  std::int64_t missing_samples = 0;  // estimated samples lost in those holes
};

template <typename S>
class ImuStreamChecker {
 public:
  core::Status Configure(const ImuStreamOptions<S>& options) {
    if (!options.Valid()) return core::Status::kInvalidArgument;
    options_ = options;
    counts_ = ImuStreamCounts{};
    has_last_ = false;
    configured_ = true;
    return core::Status::kOk;
  }

  // Forget the last sample (after a restart of the sensor or of the estimator), keep the counts.
  void Restart() { has_last_ = false; }

  ImuSampleVerdict Check(const ImuSample<S>& sample) {
    if (!configured_) return Count(ImuSampleVerdict::kDroppedInvalid);
    if (has_last_ && sample.t_us < last_t_us_) return Count(ImuSampleVerdict::kDroppedOutOfOrder);
    if (has_last_ && sample.t_us == last_t_us_) return Count(ImuSampleVerdict::kDroppedDuplicate);
    const std::int64_t missing = has_last_ ? MissingBefore(sample) : 0;
    // Whatever its content, the sample arrived in order: it closes the hole behind it.
    has_last_ = true;
    last_t_us_ = sample.t_us;
    last_seq_ = sample.seq;
    if (missing > 0) {
      ++counts_.gaps;
      counts_.missing_samples += missing;
    }
    if ((sample.flags & kImuValid) == 0u || !sample.gyro_radps.allFinite() ||
        !sample.accel_mps2.allFinite())
      return Count(ImuSampleVerdict::kDroppedInvalid);
    if (Saturated(sample)) return Count(ImuSampleVerdict::kDroppedSaturated);
    return Count(missing > 0 ? ImuSampleVerdict::kAcceptedAfterGap : ImuSampleVerdict::kAccepted);
  }

  const ImuStreamCounts& Counts() const { return counts_; }
  const ImuStreamOptions<S>& Options() const { return options_; }

 private:
  // Samples lost between the last one and this: from the sensor's counter when it moved
  // forward, from the time step when that is longer than the gap threshold; the larger.
  std::int64_t MissingBefore(const ImuSample<S>& sample) const {
    // Differences in unsigned arithmetic: exact for any ordered pair of int64 stamps, where the
    // signed subtraction could overflow on a corrupt stamp.
    const std::uint64_t period = static_cast<std::uint64_t>(options_.nominal_period_us);
    const std::uint64_t step_us =
        static_cast<std::uint64_t>(sample.t_us) - static_cast<std::uint64_t>(last_t_us_);
    std::uint64_t by_time = 0;
    if (step_us > static_cast<std::uint64_t>(options_.max_gap_periods) * period)
      by_time = (step_us + period / 2) / period - 1;
    // A counter that jumps while the time step is normal is a renumbering, not a loss: a loss the
    // counter shows must also show in time (at least half a period more than one step).
    std::uint64_t by_seq = 0;
    if (sample.seq > last_seq_ && 2 * step_us >= 3 * period)
      by_seq = static_cast<std::uint64_t>(sample.seq) - static_cast<std::uint64_t>(last_seq_) - 1;
    return static_cast<std::int64_t>(std::min(std::max(by_time, by_seq), kMaxMissingPerGap));
  }

  bool Saturated(const ImuSample<S>& sample) const {
    if ((sample.flags & (kImuGyroSaturated | kImuAccelSaturated)) != 0u) return true;
    const bool gyro_clipped = options_.gyro_range_radps > S(0) &&
                              sample.gyro_radps.cwiseAbs().maxCoeff() >= options_.gyro_range_radps;
    const bool accel_clipped = options_.accel_range_mps2 > S(0) &&
                               sample.accel_mps2.cwiseAbs().maxCoeff() >= options_.accel_range_mps2;
    return gyro_clipped || accel_clipped;
  }

  ImuSampleVerdict Count(ImuSampleVerdict v) {
    switch (v) {
      case ImuSampleVerdict::kAccepted:
      case ImuSampleVerdict::kAcceptedAfterGap: ++counts_.accepted; break;
      case ImuSampleVerdict::kDroppedOutOfOrder: ++counts_.out_of_order; break;
      case ImuSampleVerdict::kDroppedDuplicate: ++counts_.duplicated; break;
      case ImuSampleVerdict::kDroppedInvalid: ++counts_.invalid; break;
      case ImuSampleVerdict::kDroppedSaturated: ++counts_.saturated; break;
    }
    return v;
  }

  // Bounds one hole's contribution so the counters cannot overflow on corrupt stamps.
  static constexpr std::uint64_t kMaxMissingPerGap = std::uint64_t{1} << 40;

  ImuStreamOptions<S> options_;
  ImuStreamCounts counts_;
  bool configured_ = false;
  bool has_last_ = false;
  std::int64_t last_t_us_ = 0;
  std::int64_t last_seq_ = 0;
};

}  // namespace swf::estimator
