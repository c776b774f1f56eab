// swf-convert: datasets into LCM logs for swf-replay, logs back out into PNG pairs and trajectory
// files, calibrations into the form swf-fsw reads (tools/convert/README.md).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "swf/calibration/calibration_import.hpp"
#include "swf/convert/convert.hpp"
#include "swf/ground_cli/ground_cli.hpp"

namespace {

using nlohmann::json;

int Fail(const std::string& error) {
  std::fprintf(stderr, "swf-convert: %s\n", error.c_str());
  return 1;
}

json SummaryJson(const swf::convert::InputSummary& s, const swf::convert::LogInputOptions& o) {
  return {{"log", o.log_path},
          {"frames", s.frames},
          {"imu_samples", s.imu_samples},
          {"truth_poses", s.truth_poses},
          {"width", s.width},
          {"height", s.height},
          {"calibration_dir", o.calib_dir}};
}

// The three dataset inputs share their options.
struct InputCommand {
  std::string dir;
  swf::convert::LogInputOptions options;
};

CLI::App* AddInput(CLI::App& app, const char* name, const char* what, InputCommand* c) {
  CLI::App* sub = app.add_subcommand(name, what);
  sub->add_option("DIR", c->dir, "the dataset folder")->required()->check(CLI::ExistingDirectory);
  sub->add_option("--out", c->options.log_path, "the LCM log to write")->required();
  sub->add_option("--max-frames", c->options.max_frames, "only the first N frames")
      ->check(CLI::NonNegativeNumber);
  return sub;
}

int RunCalibration(const std::vector<std::string>& files, const std::string& format_name,
                   const std::string& size, double max_error_px, const std::string& out,
                   const json& run) {
  swf::calibration::ImportOptions options;
  if (!swf::calibration::ParseFormatName(format_name, &options.format)) {
    return Fail("--format " + format_name +
                ": not one of auto, euroc, ros, kalibr, opencv, kitti, cahvor");
  }
  if (!size.empty() && std::sscanf(size.c_str(), "%dx%d", &options.width, &options.height) != 2) {
    return Fail("--size " + size + ": expected WxH, e.g. 1226x370");
  }
  options.max_linearization_error_px = max_error_px;
  swf::calibration::StereoCalibration c;
  swf::calibration::RectifiedPair pair;
  std::string error;
  if (!swf::calibration::ImportStereoCalibration(files, options, &c, &error) ||
      !swf::calibration::RectifyCalibration(c, &pair, &error)) {
    return Fail(error);
  }
  if (!out.empty()) {
    for (const auto& [name, camera] : {std::pair{"left", c.left}, std::pair{"right", c.right}}) {
      if (!swf::cli::WriteFileAtomically(out + "/" + name + ".yaml",
                                         swf::calibration::EurocSensorYaml(camera), &error)) {
        return Fail(error);
      }
    }
  }
  const json report = {{"format", swf::calibration::FormatName(c.format)},
                       {"width", pair.width},
                       {"height", pair.height},
                       {"rectified_fx", pair.camera.fx},
                       {"rectified_fy", pair.camera.fy},
                       {"rectified_cx", pair.camera.cx},
                       {"rectified_cy", pair.camera.cy},
                       {"baseline_m", pair.camera.baseline_m},
                       {"linearization_error_px", c.linearization_error_px},
                       {"written_to", out},
                       {"run", run}};
  swf::ground_cli::PrintJson(report);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "swf-convert: datasets to LCM logs for swf-replay, logs to PNG pairs and trajectories, "
      "calibrations to swf-fsw's form"};
  swf::ground_cli::Adopt(&app, "swf-convert");
  app.require_subcommand(1);

  InputCommand euroc;
  InputCommand kitti;
  InputCommand grab;
  CLI::App* euroc_cmd =
      AddInput(app, "euroc", "EuRoC ASL folder -> log (frames, IMU, truth)", &euroc);
  CLI::App* kitti_cmd =
      AddInput(app, "kitti", "KITTI odometry folder -> log (frames, truth)", &kitti);
  CLI::App* grab_cmd = AddInput(app, "grab", "swf-grab PNG pairs -> log (frames)", &grab);
  for (auto [cmd, c] : {std::pair{euroc_cmd, &euroc}, std::pair{kitti_cmd, &kitti}}) {
    cmd->add_option("--calib-out", c->options.calib_dir,
                    "write left.yaml / right.yaml (EuRoC sensor.yaml) for swf-replay here");
  }
  grab_cmd->add_option("--rate-hz", grab.options.rate_hz, "frame rate (time = seq / rate)")
      ->check(CLI::PositiveNumber);

