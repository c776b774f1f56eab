// Fuzz entry point for swf-vo's text problem (kitti_vo.hpp ReadKittiVo): the first byte picks
// which of the three files the rest of the input replaces (calibration, poses or factors); the
// other two are a small valid problem. A loaded problem is also sized (KittiVoNeeds), which walks
// every factor; solving is left out (it is exercised by kitti_vo_test).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "kitti_vo.hpp"

namespace {

constexpr const char* kCalibration = "721.5377 721.5377 0 609.5593 172.854 0.537150588\n";
constexpr const char* kPoses =
    "1 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n"
    "2 1 0 0 0 0 1 0 0 0 0 1 1 0 0 0 1\n"
    "3 1 0 0 0 0 1 0 0 0 0 1 2 0 0 0 1\n";
constexpr const char* kFactors =
    "1 7 620 580 180 0.1 0.2 10\n"
    "2 7 640 600 181 0.1 0.2 10\n"
    "3 7 660 620 182 0.1 0.2 10\n"
    "1 8 500 470 150 -1 -0.5 13\n"
    "3 8 520 490 151 -1 -0.5 13\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const int which = data[0] % 3;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  std::istringstream calib(which == 0 ? text : kCalibration);
  std::istringstream poses(which == 1 ? text : kPoses);
  std::istringstream factors(which == 2 ? text : kFactors);
  swf::tools::KittiVoProblem problem;
  std::string error;
  if (swf::tools::ReadKittiVo({&calib, "calib"}, {&poses, "poses"}, {&factors, "factors"}, &problem,
                              &error)) {
    (void)swf::tools::KittiVoNeeds(problem, 0);
    (void)swf::tools::KittiVoNeeds(problem, 2);
  } else if (error.empty()) {
    __builtin_trap();  // every refusal must say why
  }
  return 0;
}
