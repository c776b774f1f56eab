// swf-grab: lists cameras and grabs N stereo pairs to PNG with timing and drop statistics.
//   swf-grab list
//   swf-grab grab --source aravis --left 192.168.1.10 --right 192.168.1.11 --pairs 50 --out cap/
//   swf-grab grab --source v4l2 --left /dev/video0 --right /dev/video2 --format GREY --pairs 50
// Run `swf-grab help` for every option. Not flight code: it allocates, prints and writes files.
#include <arv.h>
#include <linux/videodev2.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "png_writer.hpp"
#include "swf/drivers/aravis_stereo_source.hpp"
#include "swf/drivers/v4l2_stereo_source.hpp"

namespace swf::drivers {
namespace {

struct GrabArgs {
  std::string source = "aravis";
  std::string left;
  std::string right;
  bool side_by_side = false;
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::string format;  // V4L2: GREY|Y16|YUYV; Aravis: Mono8|Mono12|...
  int pairs = 10;
  std::string out = "grab";
  core::TimeNs timeout_ns = core::kNsPerS;
  std::string trigger = "free";
  double fps = 0.0;
  double exposure_us = -1.0;
  double gain = -1.0;
  std::int32_t packet_size = 0;
  std::string features;
  double tolerance_ms = 5.0;
  bool fake_gv = false;  // start Aravis GigE fake cameras in-process at --left/--right
  double fake_loss = 0.0;
};

void PrintHelp() {
  std::printf(
      "usage: swf-grab list\n"
      "       swf-grab grab [options]\n"
      "  --source aravis|v4l2     camera driver (default aravis)\n"
      "  --left ID --right ID     Aravis id/serial/IP, or V4L2 device node\n"
      "  --side-by-side           one device delivers [left|right] (--right unused)\n"
      "  --width W --height H     requested size / region of interest\n"
      "  --format F               V4L2: GREY|Y16|YUYV; Aravis: Mono8|Mono10|Mono12|Mono16\n"
      "  --pairs N --out DIR      pairs to grab, output directory (left_NNNNNN.png, ...)\n"
      "  --timeout-ms T           per-pair timeout (default 1000)\n"
      "  --trigger free|software|hardware   Aravis trigger mode (hardware uses Line1)\n"
      "  --fps F --exposure-us E --gain G --packet-size P --tolerance-ms T\n"
      "  --features \"Name=Value ...\"        extra GenICam features (Aravis)\n"
      "  --fake-gv [--fake-loss R]          serve Aravis GigE fake cameras at --left/--right\n"
      "                                     (run inside `unshare -n`, see drivers/README.md)\n");
}

int List() {
  arv_update_device_list();
  const unsigned n = arv_get_n_devices();
  std::printf("Aravis (GigE Vision / USB3 Vision): %u camera(s)\n", n);
  for (unsigned i = 0; i < n; ++i) {
    std::printf("  %s  address %s  serial %s  model %s\n", arv_get_device_id(i),
                arv_get_device_address(i) ? arv_get_device_address(i) : "-",
                arv_get_device_serial_nbr(i) ? arv_get_device_serial_nbr(i) : "-",
                arv_get_device_model(i) ? arv_get_device_model(i) : "-");
  }
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) == 0) nodes.push_back(entry.path().string());
  }
  std::sort(nodes.begin(), nodes.end());
  std::printf("V4L2: %zu node(s)\n", nodes.size());
  V4l2Kernel& kernel = LinuxV4l2Kernel();
  for (const std::string& node : nodes) {
    const int fd = kernel.Open(node.c_str());
    if (fd < 0) {
      std::printf("  %s  (cannot open: %s)\n", node.c_str(), std::strerror(-fd));
      continue;
    }
    v4l2_capability cap{};
    if (kernel.Ioctl(fd, VIDIOC_QUERYCAP, &cap) == 0) {
      const std::uint32_t caps =
          (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
      std::printf("  %s  %s (%s)%s\n", node.c_str(), reinterpret_cast<const char*>(cap.card),
                  reinterpret_cast<const char*>(cap.driver),
                  (caps & V4L2_CAP_VIDEO_CAPTURE) != 0 && (caps & V4L2_CAP_STREAMING) != 0
                      ? "  capture+streaming"
                      : "  (not a streaming capture node)");
    }
    (void)kernel.Close(fd);
  }
  return 0;
}

