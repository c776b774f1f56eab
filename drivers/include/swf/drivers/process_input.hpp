// Inputs of the process model: the navigation system's relative motion between consecutive
// frames (stereo-only estimator), or the IMU's samples (stereo-inertial estimator).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "swf/estimator/imu_preintegration.hpp"

namespace swf::drivers {

// The navigation system's relative motion camera_prev_T_camera for a frame (an IMU / navigation
// filter; the simulator; a log). Called on the real-time thread: must not allocate or block.
// The input is kept as recorded (translation, rotation vector) and turned into a pose by the
// loop, so a live run and its replay feed the filter the same bits.
struct MotionInput {
  double translation_m[3] = {0, 0, 0};  // previous camera frame, metres
  double rotation_rad[3] = {0, 0, 0};   // rotation vector, radians
};
class MotionProvider {
 public:
  virtual ~MotionProvider() = default;
  virtual bool Motion(std::uint64_t seq, MotionInput* input) = 0;
};

// The IMU's samples in stream order (the simulator's unit, an LCM subscription, a log). Called
// on the real-time thread before each cycle's stages with the exposure time the cycle stands
// for: the next sample due by then (true), or false when none is. A live stream gives the
// samples stamped at or before until_utime; a log gives the samples recorded before the frame
// just served, so a replay hands the pipeline exactly what the live run did. Must not allocate
// or block.
class ImuProvider {
 public:
  virtual ~ImuProvider() = default;
  virtual bool NextImu(std::int64_t until_utime, estimator::ImuSample<double>* sample) = 0;
};

// A stream held in memory (the simulator's unit, a dataset's imu0), served in order as its
// samples fall due. The vector is the caller's and must outlive the provider.
class StoredImuProvider final : public ImuProvider {
 public:
  void Reset(const std::vector<estimator::ImuSample<double>>* samples) {
    samples_ = samples;
    next_ = 0;
  }
  bool NextImu(std::int64_t until_utime, estimator::ImuSample<double>* sample) override {
    if (samples_ == nullptr || next_ >= samples_->size() || (*samples_)[next_].t_us > until_utime)
      return false;
    *sample = (*samples_)[next_++];
    return true;
  }

 private:
  const std::vector<estimator::ImuSample<double>>* samples_ = nullptr;
  std::size_t next_ = 0;
};

}  // namespace swf::drivers
