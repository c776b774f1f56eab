// swf-sim: renders a simulated scenario to PNG stereo pairs plus ground truth.
//   swf-sim --out DIR [--scenario descent|hover|sideways|lab] [--terrain plains|craters|rocks]
//           [--frames N] [--every K] [--seed S] [--shared DIR] [--spp 1|4] [--lcm URL] [--no-png]
//           [--summary PATH]
// --out is required: the whole default descent is ~160 MB of PNGs, not something to start by
// accident (`swf-sim` alone prints its usage, exit 2).
// Writes DIR/left_NNNN.png, right_NNNN.png, poses.csv (t_ns, position, quaternion x y z w of
// world_T_camera), landmarks.csv + observations.csv (measurement-level truth on the same terrain),
// craters.csv, rocks.csv, terrain_hazard.png (terrain height | hazard truth) and
// contact_sheet.png (12 left frames labelled with frame and altitude), drawn by swf::plot.
// The summary (default DIR/summary.json): "ok", or "failed" with the reason; the files written,
// the counts and the run echoed (docs/cli.md).
// Progress goes to stderr.
// --lcm URL also publishes every rendered pair as it is rendered: STEREO (stereo_frame_t), TRUTH
// (truth_state_t) and TRUTH_LANDMARKS (landmark_map_t), see swf/sim/lcm_publisher.hpp; --no-png
// skips the per-frame PNG files (streaming only). Every file is written under a temporary name
// and renamed when whole; SIGINT / SIGTERM remove the one being written (docs/cli.md).
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "swf/ground_cli/ground_cli.hpp"
#include "swf/plot/plot.hpp"
#include "swf/sim/hazard.hpp"
#include "swf/sim/image_io.hpp"
#include "swf/sim/lcm_publisher.hpp"
#include "swf/sim/measurement.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/trajectory.hpp"

namespace {

using swf::core::Status;

using Json = nlohmann::ordered_json;

// What the command line asked for.
struct Settings {
  std::string scenario = "descent";
  std::string terrain_name = "craters";
  std::string out;
  std::string shared;  // the shared data folder (ground_cli::SharedDir() unless --shared)
  int max_frames = -1;
  int every = 1;
  int spp = 1;
  std::uint64_t seed = 1;
  std::string lcm_url;
  bool no_png = false;
};

// The failure into the summary ("reason") and on stderr; the exit status.
int Failed(const std::string& reason, Json* summary) {
  std::fprintf(stderr, "swf-sim: %s\n", reason.c_str());
  (*summary)["reason"] = reason;
  return swf::cli::kExitFailed;
}

int Fail(const char* what, Status s, Json* summary) {
  return Failed(std::string(what) + " failed: " + swf::core::ToString(s), summary);
}

// The terrain and its hazard truth (swf::plot); false with *error saying why.
bool DrawTerrainHazard(const swf::sim::Terrain& terrain, const swf::sim::HazardMap& hazard,
                       const std::string& terrain_name, const std::string& path,
                       std::string* error) {
  swf::plot::HeightGrid grid;
  grid.size = terrain.Size();
  grid.cell_m = terrain.CellM();
  grid.x0_m = terrain.NodeX(0);
  grid.y0_m = terrain.NodeY(0);
  grid.height_m = terrain.Heights();
  grid.hazard_bits = hazard.hazard;
  const double origin[2] = {0.0, 0.0};
  if (swf::plot::DrawTerrainHazard(
          grid, false, origin, "Terrain '" + terrain_name + "' and its hazard truth", path, error))
    return true;
  *error = "cannot draw " + *error;
  return false;
}

// sim::WritePng under a temporary name, renamed when whole.
Status WritePngWhole(const std::string& path, const std::uint8_t* pixels, std::int32_t width,
                     std::int32_t height, std::int32_t channels, std::int32_t stride) {
  const std::string temp = path + ".partial";
  const int slot = swf::cli::RemovePathOnSignal(temp);
  Status s = swf::sim::WritePng(temp, pixels, width, height, channels, stride);
  if (s == Status::kOk && std::rename(temp.c_str(), path.c_str()) != 0) s = Status::kIoError;
  if (s != Status::kOk) std::remove(temp.c_str());
  swf::cli::ForgetPathOnSignal(slot);
  return s;
}

// A CSV file written whole (swf::cli::OutputFile): the header, then `rows` writes the lines;
// false with *error saying why.
template <typename Rows>
bool WriteCsv(const std::string& path, const char* header, const Rows& rows, std::string* error) {
  swf::cli::OutputFile out;
  if (!out.Open(path, error)) return false;
  std::fputs(header, out.Stream());
  rows(out.Stream());
  return out.Commit(error);
}

}  // namespace

