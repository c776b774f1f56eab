// EuRoC imu0: the recorded IMU of an ASL-layout sequence (DIR/mav0/imu0/data.csv and
// sensor.yaml) as estimator samples and noise, for the preintegration and the extended state.
//
// data.csv: a '#' header, then one row per sample `t_ns, w_x, w_y, w_z, a_x, a_y, a_z` (rad/s,
// m/s^2, in the IMU frame S). Times become microseconds (rounded), the camera clock of
// stereo_frame_t; seq is the row's index among samples. Rows are kept in file order: ordering,
// duplicates and gaps are ImuStreamChecker's to judge, not the reader's. A row that is not seven
// finite numbers is refused, naming file:line.
//
// sensor.yaml: gyroscope_noise_density, gyroscope_random_walk, accelerometer_noise_density,
// accelerometer_random_walk, rate_hz and T_BS (4x4 row-major, body_T_sensor); each must be
// present, finite and (noise) non-negative, or the error names file:line of the bad value.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/estimator/geometry.hpp"
#include "swf/estimator/imu_preintegration.hpp"

namespace swf::eval {

struct EurocImuCalibration {
  estimator::ImuNoise<double> noise;
  double rate_hz = 0.0;
  estimator::Pose<double> body_T_imu;
};

bool ReadEurocImuCalibration(const std::string& path, EurocImuCalibration* calibration,
                             std::string* error);

bool ReadEurocImuSamples(const std::string& path,
                         std::vector<estimator::ImuSample<double>>* samples, std::string* error);

// A dataset's nanosecond stamps on the microsecond clock of the flight messages (rounded).
constexpr std::int64_t NsToUs(std::int64_t t_ns) {
  return t_ns >= 0 ? (t_ns + 500) / 1000 : -((-t_ns + 500) / 1000);
}

}  // namespace swf::eval