bool ParseArgs(int argc, char** argv, GrabArgs* a) {
  for (int i = 2; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> const char* { return i + 1 < argc ? argv[++i] : ""; };
    if (k == "--source")
      a->source = value();
    else if (k == "--left")
      a->left = value();
    else if (k == "--right")
      a->right = value();
    else if (k == "--side-by-side")
      a->side_by_side = true;
    else if (k == "--width")
      a->width = std::atoi(value());
    else if (k == "--height")
      a->height = std::atoi(value());
    else if (k == "--format")
      a->format = value();
    else if (k == "--pairs")
      a->pairs = std::atoi(value());
    else if (k == "--out")
      a->out = value();
    else if (k == "--timeout-ms")
      a->timeout_ns = std::atoll(value()) * core::kNsPerMs;
    else if (k == "--trigger")
      a->trigger = value();
    else if (k == "--fps")
      a->fps = std::atof(value());
    else if (k == "--exposure-us")
      a->exposure_us = std::atof(value());
    else if (k == "--gain")
      a->gain = std::atof(value());
    else if (k == "--packet-size")
      a->packet_size = std::atoi(value());
    else if (k == "--features")
      a->features = value();
    else if (k == "--tolerance-ms")
      a->tolerance_ms = std::atof(value());
    else if (k == "--fake-gv")
      a->fake_gv = true;
    else if (k == "--fake-loss")
      a->fake_loss = std::atof(value());
    else {
      std::fprintf(stderr, "swf-grab: unknown option %s\n", k.c_str());
      return false;
    }
  }
  if (a->left.empty() || (a->right.empty() && !a->side_by_side) || a->pairs <= 0) {
    std::fprintf(stderr, "swf-grab: need --left, --right (or --side-by-side) and --pairs > 0\n");
    return false;
  }
  return true;
}

std::unique_ptr<StereoSource> MakeSource(const GrabArgs& a, core::Status* status,
                                         std::string* error) {
  const core::TimeNs tolerance_ns = static_cast<core::TimeNs>(a.tolerance_ms * 1e6);
  if (a.source == "v4l2") {
    auto src = std::make_unique<V4l2StereoSource>();
    V4l2StereoOptions o;
    o.left.device = a.left.c_str();
    o.right.device = a.right.c_str();
    o.side_by_side = a.side_by_side;
    o.pair_tolerance_ns = tolerance_ns;
    for (V4l2CameraOptions* c : {&o.left, &o.right}) {
      if (a.width > 0) c->width = a.width;
      if (a.height > 0) c->height = a.height;
      if (a.format == "Y16") c->format = PixelFormat::kGray16Le;
      if (a.format == "YUYV") c->format = PixelFormat::kYuyv;
      if (a.exposure_us >= 0) c->exposure_100us = static_cast<std::int32_t>(a.exposure_us / 100.0);
      if (a.gain >= 0) c->gain = static_cast<std::int32_t>(a.gain);
      c->buffer_count = 6;
    }
    *status = src->Configure(o);
    if (core::IsOk(*status)) *status = src->Start();
    *error = src->LastError();
    return src;
  }
  auto src = std::make_unique<AravisStereoSource>();
  AravisStereoOptions o;
  o.left_id = a.left.c_str();
  o.right_id = a.right.c_str();
  o.side_by_side = a.side_by_side;
  if (!a.format.empty()) o.pixel_format = a.format.c_str();
  o.width = a.width;
  o.height = a.height;
  o.frame_rate_hz = a.fps;
  o.exposure_us = a.exposure_us;
  o.gain = a.gain;
  o.packet_size = a.packet_size;
  o.features = a.features.empty() ? nullptr : a.features.c_str();
  o.pair_tolerance_ns = tolerance_ns;
  o.trigger = a.trigger == "software"   ? TriggerMode::kSoftware
              : a.trigger == "hardware" ? TriggerMode::kHardware
                                        : TriggerMode::kFreeRun;
  *status = src->Configure(o);
  if (core::IsOk(*status)) *status = src->Start();
  *error = src->LastError();
  return src;
}

