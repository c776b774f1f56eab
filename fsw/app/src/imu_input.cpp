#include "swf/app/imu_input.hpp"

#include <cmath>
#include <new>

namespace swf::app {

using core::Status;

bool ImuOptions::Valid() const {
  const auto finite_non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  return noise.Valid() && stream.Valid() && gravity_world_mps2.allFinite() &&
         initial_velocity_world_mps.allFinite() && imu_T_camera.t.allFinite() &&
         imu_T_camera.R.allFinite() && finite_non_negative(first_velocity_sigma_mps) &&
         finite_non_negative(first_gyro_bias_sigma_radps) &&
         finite_non_negative(first_accel_bias_sigma_mps2) &&
         finite_non_negative(static_velocity_sigma_mps) && static_alignment.min_samples >= 2 &&
         std::isfinite(time_offset_s) && max_time_offset_s > 0.0 &&
         std::abs(time_offset_s) <= max_time_offset_s;
}

Status ImuInput::Configure(const ImuOptions& options) {
  if (!options.Valid()) return Status::kInvalidArgument;
  if (checker_.Configure(options.stream) != Status::kOk) return Status::kInvalidArgument;
  options_ = options;
  if (!samples_) samples_.reset(new (std::nothrow) estimator::ImuSample<double>[kMaxImuSamples]);
  if (!samples_) return Status::kFull;
  count_ = 0;
  started_ = false;
  integrated_to_us_ = 0;
  offset_us_ = std::llround(options.time_offset_s * 1e6);
  // A step longer than the checker's gap threshold is a hole the integrator bridges.
  max_step_s_ = static_cast<double>(options.stream.max_gap_periods) *
                static_cast<double>(options.stream.nominal_period_us) * 1e-6;
  last_interval_ = ImuIntervalReport{};
  overflowed_ = 0;
  intervals_bridged_ = 0;
  static_start_ = 0;
  static_tilt_correction_rad_ = 0.0;
  return Status::kOk;
}

int ImuInput::Buffered(std::int64_t t_us, const estimator::ImuSample<double>** samples) const {
  *samples = samples_.get();
  int n = 0;
  while (n < count_ && samples_[n].t_us <= t_us + offset_us_) ++n;
  return n;
}

estimator::ImuSampleVerdict ImuInput::Add(const estimator::ImuSample<double>& sample) {
  const estimator::ImuSampleVerdict verdict = checker_.Check(sample);
  if (!estimator::IsAccepted(verdict) || !samples_) return verdict;
  if (count_ == kMaxImuSamples) {
    // Nobody integrated for longer than the ring holds: the oldest sample goes (a hole the
    // integrator bridges), the newest stays.
    for (int k = 1; k < count_; ++k) samples_[k - 1] = samples_[k];
    --count_;
    ++overflowed_;
  }
  samples_[count_++] = sample;
  return verdict;
}

Status ImuInput::Start(std::int64_t t_us, const estimator::ImuBiases<double>& biases) {
  if (!samples_) return Status::kNotConfigured;
  integrated_to_us_ = t_us + offset_us_;
  started_ = true;
  const Status s = since_estimate_.Reset(options_.noise, biases);
  if (s != Status::kOk) return s;
  DropConsumed();
  return since_trusted_.Reset(options_.noise, biases);
}

Status ImuInput::RestartSinceEstimate(const estimator::ImuBiases<double>& biases) {
  return since_estimate_.Reset(options_.noise, biases);
}

Status ImuInput::RestartSinceTrusted(const estimator::ImuBiases<double>& biases) {
  return since_trusted_.Reset(options_.noise, biases);
}

Status ImuInput::IntegrateTo(std::int64_t camera_t_us) {
  if (!started_) return Status::kNotConfigured;
  const std::int64_t t_us = camera_t_us + offset_us_;
  if (t_us <= integrated_to_us_) return Status::kOk;
  last_interval_ = ImuIntervalReport{};
  if (count_ == 0) {
    last_interval_.gap = true;
    return Status::kEmpty;
  }
  estimator::IntervalSummary summary;
  Status s =
      estimator::PreintegrateInterval(samples_.get(), count_, integrated_to_us_, t_us,
                                      options_.hold, max_step_s_, &since_estimate_, &summary);
  if (s == Status::kOk) {
    s = estimator::PreintegrateInterval(samples_.get(), count_, integrated_to_us_, t_us,
                                        options_.hold, max_step_s_, &since_trusted_, &summary);
  }
  if (s != Status::kOk) return s;
  last_interval_.samples_used = summary.samples_used;
  last_interval_.longest_step_s = summary.longest_step_s;
  last_interval_.gap = summary.bridged_steps > 0;
  intervals_bridged_ += last_interval_.gap ? 1 : 0;
  integrated_to_us_ = t_us;
  DropConsumed();
  return Status::kOk;
}

// Keeps the last sample at or before the integrated time (it holds into the next interval) and
// everything after it.
void ImuInput::DropConsumed() {
  int first = 0;
  while (first + 1 < count_ && samples_[first + 1].t_us <= integrated_to_us_) ++first;
  if (first == 0) return;
  for (int k = first; k < count_; ++k) samples_[k - first] = samples_[k];
  count_ -= first;
}

ImuCounts ImuInput::Counts() const {
  ImuCounts c;
  c.stream = checker_.Counts();
  c.overflowed = overflowed_;
  c.intervals_bridged = intervals_bridged_;
  c.static_start = static_start_;
  c.static_tilt_correction_rad = static_tilt_correction_rad_;
  return c;
}

}  // namespace swf::app
