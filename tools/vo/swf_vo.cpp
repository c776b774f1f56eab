// swf-vo: solves a stereo visual-odometry problem in the kitti-vo text format with the Sliding
// Window Filter and prints one JSON object.
//   swf-vo --calib F --poses F --factors F [--window K]
// Without --window the whole problem is solved in batch (first pose fixed, sigma 1 px). The
// filter instance is chosen to fit the problem (kitti_vo.hpp); exit 0 on success, 1 when the
// input or the solve fails (the message names the file and line, pose or capacity), 2 on a
// usage error.
#include <climits>
#include <cstdio>
#include <string>

#include "kitti_vo.hpp"

namespace {

constexpr const char* kUsage =
    "usage: swf-vo --calib F --poses F --factors F [--window K]\n"
    "  --calib F    fx fy skew u0 v0 baseline_m\n"
    "  --poses F    one line per pose: id + row-major 4x4 camera-to-world initial estimate\n"
    "  --factors F  one line per stereo factor: pose_id landmark_id uL uR v X Y Z\n"
    "  --window K   sliding window of K poses (default: batch over all poses)\n"
    "  --help       this text\n"
    "Prints one JSON object: mode, instance, needs, initial_cost, final_cost (0.5 x sum of\n"
    "squared residuals, sigma 1 px), iterations, solve_time_ms, fault_bits, poses.\n";

int Usage(const std::string& why) {
  std::fprintf(stderr, "swf-vo: %s\n%s", why.c_str(), kUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string calib;
  std::string poses;
  std::string factors;
  int window = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    std::string* target = arg == "--calib"     ? &calib
                          : arg == "--poses"   ? &poses
                          : arg == "--factors" ? &factors
                                               : nullptr;
    if (target == nullptr && arg != "--window") return Usage("unknown option " + arg);
    if (i + 1 >= argc) return Usage("missing value for " + arg);
    const std::string value = argv[++i];
    if (target != nullptr) {
      *target = value;
    } else if (long long k = 0; swf::tools::ParseCount(value, INT_MAX, &k)) {
      window = static_cast<int>(k);
    } else {
      return Usage("--window takes a positive integer");
    }
  }
  if (calib.empty() || poses.empty() || factors.empty())
    return Usage("--calib, --poses and --factors are required");
  swf::tools::KittiVoProblem problem;
  std::string error;
  if (!swf::tools::LoadKittiVo(calib, poses, factors, &problem, &error)) {
    std::fprintf(stderr, "swf-vo: %s\n", error.c_str());
    return 1;
  }
  const swf::tools::KittiVoResult r = swf::tools::SolveKittiVo(problem, window);
  if (!r.ok) {
    std::fprintf(stderr, "swf-vo: %s\n", r.error.c_str());
    return 1;
  }
  std::fputs(swf::tools::KittiVoJson(problem, r, window).c_str(), stdout);
  return 0;
}