int Grab(const GrabArgs& a) {
  std::vector<ArvGvFakeCamera*> fakes;
  if (a.fake_gv) {
    for (const std::string& address : {a.left, a.right}) {
      if (address.empty()) continue;
      ArvGvFakeCamera* fake = arv_gv_fake_camera_new(address.c_str(), nullptr);
      if (fake == nullptr || !arv_gv_fake_camera_is_running(fake)) {
        std::fprintf(stderr, "swf-grab: cannot serve a fake camera on %s\n", address.c_str());
        return 2;
      }
      if (address == a.right && a.fake_loss > 0) {
        g_object_set(fake, "gvsp-lost-ratio", a.fake_loss, nullptr);
      }
      fakes.push_back(fake);
    }
  }
  core::Status status = core::Status::kOk;
  std::string error;
  std::unique_ptr<StereoSource> source = MakeSource(a, &status, &error);
  if (!core::IsOk(status)) {
    std::fprintf(stderr, "swf-grab: start failed: %s: %s\n", core::ToString(status), error.c_str());
    for (ArvGvFakeCamera* f : fakes) g_object_unref(f);
    return 1;
  }
  std::filesystem::create_directories(a.out);
  std::vector<double> next_ms;
  int written = 0;
  int failures = 0;
  const core::Stopwatch total;
  for (int i = 0; i < a.pairs && failures < 5; ++i) {
    StereoPair pair;
    const core::Stopwatch watch;
    status = source->Next(a.timeout_ns, &pair);
    next_ms.push_back(core::NsToMs(watch.ElapsedNs()));
    if (!core::IsOk(status)) {
      ++failures;
      std::fprintf(stderr, "pair %d: %s: %s\n", i, core::ToString(status), source->LastError());
      if (status == core::Status::kDeviceLost || status == core::Status::kIoError) break;
      continue;
    }
    char path[512];
    std::snprintf(path, sizeof(path), "%s/left_%06llu.png", a.out.c_str(),
                  static_cast<unsigned long long>(pair.seq));
    bool ok = WriteGrayPng(path, pair.left);
    std::snprintf(path, sizeof(path), "%s/right_%06llu.png", a.out.c_str(),
                  static_cast<unsigned long long>(pair.seq));
    ok = WriteGrayPng(path, pair.right) && ok;
    written += ok ? 1 : 0;
    std::printf("pair %llu  %dx%d  left-right %+.3f ms  dropped_before %u  next %.2f ms\n",
                static_cast<unsigned long long>(pair.seq), pair.left.width, pair.left.height,
                core::NsToMs(pair.left_exposure_ns - pair.right_exposure_ns), pair.dropped_before,
                next_ms.back());
    source->Release(pair);
  }
  const double elapsed_s = core::NsToMs(total.ElapsedNs()) / 1000.0;
  const SourceStats s = source->Stats();
  source->Stop();
  for (ArvGvFakeCamera* f : fakes) g_object_unref(f);
  std::sort(next_ms.begin(), next_ms.end());
  const double p50 = next_ms.empty() ? 0 : next_ms[next_ms.size() / 2];
  const double max = next_ms.empty() ? 0 : next_ms.back();
  std::printf(
      "{\"source\": \"%s\", \"pairs_written\": %d, \"elapsed_s\": %.3f, \"pairs_per_s\": %.2f, "
      "\"next_p50_ms\": %.3f, \"next_max_ms\": %.3f, \"frames_dropped\": %llu, "
      "\"frames_rejected\": %llu, \"pairing_failures\": %llu, \"timeouts\": %llu}\n",
      source->Name(), written, elapsed_s, elapsed_s > 0 ? written / elapsed_s : 0.0, p50, max,
      static_cast<unsigned long long>(s.frames_dropped),
      static_cast<unsigned long long>(s.frames_rejected),
      static_cast<unsigned long long>(s.pairing_failures),
      static_cast<unsigned long long>(s.timeouts));
  return written == a.pairs ? 0 : 1;
}

}  // namespace
}  // namespace swf::drivers

int main(int argc, char** argv) {
  const std::string verb = argc > 1 ? argv[1] : "help";
  if (verb == "list") return swf::drivers::List();
  if (verb == "grab") {
    swf::drivers::GrabArgs args;
    if (!swf::drivers::ParseArgs(argc, argv, &args)) return 2;
    return swf::drivers::Grab(args);
  }
  swf::drivers::PrintHelp();
  return verb == "help" ? 0 : 2;
}