// Renders the scenario into settings.out; the exit status, with what was written (or why not)
// in *summary.
int Simulate(const Settings& settings, Json* summary) {
  const std::string& scenario = settings.scenario;
  const std::string& terrain_name = settings.terrain_name;
  const std::string& out = settings.out;
  const std::uint64_t seed = settings.seed;
  const std::string& lcm_url = settings.lcm_url;
  const bool write_png = !settings.no_png;
  swf::sim::RigOptions rig = swf::sim::EdlRig();
  swf::sim::TrajectoryOptions traj;
  double scale = 1.0;
  if (scenario == "descent") {
    traj = swf::sim::DescentTrajectory(15.0);
  } else if (scenario == "hover") {
    traj = swf::sim::HoverTrajectory(50.0, 60);
  } else if (scenario == "sideways") {
    traj = swf::sim::SidewaysTrajectory(rig, 50.0, 0.85, 40);
  } else if (scenario == "lab") {
    rig = swf::sim::LabRig();
    traj = swf::sim::LabTrajectory(15.0);
    scale = 0.1;
  } else {
    return Failed("unknown scenario '" + scenario + "'", summary);
  }
  traj.seed = seed;
  swf::sim::TerrainPreset preset;
  if (!swf::sim::ParseTerrainPreset(terrain_name.c_str(), &preset)) {
    return Failed("unknown terrain '" + terrain_name + "'", summary);
  }
  std::string error;
  if (!swf::cli::MakeDirectories(out, &error)) return Failed("--out: " + error, summary);
  Json written = Json::array();  // every file, in the order written

  std::fprintf(stderr, "swf-sim: terrain '%s' (seed %llu) ...\n", terrain_name.c_str(),
               static_cast<unsigned long long>(seed));
  swf::sim::Terrain terrain;
  swf::sim::TerrainOptions terrain_options =
      swf::sim::ScaleTerrain(swf::sim::TerrainPresetOptions(preset, seed), scale);
  if (Status s = terrain.Configure(terrain_options); s != Status::kOk)
    return Fail("terrain", s, summary);
  swf::sim::AppearanceOptions look = swf::sim::DefaultImagery(settings.shared);
  look.image_pixel_m *= scale;
  look.seed = seed;
  swf::sim::Appearance appearance;
  if (Status s = appearance.Configure(terrain, look); s != Status::kOk) {
    return Fail("appearance (is --shared right?)", s, summary);
  }
  swf::sim::HazardOptions hazard_options;
  hazard_options.max_rock_height_m *= scale;
  hazard_options.slope_baseline_m *= scale;
  swf::sim::HazardMap hazard;
  if (Status s = swf::sim::ComputeHazardTruth(terrain, hazard_options, &hazard); s != Status::kOk) {
    return Fail("hazard truth", s, summary);
  }
  if (!DrawTerrainHazard(terrain, hazard, terrain_name, out + "/terrain_hazard.png", &error)) {
    return Failed(error, summary);
  }
  written.push_back(out + "/terrain_hazard.png");
  const bool terrain_written =
      WriteCsv(
          out + "/rocks.csv", "x_m,y_m,diameter_m,height_m,base_z_m\n",
          [&](std::FILE* f) {
            for (const auto& r : terrain.Rocks()) {
              std::fprintf(f, "%.6f,%.6f,%.6f,%.6f,%.6f\n", r.center_m.x(), r.center_m.y(),
                           r.diameter_m, r.height_m, r.base_z_m);
            }
          },
          &error) &&
      WriteCsv(
          out + "/craters.csv", "x_m,y_m,diameter_m,depth_m,rim_height_m\n",
          [&](std::FILE* f) {
            for (const auto& c : terrain.Craters()) {
              std::fprintf(f, "%.6f,%.6f,%.6f,%.6f,%.6f\n", c.center_m.x(), c.center_m.y(),
                           c.diameter_m, c.depth_m, c.rim_height_m);
            }
          },
          &error);
  if (!terrain_written) return Failed(error, summary);
  written.push_back(out + "/rocks.csv");
  written.push_back(out + "/craters.csv");

  swf::sim::Trajectory trajectory;
  if (Status s = trajectory.Configure(traj); s != Status::kOk)
    return Fail("trajectory", s, summary);
  swf::sim::MeasurementOptions mo;
  mo.trajectory = traj;
  mo.rig = rig;
  mo.surface = &terrain;
  mo.seed = seed;
  swf::sim::MeasurementScenario measurements;
  if (Status s = measurements.Configure(mo); s != Status::kOk)
    return Fail("measurements", s, summary);
  const bool measurements_written =
      WriteCsv(
          out + "/landmarks.csv", "id,x_m,y_m,z_m\n",
          [&](std::FILE* f) {
            for (size_t i = 0; i < measurements.Landmarks().size(); ++i) {
              const auto& l = measurements.Landmarks()[i];
              std::fprintf(f, "%zu,%.6f,%.6f,%.6f\n", i, l.x(), l.y(), l.z());
            }
          },
          &error) &&
      WriteCsv(
          out + "/observations.csv", "frame,landmark_id,u_left_px,u_right_px,v_px,is_outlier\n",
          [&](std::FILE* f) {
            for (int k = 0; k < measurements.NumFrames(); ++k) {
              for (const auto& o : measurements.Frame(k).observations) {
                std::fprintf(f, "%d,%d,%.6f,%.6f,%.6f,%d\n", k, o.landmark_id, o.u_left_px,
                             o.u_right_px, o.v_px, o.is_outlier ? 1 : 0);
              }
            }
          },
          &error);
  if (!measurements_written) return Failed(error, summary);
  written.push_back(out + "/landmarks.csv");
  written.push_back(out + "/observations.csv");

  swf::sim::SimLcmPublisher publisher;
  if (!lcm_url.empty()) {
    if (Status s = publisher.Open(lcm_url); s != Status::kOk) {
      return Failed("cannot open LCM at '" + lcm_url +
                        "' (udpm needs a multicast route: run inside `unshare -rn` with `ip "
                        "route add 239.0.0.0/8 dev lo`, see RECIPES.md)",
                    summary);
    }
  }
  std::vector<std::int32_t> times_observed(measurements.Landmarks().size(), 0);
  std::vector<swf::sim::TruthLandmark> visible;

  swf::sim::RenderOptions ro;
  ro.rig = rig;
  ro.seed = seed;
  ro.samples_per_pixel = settings.spp;
  swf::sim::Renderer renderer;
  if (Status s = renderer.Configure(ro); s != Status::kOk) return Fail("renderer", s, summary);
  std::vector<int> frames;
  for (int k = 0; k < trajectory.NumFrames(); k += settings.every) frames.push_back(k);
  if (settings.max_frames >= 0 && static_cast<int>(frames.size()) > settings.max_frames) {
    frames.resize(settings.max_frames);
  }

  // The contact sheet: 12 left frames spread over the run.
  constexpr int kSheetFrames = 12;
  std::vector<int> sheet_frames;
  for (int s = 0; s < kSheetFrames && !frames.empty(); ++s) {
    sheet_frames.push_back(frames[(frames.size() - 1) * s / (kSheetFrames - 1)]);
  }
  std::vector<swf::plot::ContactFrame> sheet;

  swf::cli::OutputFile poses_file;
  if (!poses_file.Open(out + "/poses.csv", &error)) return Failed(error, summary);
  std::FILE* poses = poses_file.Stream();
  std::fprintf(poses, "frame,t_ns,x_m,y_m,z_m,qx,qy,qz,qw\n");
  swf::sim::StereoImages images;
  int png_pairs = 0;
  const swf::core::TimeNs start = swf::core::MonotonicNs();
  for (size_t n = 0; n < frames.size(); ++n) {
    const int k = frames[n];
    const auto& pose = trajectory.WorldTCamera(k);
    if (Status s =
            renderer.Render(terrain, appearance, pose, static_cast<std::uint64_t>(k), &images);
        s != Status::kOk) {
      return Fail("render", s, summary);
    }
    if (write_png) {
      char left[64];
      char right[64];
      std::snprintf(left, sizeof(left), "/left_%04d.png", k);
      std::snprintf(right, sizeof(right), "/right_%04d.png", k);
      if (Status s = WritePngWhole(out + left, images.left.data(), images.width, images.height, 1,
                                   images.width);
          s != Status::kOk) {
        return Fail((out + left).c_str(), s, summary);
      }
      if (Status s = WritePngWhole(out + right, images.right.data(), images.width, images.height, 1,
                                   images.width);
          s != Status::kOk) {
        return Fail((out + right).c_str(), s, summary);
      }
      ++png_pairs;
    }
    if (!lcm_url.empty()) {
      const std::int64_t utime = trajectory.FrameTimeNs(k) / 1000;
      visible.clear();
      if (k < measurements.NumFrames()) {
        for (const auto& o : measurements.Frame(k).observations) {
          const auto id = static_cast<size_t>(o.landmark_id);
          if (o.landmark_id < 0 || id >= times_observed.size()) continue;
          // Frames between `every` steps are not served but their observations still count.
          visible.push_back({o.landmark_id, measurements.Landmarks()[id], 0});
        }
      }
      for (int j = n == 0 ? 0 : frames[n - 1] + 1; j <= k && j < measurements.NumFrames(); ++j) {
        for (const auto& o : measurements.Frame(j).observations) {
          if (o.landmark_id >= 0 && static_cast<size_t>(o.landmark_id) < times_observed.size()) {
            ++times_observed[static_cast<size_t>(o.landmark_id)];
          }
        }
      }
      for (auto& l : visible) l.num_observations = times_observed[static_cast<size_t>(l.id)];
      if (Status s = publisher.PublishFrame(images, k, utime); s != Status::kOk) {
        return Fail("LCM stereo frame", s, summary);
      }
      const double altitude_m = pose.t.z() - terrain.HeightAt(pose.t.x(), pose.t.y());
      if (Status s =
              publisher.PublishTruthPose(pose, traj.velocity_world_mps, altitude_m, k, utime);
          s != Status::kOk) {
        return Fail("LCM truth pose", s, summary);
      }
      if (Status s = publisher.PublishTruthLandmarks(visible, k, utime); s != Status::kOk) {
        return Fail("LCM truth landmarks", s, summary);
      }
    }
    const Eigen::Quaterniond q(pose.R);
    std::fprintf(poses, "%d,%lld,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f,%.12f\n", k,
                 static_cast<long long>(trajectory.FrameTimeNs(k)), pose.t.x(), pose.t.y(),
                 pose.t.z(), q.x(), q.y(), q.z(), q.w());
    if (std::find(sheet_frames.begin(), sheet_frames.end(), k) != sheet_frames.end()) {
      sheet.push_back({k, pose.t.z() - terrain.HeightAt(pose.t.x(), pose.t.y()), images.width,
                       images.height, images.left});
    }
    const double elapsed_s = (swf::core::MonotonicNs() - start) * 1e-9;
    std::fprintf(stderr, "\rswf-sim: frame %d (%zu/%zu), altitude %.1f m, %.2f s/pair", k, n + 1,
                 frames.size(), pose.t.z(), elapsed_s / static_cast<double>(n + 1));
  }
  std::fprintf(stderr, "\n");
  if (!poses_file.Commit(&error)) return Failed(error, summary);
  written.push_back(out + "/poses.csv");
  if (!swf::plot::DrawContactSheet(
          sheet, "Left camera, scenario '" + scenario + "' over terrain '" + terrain_name + "'",
          out + "/contact_sheet.png", &error)) {
    return Failed("cannot draw " + error, summary);
  }
  written.push_back(out + "/contact_sheet.png");
  (*summary)["written"] = written;
  (*summary)["png_pairs"] = png_pairs;  // left_NNNN.png, right_NNNN.png
  (*summary)["frames"] = frames.size();
  (*summary)["landmarks"] = measurements.Summary().num_landmarks;
  (*summary)["rocks"] = terrain.Rocks().size();
  (*summary)["craters"] = terrain.Craters().size();
  if (!lcm_url.empty()) (*summary)["lcm_messages"] = publisher.Published();
  std::fprintf(stderr, "swf-sim: wrote %zu pairs, %d landmarks, %zu rocks, %zu craters to %s\n",
               frames.size(), measurements.Summary().num_landmarks, terrain.Rocks().size(),
               terrain.Craters().size(), out.c_str());
  if (!lcm_url.empty()) {
    std::fprintf(stderr, "swf-sim: published %lld LCM messages to %s\n",
                 static_cast<long long>(publisher.Published()), lcm_url.c_str());
  }
  return 0;
}

