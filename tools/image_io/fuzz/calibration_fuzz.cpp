// Fuzz entry point for the calibration parser (EuRoC sensor.yaml and ROS camera_info text): a
// parsed calibration has finite values, positive focal lengths and a resolution inside the image
// limits; a refusal says why.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "swf/image_io/image_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace swf::image_io;
  const std::string text(reinterpret_cast<const char*>(data), size);
  swf::frontend::CameraCalibration c;
  std::string error;
  if (ParseCalibration(text, "sensor.yaml", &c, &error)) {
    const bool sane = c.fx > 0.0 && c.fy > 0.0 && std::isfinite(c.fx + c.fy + c.cx + c.cy) &&
                      c.width >= 1 && c.width <= kMaxImageSide && c.height >= 1 &&
                      c.height <= kMaxImageSide && c.body_T_camera.t.allFinite();
    if (!sane) __builtin_trap();
  } else if (error.rfind("sensor.yaml: ", 0) != 0) {
    __builtin_trap();  // a refusal names the file
  }
  return 0;
}
