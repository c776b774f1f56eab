// Fuzz entry point for the calibration importers: the input is written to a file and imported as
// every format (as both cameras for the two-file formats). Nothing may crash or throw; an import
// that succeeds gives two cameras with positive focal lengths, finite numbers and a size inside
// the limits, and a refusal says why, naming the file.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "swf/calibration/calibration_import.hpp"

namespace {

bool Sane(const swf::frontend::CameraCalibration& c) {
  return c.fx > 0.0 && c.fy > 0.0 &&
         std::isfinite(c.fx + c.fy + c.cx + c.cy + c.k1 + c.k2 + c.k3) && c.width >= 1 &&
         c.width <= 16384 && c.height >= 1 && c.height <= 16384 && c.body_T_camera.t.allFinite() &&
         c.body_T_camera.R.allFinite();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using swf::calibration::CalibrationFormat;
  static const std::string kPath =
      "/tmp/swf_calibration_fuzz_" + std::to_string(::getpid()) + ".txt";
  std::FILE* f = std::fopen(kPath.c_str(), "wb");
  if (f == nullptr) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  for (const CalibrationFormat format :
       {CalibrationFormat::kAuto, CalibrationFormat::kEuroc, CalibrationFormat::kRos,
        CalibrationFormat::kKalibr, CalibrationFormat::kOpenCv, CalibrationFormat::kKitti,
        CalibrationFormat::kCahvor}) {
    swf::calibration::ImportOptions options;
    options.format = format;
    options.width = format == CalibrationFormat::kKitti ? 640 : 0;
    options.height = format == CalibrationFormat::kKitti ? 480 : 0;
    const bool pair = format == CalibrationFormat::kEuroc || format == CalibrationFormat::kRos ||
                      format == CalibrationFormat::kCahvor;
    std::vector<std::string> files = {kPath};
    if (pair) files.push_back(kPath);
    swf::calibration::StereoCalibration c;
    std::string error;
    if (swf::calibration::ImportStereoCalibration(files, options, &c, &error)) {
      if (!Sane(c.left) || !Sane(c.right)) __builtin_trap();
    } else if (error.empty()) {
      __builtin_trap();  // a refusal says why
    }
  }
  std::remove(kPath.c_str());
  return 0;
}
