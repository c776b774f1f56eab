// swf-vo-synth: writes a generated kitti-vo problem (kitti_vo_synth.hpp; by default with the
// statistics of the KITTI sequence-00 excerpt: 77 poses, 15,638 landmarks, 52,544 factors) so
// swf-vo can be run on it.
//   swf-vo-synth --calib F --out DIR [--poses N] [--landmarks N] [--observations N] [--seed S]
//                [--summary PATH]
// writes DIR/VO_calibration.txt, DIR/VO_camera_poses.txt and DIR/VO_stereo_factors.txt (DIR is
// created when missing), and the summary (default DIR/summary.json): the result ("ok" or
// "failed" with the reason), the files written, the problem's size and the run echoed
// (docs/cli.md).
#include <climits>
#include <cstdio>
#include <string>
#include <vector>

#include "kitti_vo.hpp"
#include "kitti_vo_synth.hpp"
#include "swf/ground_cli/ground_cli.hpp"

int main(int argc, char** argv) {
  std::string calib;
  std::string out;
  std::string summary_path;
  swf::tools::KittiLikeOptions options;
  CLI::App app{"swf-vo-synth: writes a generated kitti-vo problem for swf-vo"};
  swf::ground_cli::Adopt(&app, "swf-vo-synth");
  app.add_option("--calib", calib, "the camera (kitti-vo calibration file)")->required();
  app.add_option("--out", out, "directory for the three kitti-vo files (created when missing)")
      ->required();
  app.add_option("--poses", options.poses, "poses")
      ->capture_default_str()
      ->check(CLI::Range(1, INT_MAX));
  app.add_option("--landmarks", options.landmarks, "landmarks")
      ->capture_default_str()
      ->check(CLI::Range(1, INT_MAX));
  app.add_option("--observations", options.observations, "stereo observations")
      ->capture_default_str()
      ->check(CLI::Range(1, INT_MAX));
  app.add_option("--seed", options.seed, "random seed")->capture_default_str();
  app.add_option("--summary", summary_path, "the JSON summary (default: OUT/summary.json)");
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  if (summary_path.empty()) summary_path = out + "/summary.json";
  const std::vector<std::string> files = {out + "/VO_calibration.txt", out + "/VO_camera_poses.txt",
                                          out + "/VO_stereo_factors.txt"};
  swf::estimator::StereoCamera<double> camera;
  swf::tools::KittiVoProblem problem;
  std::string error;
  const bool ok = swf::cli::MakeDirectories(out, &error) &&
                  swf::tools::LoadKittiVoCalibration(calib, &camera, &error) &&
                  swf::tools::GenerateKittiLike(camera, options, &problem, nullptr, &error) &&
                  swf::tools::WriteKittiVo(problem, files[0], files[1], files[2], &error);
  nlohmann::ordered_json summary = {{"result", ok ? "ok" : "failed"}};
  if (ok) {
    summary["written"] = files;
    summary["poses"] = problem.poses.size();
    summary["landmarks"] = options.landmarks;
    summary["factors"] = problem.factors.size();
  } else {
    std::fprintf(stderr, "swf-vo-synth: %s\n", error.c_str());
    summary["reason"] = error;
  }
  summary["run"] = swf::ground_cli::RunEcho(app, "swf-vo-synth", argc, argv);
  if (std::string why; !swf::ground_cli::WriteJson(summary_path, summary, &why)) {
    std::fprintf(stderr, "swf-vo-synth: %s\n", why.c_str());
    return swf::cli::kExitFailed;
  }
  if (!ok) return swf::cli::kExitFailed;
  std::printf("swf-vo-synth: wrote %s: %zu poses, %d landmarks, %zu factors; summary %s\n",
              out.c_str(), problem.poses.size(), options.landmarks, problem.factors.size(),
              summary_path.c_str());
  return swf::cli::kExitOk;
}
