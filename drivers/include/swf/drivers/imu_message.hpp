// imu_t (messages/imu_t.lcm) and the estimator's ImuSample: the one conversion each way, for the
// LCM subscription, the log's recording and its replay.
#pragma once

#include <cstdint>

#include "swf/estimator/imu_preintegration.hpp"
#include "swf_msgs/imu_t.hpp"

namespace swf::drivers {

inline estimator::ImuSample<double> ImuSampleOf(const swf_msgs::imu_t& m) {
  estimator::ImuSample<double> s;
  s.t_us = m.utime;
  s.seq = m.seq;
  for (int i = 0; i < 3; ++i) {
    s.gyro_radps[i] = m.angular_rate_radps[i];
    s.accel_mps2[i] = m.specific_force_mps2[i];
  }
  s.flags = static_cast<std::uint32_t>(m.flags);
  return s;
}

inline void ImuMessageOf(const estimator::ImuSample<double>& s, swf_msgs::imu_t* m) {
  m->utime = s.t_us;
  m->seq = s.seq;
  for (int i = 0; i < 3; ++i) {
    m->angular_rate_radps[i] = s.gyro_radps[i];
    m->specific_force_mps2[i] = s.accel_mps2[i];
  }
  m->flags = static_cast<std::int32_t>(s.flags);
}

}  // namespace swf::drivers
