// swf-track: runs the flight front end's components on image files.
//   swf-track flow IMG1 IMG2        Harris features of IMG1 tracked into IMG2 (pyramidal LK)
//   swf-track stereo LEFT RIGHT     Harris features of a rectified pair matched along rows
//   swf-track rectify CAM0.yaml CAM1.yaml LEFT RIGHT OUT.png
//                                   rectifies a raw pair and writes it side by side with
//                                   epipolar lines (every 24 rows)
// flow/stereo print one JSON object with a `features` array ({x, y, dx, dy} or
// {x, y, disparity}, pixels) and exit 0; errors go to stderr with exit code 1 (usage: 2).
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "swf/frontend/harris.hpp"
#include "swf/frontend/rectify.hpp"
#include "swf/frontend/stereo_matcher.hpp"
#include "swf/frontend/tracker.hpp"
#include "swf/image_io/image_io.hpp"

namespace {

using swf::core::Status;
using swf::frontend::CornerList;
using swf::frontend::HarrisDetector;
using swf::frontend::HarrisOptions;
using swf::image_io::GrayImage;

int Usage() {
  std::fprintf(stderr,
               "usage: swf-track flow IMG1 IMG2\n"
               "       swf-track stereo LEFT RIGHT\n"
               "       swf-track rectify CAM0.yaml CAM1.yaml LEFT RIGHT OUT.png\n");
  return 2;
}

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

// The printed JSON object up to its feature list: the mode, the image size, the detections.
void PrintHeader(const char* mode, const GrayImage& image, std::size_t detected) {
  std::printf(
      "{\"mode\": \"%s\", \"width_px\": %d, \"height_px\": %d, \"detected\": %zu, "
      "\"features\": [",
      mode, image.width, image.height, detected);
}

int Flow(const char* a_path, const char* b_path) {
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
  PrintHeader("flow", a, corners->size());
  const char* sep = "";
  for (const auto& c : *corners) {
    float x = c.x;
    float y = c.y;
    float q = 0.0f;
    if (!tracker.TrackFlow(*prev, *cur, c.x, c.y, &x, &y, &q)) continue;
    std::printf("%s\n  {\"x\": %.0f, \"y\": %.0f, \"dx\": %.4f, \"dy\": %.4f, \"quality\": %.4f}",
                sep, c.x, c.y, x - c.x, y - c.y, q);
    sep = ",";
  }
  std::printf("\n]}\n");
  return 0;
}

int Stereo(const char* l_path, const char* r_path) {
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
  PrintHeader("stereo", l, corners->size());
  const char* sep = "";
  for (const auto& m : *matches) {
    std::printf("%s\n  {\"x\": %.0f, \"y\": %.0f, \"disparity\": %.4f, \"quality\": %.4f}", sep,
                m.x, m.y, m.disparity, m.quality);
    sep = ",";
  }
  std::printf("\n]}\n");
  return 0;
}

int Rectify(const char* cam0, const char* cam1, const char* l_path, const char* r_path,
            const char* out_path) {
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
  if (!swf::image_io::SavePng(out_path, out, &error)) {
    std::fprintf(stderr, "swf-track: %s\n", error.c_str());
    return 1;
  }
  const auto& cam = rectifier->Camera();
  std::printf(
      "{\"mode\": \"rectify\", \"fx_px\": %.3f, \"cx_px\": %.3f, \"cy_px\": %.3f, "
      "\"baseline_m\": %.5f, \"out\": \"%s\"}\n",
      cam.fx, cam.cx, cam.cy, cam.baseline_m, out_path);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "flow") == 0) return Flow(argv[2], argv[3]);
  if (argc == 4 && std::strcmp(argv[1], "stereo") == 0) return Stereo(argv[2], argv[3]);
  if (argc == 7 && std::strcmp(argv[1], "rectify") == 0) {
    return Rectify(argv[2], argv[3], argv[4], argv[5], argv[6]);
  }
  return Usage();
}
