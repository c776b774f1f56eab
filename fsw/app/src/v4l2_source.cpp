#include "swf/app/v4l2_source.hpp"

#include <cmath>

namespace swf::app {

namespace {

drivers::PixelFormat FormatOf(const std::string& name) {
  if (name == "y16") return drivers::PixelFormat::kGray16Le;
  if (name == "yuyv") return drivers::PixelFormat::kYuyv;
  return drivers::PixelFormat::kGray8;
}

}  // namespace

drivers::V4l2StereoOptions V4l2OptionsFromConfig(const FswConfig& config, int width, int height) {
  drivers::V4l2StereoOptions o;
  for (drivers::V4l2CameraOptions* side : {&o.left, &o.right}) {
    side->width = width;
    side->height = height;
    side->format = FormatOf(config.camera.format);
    side->buffer_count = config.camera.buffers;
    // V4L2's controls: exposure in units of 100 us, an integer gain.
    if (config.camera.exposure_us > 0.0) {
      side->exposure_100us =
          static_cast<std::int32_t>(std::llround(config.camera.exposure_us / 100.0));
    }
    if (config.camera.gain >= 0.0)
      side->gain = static_cast<std::int32_t>(std::llround(config.camera.gain));
  }
  o.left.device = config.camera.left.c_str();
  o.right.device = config.camera.right.c_str();
  o.pair_tolerance_ns =
      static_cast<core::TimeNs>(std::llround(config.camera.pair_tolerance_ms * 1e6));
  return o;
}

std::unique_ptr<drivers::V4l2StereoSource> MakeV4l2Source(const FswConfig& config, int width,
                                                          int height, drivers::V4l2Kernel& kernel,
                                                          std::string* error) {
  auto source = std::make_unique<drivers::V4l2StereoSource>(kernel);
  if (const core::Status s = source->Configure(V4l2OptionsFromConfig(config, width, height));
      s != core::Status::kOk) {
    *error = std::string("the v4l2 source refused its options (") + core::ToString(s) +
             "): " + source->LastError();
    return nullptr;
  }
  return source;
}

}  // namespace swf::app
