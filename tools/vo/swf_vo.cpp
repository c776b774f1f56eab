// swf-vo: solves a stereo visual-odometry problem in the kitti-vo text format with the Sliding
// Window Filter and prints one JSON object.
//   swf-vo --calib F --poses F --factors F [--window K]
// Without --window the whole problem is solved in batch (first pose fixed, sigma 1 px). The
// filter instance is chosen to fit the problem (kitti_vo.hpp); exit 0 on success, 1 when the
// input or the solve fails (the message names the file and line, pose or capacity), 2 on a
// usage error (docs/cli.md).
#include <climits>
#include <cstdio>
#include <string>

#include "kitti_vo.hpp"
#include "swf/ground_cli/ground_cli.hpp"

int main(int argc, char** argv) {
  std::string calib;
  std::string poses;
  std::string factors;
  int window = 0;
  CLI::App app{
      "swf-vo: solves a kitti-vo stereo VO problem with the Sliding Window Filter and prints one "
      "JSON object: mode, instance, needs, initial_cost, final_cost (0.5 x sum of squared "
      "residuals, sigma 1 px), iterations, solve_time_ms, fault_bits, poses"};
  swf::ground_cli::Adopt(&app, "swf-vo");
  app.add_option("--calib", calib, "fx fy skew u0 v0 baseline_m")->required();
  app.add_option("--poses", poses,
                 "one line per pose: id + row-major 4x4 camera-to-world initial estimate")
      ->required();
  app.add_option("--factors", factors,
                 "one line per stereo factor: pose_id landmark_id uL uR v X Y Z")
      ->required();
  app.add_option("--window", window, "sliding window of K poses (default: batch over all poses)")
      ->check(CLI::Range(1, INT_MAX));
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  swf::tools::KittiVoProblem problem;
  std::string error;
  if (!swf::tools::LoadKittiVo(calib, poses, factors, &problem, &error)) {
    std::fprintf(stderr, "swf-vo: %s\n", error.c_str());
    return swf::cli::kExitFailed;
  }
  const swf::tools::KittiVoResult r = swf::tools::SolveKittiVo(problem, window);
  if (!r.ok) {
    std::fprintf(stderr, "swf-vo: %s\n", r.error.c_str());
    return swf::cli::kExitFailed;
  }
  // The run echoed after the results (docs/cli.md).
  nlohmann::ordered_json report = swf::tools::KittiVoReport(problem, r, window);
  report["run"] = nlohmann::ordered_json(swf::ground_cli::RunEcho(app, "swf-vo", argc, argv));
  swf::ground_cli::PrintJson(report);
  return swf::cli::kExitOk;
}