  std::string log_path;
  std::string channel = "SWF_STEREO";
  std::string out_dir;
  CLI::App* pngs_cmd = app.add_subcommand("pngs", "log -> PNG pairs (left_NNNNNN.png, right_...)");
  pngs_cmd->add_option("LOG", log_path, "LCM log")->required()->check(CLI::ExistingFile);
  pngs_cmd->add_option("--out", out_dir, "output folder")->required();
  pngs_cmd->add_option("--channel", channel, "stereo_frame_t channel");

  std::string nav_channel = "SWF_NAV";
  std::string tum_path;
  std::string kitti_path;
  CLI::App* traj_cmd =
      app.add_subcommand("trajectory", "a run's recording -> TUM and/or KITTI trajectory");
  traj_cmd->add_option("LOG", log_path, "LCM log (swf-replay --record, swf-fsw record.path)")
      ->required()
      ->check(CLI::ExistingFile);
  traj_cmd->add_option("--tum", tum_path, "TUM file to write");
  traj_cmd->add_option("--kitti", kitti_path, "KITTI poses file to write");
  traj_cmd->add_option("--channel", nav_channel, "nav_state_t channel");
  bool anchor_first = false;
  traj_cmd->add_flag("--anchor-first", anchor_first,
                     "poses in the first output's camera frame (KITTI: first pose = identity)");

  std::string euroc_dir;
  CLI::App* ate_cmd =
      app.add_subcommand("ate", "ATE of a TUM trajectory against EuRoC truth (swf-eval's code)");
  ate_cmd->add_option("--tum", tum_path, "estimate, TUM")->required()->check(CLI::ExistingFile);
  ate_cmd->add_option("--euroc", euroc_dir, "EuRoC folder")
      ->required()
      ->check(CLI::ExistingDirectory);

  std::vector<std::string> calib_files;
  std::string format = "auto";
  std::string size;
  double max_error_px = 0.5;
  CLI::App* calib_cmd = app.add_subcommand("calib", "calibration import (docs/calibration.md)");
  calib_cmd->add_option("FILES", calib_files, "one or two files (left, right)")
      ->required()
      ->check(CLI::ExistingFile);
  calib_cmd->add_option("--format", format, "auto|euroc|ros|kalibr|opencv|kitti|cahvor");
  calib_cmd->add_option("--size", size, "image size WxH (KITTI; OpenCV without one)");
  calib_cmd->add_option("--max-linearization-error-px", max_error_px, "CAHVOR/CAHVORE limit")
      ->check(CLI::PositiveNumber);
  calib_cmd->add_option("--out", out_dir, "write left.yaml / right.yaml here");

  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  // Every summary printed echoes the run (docs/cli.md).
  const json run = swf::ground_cli::RunEcho(app, "swf-convert", argc, argv);
  const auto print = [&run](json summary) {
    summary["run"] = run;
    swf::ground_cli::PrintJson(summary);
  };

  std::string error;
  for (auto [cmd, c, run] : {std::tuple{euroc_cmd, &euroc, &swf::convert::EurocToLog},
                             std::tuple{kitti_cmd, &kitti, &swf::convert::KittiToLog},
                             std::tuple{grab_cmd, &grab, &swf::convert::GrabToLog}}) {
    if (!cmd->parsed()) continue;
    swf::convert::InputSummary summary;
    if (!run(c->dir, c->options, &summary, &error)) return Fail(error);
    print(SummaryJson(summary, c->options));
    return 0;
  }
  if (pngs_cmd->parsed()) {
    std::int64_t pairs = 0;
    if (!swf::convert::LogToPngs(log_path, channel, out_dir, &pairs, &error)) return Fail(error);
    print({{"pairs", pairs}, {"out", out_dir}});
    return 0;
  }
  if (traj_cmd->parsed()) {
    if (tum_path.empty() && kitti_path.empty())
      return Fail("trajectory: give --tum and/or --kitti");
    std::int64_t poses = 0;
    if (!swf::convert::LogToTrajectory(log_path, nav_channel, tum_path, kitti_path, anchor_first,
                                       &poses, &error))
      return Fail(error);
    print({{"poses", poses}, {"tum", tum_path}, {"kitti", kitti_path}});
    return 0;
  }
  if (ate_cmd->parsed()) {
    swf::convert::AteResult r;
    if (!swf::convert::TumAteAgainstEuroc(tum_path, euroc_dir, &r, &error)) return Fail(error);
    print({{"matched", r.matched},
           {"ate_rmse_m", swf::ground_cli::Number(r.ate_rmse_m)},
           {"ate_max_m", swf::ground_cli::Number(r.ate_max_m)}});
    return 0;
  }
  return RunCalibration(calib_files, format, size, max_error_px, out_dir, run);
}
