// source: v4l2 — the V4L2 stereo source of a configuration (two /dev/videoN capture devices,
// raw images rectified by the pipeline). The kernel is a parameter: swf-fsw passes the real one
// (drivers::LinuxV4l2Kernel()), tests a scripted one.
#pragma once

#include <memory>
#include <string>

#include "swf/app/config.hpp"
#include "swf/drivers/v4l2_kernel.hpp"
#include "swf/drivers/v4l2_stereo_source.hpp"

namespace swf::app {

// The driver options for a validated configuration and the calibrations' image size. The device
// pointers point into `config`, which must outlive the options and any source built from them.
drivers::V4l2StereoOptions V4l2OptionsFromConfig(const FswConfig& config, int width, int height);

// A configured (not started) source over `kernel`; nullptr with *error naming the problem.
std::unique_ptr<drivers::V4l2StereoSource> MakeV4l2Source(const FswConfig& config, int width,
                                                          int height, drivers::V4l2Kernel& kernel,
                                                          std::string* error);

}  // namespace swf::app
