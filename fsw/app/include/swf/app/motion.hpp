// Motion input of the process model: the navigation system's (IMU's) relative motion between
// consecutive frames.
#pragma once

#include <cstdint>

namespace swf::app {

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

}  // namespace swf::app