int main(int argc, char** argv) {
  Settings settings;
  settings.shared = swf::ground_cli::SharedDir();
  std::string summary_path;
  CLI::App app{
      "swf-sim: renders a simulated scenario to PNG stereo pairs plus ground truth "
      "(sim/README.md)"};
  swf::ground_cli::Adopt(&app, "swf-sim");
  app.add_option("--out", settings.out,
                 "output directory (created); the default descent is ~160 MB")
      ->required();
  app.add_option("--scenario", settings.scenario)
      ->capture_default_str()
      ->check(CLI::IsMember({"descent", "hover", "sideways", "lab"}));
  app.add_option("--terrain", settings.terrain_name)
      ->capture_default_str()
      ->check(CLI::IsMember({"plains", "craters", "rocks"}));
  app.add_option("--frames", settings.max_frames, "at most N frames (default: the whole scenario)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--every", settings.every, "render every K-th frame")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--seed", settings.seed)->capture_default_str();
  app.add_option("--shared", settings.shared, "the shared data directory (orbital imagery)")
      ->capture_default_str();
  app.add_option("--spp", settings.spp, "samples per pixel")
      ->capture_default_str()
      ->check(CLI::IsMember({1, 4}));
  app.add_option("--lcm", settings.lcm_url,
                 "also publish every pair and its truth on this LCM URL");
  app.add_flag("--no-png", settings.no_png, "no per-frame PNG files (streaming only)");
  app.add_option("--summary", summary_path, "the JSON summary (default: OUT/summary.json)");
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  if (summary_path.empty()) summary_path = settings.out + "/summary.json";
  swf::cli::RemovePartialOutputsOnSignal();
  Json summary = {{"result", "failed"}};
  const int code = Simulate(settings, &summary);
  if (code == swf::cli::kExitOk) summary["result"] = "ok";
  summary["run"] = swf::ground_cli::RunEcho(app, "swf-sim", argc, argv);
  if (std::string error; !swf::ground_cli::WriteJson(summary_path, summary, &error)) {
    std::fprintf(stderr, "swf-sim: %s\n", error.c_str());
    return swf::cli::kExitFailed;
  }
  return code;
}
