// ImuInput: the IMU samples between camera frames, as the flight pipeline consumes them.
//
// Samples arrive (Add) in stream order, each judged by the ImuStreamChecker (dropped kinds are
// counted, never fatal). Accepted ones wait in a fixed ring until the pipeline integrates up to
// a frame's exposure (IntegrateTo), which appends the interval to two preintegrations:
//   since the filter's newest state   the next process factor, or the coasted state in an outage
//   since the last trusted state      a restart of the filter from that state
// Each is started at the bias estimate of the state it begins at (first-order bias correction
// stays small). The last sample at or before the integrated time is kept: it holds the signal
// into the next interval, and bridges a hole when the stream stops (counted, flagged).
//
// Determinism: the result depends only on the samples added before IntegrateTo, so a live run
// and its replay agree when both add the samples stamped at or before each exposure.
//
// Flight code: no allocation after Configure, bounded work per sample and per interval.
#pragma once

#include <cstdint>
#include <memory>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/imu_stream.hpp"
#include "swf/estimator/inertial_model.hpp"

namespace swf::app {

// Accepted samples held between two integrations (10 s at 400 Hz).
inline constexpr int kMaxImuSamples = 4096;

struct ImuOptions {
  bool enabled = false;  // false: stereo-only (motion input or constant velocity)
  estimator::ImuNoise<double> noise;
  estimator::ImuStreamOptions<double> stream;
  estimator::SampleHold hold = estimator::SampleHold::kMidpoint;
  estimator::Pose<double> imu_T_camera;  // the left (rectified) camera in the IMU frame
  estimator::Vec3<double> gravity_world_mps2 = estimator::Vec3<double>(0.0, 0.0, -9.81);
  // The first state beyond its pose (the state guidance hands over): velocity of the IMU in the
  // world frame, and the prior sigmas of velocity and biases (biases start at zero).
  estimator::Vec3<double> initial_velocity_world_mps = estimator::Vec3<double>::Zero();
  double first_velocity_sigma_mps = 0.1;
  double first_gyro_bias_sigma_radps = 0.01;
  double first_accel_bias_sigma_mps2 = 0.1;
  // Static start: the vehicle stands still before the first frame; the samples up to it give
  // the gyroscope bias and level the guidance's attitude (estimator::AlignStatic), and the
  // velocity starts at zero with static_velocity_sigma_mps. Refused (counted) when the samples
  // do not look static: the start then takes the guidance's state.
  bool static_start = false;
  estimator::StaticAlignmentOptions<double> static_alignment;
  double static_velocity_sigma_mps = 0.01;
  // Camera-IMU time offset: the IMU stamps an instant t as t + offset (seconds), so a frame's
  // interval ends at its exposure + offset on the IMU's clock. time_offset_s is the known one
  // (a calibration's); with estimate_time_offset the pipeline estimates it online
  // (estimator::TimeOffsetEstimator) from there, held within +-max_time_offset_s.
  double time_offset_s = 0.0;
  bool estimate_time_offset = false;
  double max_time_offset_s = 0.05;

  bool Valid() const;
};

// What the last integration had to bridge.
struct ImuIntervalReport {
  int samples_used = 0;
  bool gap = false;  // a step longer than the stream's gap threshold was held (or no sample)
  double longest_step_s = 0.0;
};

struct ImuCounts {
  estimator::ImuStreamCounts stream;   // every sample's verdict
  std::int64_t overflowed = 0;         // accepted but lost: the ring was full (oldest dropped)
  std::int64_t intervals_bridged = 0;  // integrations that held a sample over a gap
  // Static start (ImuOptions::static_start): 1 aligned, -1 refused (not at rest), 0 not asked;
  // the levelling applied to the guidance's attitude.
  std::int32_t static_start = 0;
  double static_tilt_correction_rad = 0.0;
};

class ImuInput {
 public:
  using Pim = estimator::ImuPreintegration<double>;

  core::Status Configure(const ImuOptions& options);

  // One sample from the source (in stream order). Returns the checker's verdict.
  estimator::ImuSampleVerdict Add(const estimator::ImuSample<double>& sample);

  // Times below are the cameras' (exposures): the samples are read at t + the time offset
  // (ImuOptions::time_offset_s, then SetTimeOffsetUs).
  // Starts both intervals at t_us (the first estimated frame) with these biases.
  core::Status Start(std::int64_t t_us, const estimator::ImuBiases<double>& biases);
  bool Started() const { return started_; }
  // Starts an interval again at the integrated time, at new biases.
  core::Status RestartSinceEstimate(const estimator::ImuBiases<double>& biases);
  core::Status RestartSinceTrusted(const estimator::ImuBiases<double>& biases);

  // Appends [integrated time, t_us] to both intervals (nothing if t_us is not later). kEmpty
  // when no sample was ever accepted (nothing to hold), kNotConfigured before Start.
  core::Status IntegrateTo(std::int64_t t_us);

  const Pim& SinceEstimate() const { return since_estimate_; }
  const Pim& SinceTrusted() const { return since_trusted_; }
  const ImuIntervalReport& LastInterval() const { return last_interval_; }
  ImuCounts Counts() const;
  const ImuOptions& Options() const { return options_; }
  // The accepted samples stamped at or before t_us (+ offset) that wait in the ring (before Start:
  // all of them since Configure, up to kMaxImuSamples), for the static start.
  int Buffered(std::int64_t t_us, const estimator::ImuSample<double>** samples) const;
  void NoteStaticStart(std::int32_t outcome, double tilt_correction_rad) {
    static_start_ = outcome;
    static_tilt_correction_rad_ = tilt_correction_rad;
  }
  // The offset applied from the next integration on (an estimate's change moves the end of the
  // next interval, never the time already integrated).
  void SetTimeOffsetUs(std::int64_t offset_us) { offset_us_ = offset_us; }
  std::int64_t TimeOffsetUs() const { return offset_us_; }

 private:
  void DropConsumed();

  ImuOptions options_;
  estimator::ImuStreamChecker<double> checker_;
  std::unique_ptr<estimator::ImuSample<double>[]> samples_;
  int count_ = 0;
  bool started_ = false;
  std::int64_t integrated_to_us_ = 0;  // on the IMU's clock
  std::int64_t offset_us_ = 0;
  double max_step_s_ = 0.0;
  Pim since_estimate_;
  Pim since_trusted_;
  ImuIntervalReport last_interval_;
  std::int64_t overflowed_ = 0;
  std::int64_t intervals_bridged_ = 0;
  std::int32_t static_start_ = 0;
  double static_tilt_correction_rad_ = 0.0;
};

}  // namespace swf::app
