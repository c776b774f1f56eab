// Fuzz entry point for swf-eval's KITTI inputs: an even first byte sends the rest to the
// calib.txt parser (ParseKittiCalibration), an odd one to the poses.txt parser
// (ParseKittiPoses). Accepted values must be finite (positive focal lengths and baseline,
// rotations); every refusal must say why.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "kitti.hpp"

namespace {

void Expect(bool condition) {
  if (!condition) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  std::string error;
  if (data[0] % 2 == 0) {
    swf::estimator::StereoCamera<double> camera;
    if (swf::eval::ParseKittiCalibration(in, "calib.txt", &camera, &error)) {
      Expect(camera.fx > 0.0 && camera.fy > 0.0 && camera.baseline_m > 0.0 &&
             std::isfinite(camera.baseline_m));
    } else {
      Expect(error.rfind("calib.txt", 0) == 0);
    }
  } else {
    std::vector<swf::eval::PoseD> poses;
    if (swf::eval::ParseKittiPoses(in, "poses.txt", &poses, &error)) {
      Expect(poses.size() >= 3);
      for (const swf::eval::PoseD& p : poses) Expect(p.R.allFinite() && p.t.allFinite());
    } else {
      Expect(error.rfind("poses.txt", 0) == 0);
    }
  }
  return 0;
}
