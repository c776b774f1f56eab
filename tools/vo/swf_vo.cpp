// swf-vo: solves a stereo visual-odometry problem in the kitti-vo text format with the Sliding
// Window Filter and prints one JSON object.
//   swf-vo --calib F --poses F --factors F [--window K]
// Without --window the whole problem is solved in batch (first pose fixed, sigma 1 px).
#include <cstdio>
#include <cstdlib>
#include <string>

#include "kitti_vo.hpp"

namespace {

int Usage(const char* why) {
  std::fprintf(stderr, "swf-vo: %s\nusage: swf-vo --calib F --poses F --factors F [--window K]\n",
               why);
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
    if (i + 1 >= argc) return Usage(("missing value for " + arg).c_str());
    const std::string value = argv[++i];
    if (arg == "--calib") {
      calib = value;
    } else if (arg == "--poses") {
      poses = value;
    } else if (arg == "--factors") {
      factors = value;
    } else if (arg == "--window") {
      char* end = nullptr;
      const long k = std::strtol(value.c_str(), &end, 10);
      if (end == value.c_str() || *end != '\0' || k < 1)
        return Usage("--window takes a positive integer");
      window = static_cast<int>(k);
    } else {
      return Usage(("unknown option " + arg).c_str());
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
  std::printf(
      "{\n  \"mode\": \"%s\",\n  \"window\": %d,\n  \"initial_cost\": %.17g,\n"
      "  \"final_cost\": %.17g,\n  \"iterations\": %d,\n  \"solve_time_ms\": %.3f,\n"
      "  \"fault_bits\": %u,\n  \"poses\": [\n",
      window > 0 ? "sliding_window" : "batch", window, r.initial_cost, r.final_cost, r.iterations,
      r.solve_time_ms, r.fault_bits);
  for (std::size_t j = 0; j < r.poses.size(); ++j) {
    const Eigen::Matrix4d m = r.poses[j].Matrix();
    std::printf("    {\"id\": %lld, \"camera_to_world\": [",
                static_cast<long long>(problem.pose_ids[j]));
    for (int k = 0; k < 16; ++k) std::printf("%s%.17g", k == 0 ? "" : ", ", m(k / 4, k % 4));
    std::printf("]}%s\n", j + 1 < r.poses.size() ? "," : "");
  }
  std::printf("  ]\n}\n");
  return 0;
}
