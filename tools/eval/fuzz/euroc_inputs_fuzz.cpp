// Fuzz entry point for swf-eval's EuRoC inputs: an even first byte sends the rest to the
// sensor.yaml parser and the calibration checks (image_io::ParseCalibration, CheckCalibration),
// an odd one to the data.csv image-list parser (ParseImageList). Accepted lists must hold
// increasing timestamps and names inside data/; every refusal must say why.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "euroc.hpp"
#include "swf/image_io/image_io.hpp"

namespace {

void Expect(bool condition) {
  if (!condition) __builtin_trap();
}

void Calibration(const std::string& text) {
  swf::frontend::CameraCalibration c;
  std::string error;
  if (swf::image_io::ParseCalibration(text, "sensor.yaml", &c, &error)) {
    if (!swf::eval::CheckCalibration(c, "sensor.yaml", &error)) Expect(!error.empty());
  } else {
    Expect(!error.empty());
  }
}

void ImageList(const std::string& text) {
  std::istringstream in(text);
  std::vector<swf::eval::ListedImage> frames;
  std::string error;
  if (!swf::eval::ParseImageList(in, "data.csv", &frames, &error)) {
    Expect(error.rfind("data.csv", 0) == 0);
    return;
  }
  for (std::size_t k = 0; k < frames.size(); ++k) {
    Expect(k == 0 || frames[k].stamp_ns > frames[k - 1].stamp_ns);
    Expect(swf::eval::CheckImageName(frames[k].name, &error));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (data[0] % 2 == 0) {
    Calibration(text);
  } else {
    ImageList(text);
  }
  return 0;
}
