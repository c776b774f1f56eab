// swf-track: runs the flight front end's components on image files.
//   swf-track flow IMG1 IMG2        Harris features of IMG1 tracked into IMG2 (pyramidal LK)
//   swf-track stereo LEFT RIGHT     Harris features of a rectified pair matched along rows
//   swf-track rectify CAM0.yaml CAM1.yaml LEFT RIGHT OUT.png
//                                   rectifies a raw pair and writes it side by side with
//                                   epipolar lines (every 24 rows)
// flow/stereo print one JSON object with a `features` array ({x, y, dx, dy} or
// {x, y, disparity}, pixels) and exit 0; errors go to stderr with exit code 1 (usage: 2;
// docs/cli.md). rectify creates OUT.png's directory.
#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>

#include "swf/frontend/harris.hpp"
#include "swf/frontend/rectify.hpp"
#include "swf/frontend/stereo_matcher.hpp"
#include "swf/frontend/tracker.hpp"
#include "swf/ground_cli/ground_cli.hpp"
#include "swf/image_io/image_io.hpp"

namespace {

using nlohmann::json;
using swf::core::Status;
using swf::frontend::CornerList;
using swf::frontend::HarrisDetector;
using swf::frontend::HarrisOptions;
using swf::ground_cli::Number;
using swf::image_io::GrayImage;

bool Load(const char* path, GrayImage* image) {
  std::string error;
  if (!swf::image_io::LoadGray(path, image, &error)) {
    std::fprintf(stderr, "swf-track: %s\n", error.c_str());
    return false;
  }
  if (image->width > swf::frontend::kMaxImageWidth ||
      image->height > swf::frontend::kMaxImageHeight) {
    std::fprintf(stderr, "swf-track: %s: %dx%d exceeds the front end's %dx%d\n", path, image->width,
                 image->height, swf::frontend::kMaxImageWidth, swf::frontend::kMaxImageHeight);
    return false;
  }
  // The detector needs its border on both sides plus a 3 px interior.
  const int min_side = 2 * HarrisOptions{}.border_px + 3;
  if (image->width < min_side || image->height < min_side) {
    std::fprintf(stderr, "swf-track: %s: %dx%d is smaller than the front end's minimum of %dx%d\n",
                 path, image->width, image->height, min_side, min_side);
    return false;
  }
  return true;
}

// About one feature per 40x40 pixels, spread by bucketing.
HarrisOptions DetectorOptions(int width, int height) {
  HarrisOptions o;
  o.bucket_cols = std::max(1, std::min(64, width / 40));
  o.bucket_rows = std::max(1, std::min(64, height / 40));
  o.max_per_bucket = 2;
  return o;
}

bool Detect(const char* path, const GrayImage& image, CornerList* corners) {
  auto detector = std::make_unique<HarrisDetector>();
  Status st = detector->Configure(DetectorOptions(image.width, image.height));
  if (st == Status::kOk) st = detector->Detect(image.View(), nullptr, 0, corners);
  if (st != Status::kOk) {
    std::fprintf(stderr, "swf-track: %s: feature detection failed (%s)\n", path,
                 swf::core::ToString(st));
    return false;
  }
  return true;
}

// The two images of a pair (of one size) and the features detected in the first.
bool LoadPairAndDetect(const char* a_path, const char* b_path, GrayImage* a, GrayImage* b,
                       CornerList* corners) {
  if (!Load(a_path, a) || !Load(b_path, b)) return false;
  if (a->width != b->width || a->height != b->height) {
    std::fprintf(stderr, "swf-track: %s is %dx%d but %s is %dx%d\n", b_path, b->width, b->height,
                 a_path, a->width, a->height);
    return false;
  }
  return Detect(a_path, *a, corners);
}

// The printed JSON object around its feature list: the mode, the image size, the detections and
// the run (docs/cli.md).
json Report(const char* mode, const GrayImage& image, std::size_t detected, const json& run) {
  return {{"mode", mode},         {"width_px", image.width},   {"height_px", image.height},
          {"detected", detected}, {"features", json::array()}, {"run", run}};
}

int Flow(const char* a_path, const char* b_path, const json& run) {
  GrayImage a;
  GrayImage b;
  auto corners = std::make_unique<CornerList>();
  if (!LoadPairAndDetect(a_path, b_path, &a, &b, corners.get())) return 1;
  auto prev = std::make_unique<swf::frontend::Pyramid>();
  auto cur = std::make_unique<swf::frontend::Pyramid>();
  swf::frontend::PatchTracker tracker;
  const swf::frontend::TrackerOptions options;
  if (prev->Build(a.View(), options.pyramid_levels) != Status::kOk ||
      cur->Build(b.View(), options.pyramid_levels) != Status::kOk ||
      tracker.Configure(options) != Status::kOk) {
    std::fprintf(stderr, "swf-track: %s, %s: tracker set-up failed\n", a_path, b_path);
    return 1;
  }
  json report = Report("flow", a, corners->size(), run);
  for (const auto& c : *corners) {
    float x = c.x;
    float y = c.y;
    float q = 0.0f;
    if (!tracker.TrackFlow(*prev, *cur, c.x, c.y, &x, &y, &q)) continue;
    report["features"].push_back({{"x", Number(c.x)},
                                  {"y", Number(c.y)},
                                  {"dx", Number(x - c.x)},
                                  {"dy", Number(y - c.y)},
                                  {"quality", Number(q)}});
  }
  swf::ground_cli::PrintJson(report, 1);
  return 0;
}

int Stereo(const char* l_path, const char* r_path, const json& run) {
  GrayImage l;
  GrayImage r;
  auto corners = std::make_unique<CornerList>();
  if (!LoadPairAndDetect(l_path, r_path, &l, &r, corners.get())) return 1;
  swf::frontend::StereoMatcher matcher;
  swf::frontend::StereoMatcherOptions options;
  options.max_disparity = std::min(swf::frontend::kMaxDisparity, l.width / 4);
  auto matches = std::make_unique<swf::frontend::StereoMatchList>();
  if (matcher.Configure(options) != Status::kOk ||
      matcher.MatchAll(l.View(), r.View(), *corners, matches.get()) != Status::kOk) {
    std::fprintf(stderr, "swf-track: %s, %s: stereo matching failed\n", l_path, r_path);
    return 1;
  }
  json report = Report("stereo", l, corners->size(), run);
  for (const auto& m : *matches) {
    report["features"].push_back({{"x", Number(m.x)},
                                  {"y", Number(m.y)},
                                  {"disparity", Number(m.disparity)},
                                  {"quality", Number(m.quality)}});
  }
  swf::ground_cli::PrintJson(report, 1);
  return 0;
}

int Rectify(const char* cam0, const char* cam1, const char* l_path, const char* r_path,
            const char* out_path, const json& run) {
  swf::frontend::CameraCalibration c0;
  swf::frontend::CameraCalibration c1;
  std::string error;
  if (!swf::image_io::LoadCalibration(cam0, &c0, &error) ||
      !swf::image_io::LoadCalibration(cam1, &c1, &error)) {
    std::fprintf(stderr, "swf-track: %s\n", error.c_str());
    return 1;
  }
  GrayImage l;
  GrayImage r;
  if (!Load(l_path, &l) || !Load(r_path, &r)) return 1;
  auto rectifier = std::make_unique<swf::frontend::StereoRectifier>();
  if (rectifier->Configure(c0, c1, swf::frontend::RectifyOptions{}) != Status::kOk) {
    std::fprintf(stderr, "swf-track: %s, %s: the rectifier refuses this calibration pair\n", cam0,
                 cam1);
    return 1;
  }
  GrayImage rl;
  GrayImage rr;
  rl.Resize(rectifier->Width(), rectifier->Height());
  rr.Resize(rectifier->Width(), rectifier->Height());
  if (rectifier->Rectify(l.View(), r.View(), rl.MutableView(), rr.MutableView()) != Status::kOk) {
    std::fprintf(stderr, "swf-track: %s (%dx%d), %s (%dx%d): image size does not match %s\n",
                 l_path, l.width, l.height, r_path, r.width, r.height, cam0);
    return 1;
  }
  swf::image_io::RgbImage out;
  out.width = 2 * rl.width;
  out.height = rl.height;
  out.pixels.assign(static_cast<std::size_t>(out.width) * out.height * 3, 0);
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const GrayImage& src = x < rl.width ? rl : rr;
      const std::uint8_t g = src.pixels[static_cast<std::size_t>(y) * src.width + x % rl.width];
      std::uint8_t* p = &out.pixels[(static_cast<std::size_t>(y) * out.width + x) * 3];
      const bool line = y % 24 == 12;
      p[0] = line ? 255 : g;
      p[1] = line ? static_cast<std::uint8_t>(g / 2) : g;
      p[2] = line ? 0 : g;
    }
  }
  if (!swf::cli::MakeParentDirectories(out_path, &error) ||
      !swf::image_io::SavePng(out_path, out, &error)) {
    std::fprintf(stderr, "swf-track: %s\n", error.c_str());
    return 1;
  }
  const auto& cam = rectifier->Camera();
  const json report = {{"mode", "rectify"},
                       {"fx_px", Number(cam.fx)},
                       {"cx_px", Number(cam.cx)},
                       {"cy_px", Number(cam.cy)},
                       {"baseline_m", Number(cam.baseline_m)},
                       {"out", out_path},
                       {"run", run}};
  swf::ground_cli::PrintJson(report, 1);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"swf-track: the flight front end's components on image files"};
  swf::ground_cli::Adopt(&app, "swf-track");
  app.require_subcommand(1);
  std::string a;
  std::string b;
  CLI::App* flow = app.add_subcommand("flow", "Harris features of IMG1 tracked into IMG2 (LK)");
  flow->add_option("IMG1", a)->required()->check(CLI::ExistingFile);
  flow->add_option("IMG2", b)->required()->check(CLI::ExistingFile);
  CLI::App* stereo =
      app.add_subcommand("stereo", "Harris features of a rectified pair matched along rows");
  stereo->add_option("LEFT", a)->required()->check(CLI::ExistingFile);
  stereo->add_option("RIGHT", b)->required()->check(CLI::ExistingFile);
  std::string cam0;
  std::string cam1;
  std::string out;
  CLI::App* rectify = app.add_subcommand(
      "rectify", "a raw pair rectified, side by side with epipolar lines every 24 rows");
  rectify->add_option("CAM0", cam0, "left calibration (sensor.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  rectify->add_option("CAM1", cam1, "right calibration")->required()->check(CLI::ExistingFile);
  rectify->add_option("LEFT", a)->required()->check(CLI::ExistingFile);
  rectify->add_option("RIGHT", b)->required()->check(CLI::ExistingFile);
  rectify->add_option("OUT", out, "the PNG to write (its directory is created)")->required();
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  const json run = swf::ground_cli::RunEcho(app, "swf-track", argc, argv);
  if (flow->parsed()) return Flow(a.c_str(), b.c_str(), run);
  if (stereo->parsed()) return Stereo(a.c_str(), b.c_str(), run);
  return Rectify(cam0.c_str(), cam1.c_str(), a.c_str(), b.c_str(), out.c_str(), run);
}
