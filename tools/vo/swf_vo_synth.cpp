// swf-vo-synth: writes a generated kitti-vo problem (kitti_vo_synth.hpp; by default with the
// statistics of the KITTI sequence-00 excerpt: 77 poses, 15,638 landmarks, 52,544 factors) so
// swf-vo can be run on it.
//   swf-vo-synth --calib F --out DIR [--poses N] [--landmarks N] [--observations N] [--seed S]
// writes DIR/VO_calibration.txt, DIR/VO_camera_poses.txt and DIR/VO_stereo_factors.txt.
#include <climits>
#include <cstdio>
#include <string>

#include "kitti_vo.hpp"
#include "kitti_vo_synth.hpp"

namespace {

constexpr const char* kUsage =
    "usage: swf-vo-synth --calib F --out DIR [--poses N] [--landmarks N] [--observations N]\n"
    "                    [--seed S]\n"
    "  --calib F  the camera (kitti-vo calibration file)\n"
    "  --out DIR  an existing directory for the three kitti-vo files\n"
    "  defaults: 77 poses, 15638 landmarks, 52544 observations, seed 1\n";

int Usage(const std::string& why) {
  std::fprintf(stderr, "swf-vo-synth: %s\n%s", why.c_str(), kUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string calib;
  std::string out;
  swf::tools::KittiLikeOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    const bool known = arg == "--calib" || arg == "--out" || arg == "--poses" ||
                       arg == "--landmarks" || arg == "--observations" || arg == "--seed";
    if (!known) return Usage("unknown option " + arg);
    if (i + 1 >= argc) return Usage("missing value for " + arg);
    const std::string value = argv[++i];
    long long k = 0;
    if (arg == "--calib") {
      calib = value;
    } else if (arg == "--out") {
      out = value;
    } else if (!swf::tools::ParseCount(value, arg == "--seed" ? LLONG_MAX : INT_MAX, &k)) {
      return Usage(arg + " takes a positive integer");
    } else if (arg == "--poses") {
      options.poses = static_cast<int>(k);
    } else if (arg == "--landmarks") {
      options.landmarks = static_cast<int>(k);
    } else if (arg == "--observations") {
      options.observations = static_cast<int>(k);
    } else {
      options.seed = static_cast<std::uint64_t>(k);
    }
  }
  if (calib.empty() || out.empty()) return Usage("--calib and --out are required");
  swf::estimator::StereoCamera<double> camera;
  swf::tools::KittiVoProblem problem;
  std::string error;
  if (!swf::tools::LoadKittiVoCalibration(calib, &camera, &error) ||
      !swf::tools::GenerateKittiLike(camera, options, &problem, nullptr, &error) ||
      !swf::tools::WriteKittiVo(problem, out + "/VO_calibration.txt", out + "/VO_camera_poses.txt",
                                out + "/VO_stereo_factors.txt", &error)) {
    std::fprintf(stderr, "swf-vo-synth: %s\n", error.c_str());
    return 1;
  }
  std::printf("swf-vo-synth: wrote %s: %zu poses, %d landmarks, %zu factors\n", out.c_str(),
              problem.poses.size(), options.landmarks, problem.factors.size());
  return 0;
}
