// swf-grab: lists cameras and grabs N stereo pairs to PNG with timing and drop statistics.
//   swf-grab list
//   swf-grab grab --source aravis --left 192.168.1.10 --right 192.168.1.11 --pairs 50 --out cap/
//   swf-grab grab --source v4l2 --left /dev/video0 --right /dev/video2 --format GREY --pairs 50
// Run `swf-grab grab --help` for every option. Not flight code: it allocates, prints and writes
// files (a ground tool: CLI11 and nlohmann-json, docs/cli.md).
#include <arv.h>
#include <linux/videodev2.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "png_writer.hpp"
#include "swf/drivers/aravis_stereo_source.hpp"
#include "swf/drivers/v4l2_stereo_source.hpp"
#include "swf/ground_cli/ground_cli.hpp"

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

// The grab subcommand's options.
void AddGrabOptions(CLI::App* grab, GrabArgs* a, double* timeout_ms) {
  grab->add_option("--source", a->source, "camera driver")
      ->capture_default_str()
      ->check(CLI::IsMember({"aravis", "v4l2"}));
  grab->add_option("--left", a->left, "Aravis id, serial or IP address, or V4L2 device node")
      ->required();
  grab->add_option("--right", a->right, "the right camera (not with --side-by-side)");
  grab->add_flag("--side-by-side", a->side_by_side, "one device delivers [left|right]");
  grab->add_option("--width", a->width, "requested width / region of interest")
      ->check(CLI::NonNegativeNumber);
  grab->add_option("--height", a->height, "requested height")->check(CLI::NonNegativeNumber);
  grab->add_option("--format", a->format,
                   "V4L2: GREY|Y16|YUYV; Aravis: Mono8|Mono10|Mono12|Mono16");
  grab->add_option("--pairs", a->pairs, "pairs to grab")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  grab->add_option("--out", a->out, "output directory (left_NNNNNN.png, ...; created)")
      ->capture_default_str();
  grab->add_option("--timeout-ms", *timeout_ms, "per-pair timeout")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  grab->add_option("--trigger", a->trigger, "Aravis trigger mode (hardware uses Line1)")
      ->capture_default_str()
      ->check(CLI::IsMember({"free", "software", "hardware"}));
  grab->add_option("--fps", a->fps, "frame rate (free run)")->check(CLI::NonNegativeNumber);
  grab->add_option("--exposure-us", a->exposure_us, "exposure time");
  grab->add_option("--gain", a->gain, "gain");
  grab->add_option("--packet-size", a->packet_size, "GigE packet size (0: negotiated)")
      ->check(CLI::NonNegativeNumber);
  grab->add_option("--features", a->features, "extra GenICam features \"Name=Value ...\" (Aravis)");
  grab->add_option("--tolerance-ms", a->tolerance_ms, "pairing tolerance")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  grab->add_flag("--fake-gv", a->fake_gv,
                 "serve Aravis GigE fake cameras at --left/--right: addresses, or serials served "
                 "on 127.0.0.1/.2 (inside `unshare -n`, drivers/README.md)");
  grab->add_option("--fake-loss", a->fake_loss, "the right fake camera's packet loss ratio")
      ->check(CLI::Range(0.0, 1.0));
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

int Grab(const GrabArgs& a, const nlohmann::json& run) {
  if (a.right.empty() && !a.side_by_side) {
    std::fprintf(stderr, "swf-grab: grab: --right is required (or --side-by-side)\n");
    return cli::kExitUsage;
  }
  std::vector<ArvGvFakeCamera*> fakes;
  if (a.fake_gv) {
    // At the address --left / --right name, or, for a serial number, at 127.0.0.1 / 127.0.0.2
    // with that serial (then found by discovery, as a bench's cameras are).
    for (const auto& [id, default_address] :
         {std::pair{a.left, "127.0.0.1"}, std::pair{a.right, "127.0.0.2"}}) {
      if (id.empty()) continue;
      const bool by_address = IsIpv4Address(id.c_str());
      const std::string address = by_address ? id : default_address;
      ArvGvFakeCamera* fake =
          arv_gv_fake_camera_new(address.c_str(), by_address ? nullptr : id.c_str());
      if (fake == nullptr || !arv_gv_fake_camera_is_running(fake)) {
        std::fprintf(stderr, "swf-grab: cannot serve a fake camera on %s\n", address.c_str());
        for (ArvGvFakeCamera* f : fakes) g_object_unref(f);
        if (fake != nullptr) g_object_unref(fake);
        return cli::kExitFailed;
      }
      if (id == a.right && a.fake_loss > 0) {
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
    return cli::kExitFailed;
  }
  if (!cli::MakeDirectories(a.out, &error)) {
    std::fprintf(stderr, "swf-grab: --out: %s\n", error.c_str());
    source->Stop();
    for (ArvGvFakeCamera* f : fakes) g_object_unref(f);
    return cli::kExitFailed;
  }
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
  const nlohmann::json summary = {{"source", source->Name()},
                                  {"pairs_written", written},
                                  {"elapsed_s", ground_cli::Number(elapsed_s)},
                                  {"pairs_per_s", elapsed_s > 0 ? written / elapsed_s : 0.0},
                                  {"next_p50_ms", ground_cli::Number(p50)},
                                  {"next_max_ms", ground_cli::Number(max)},
                                  {"frames_dropped", s.frames_dropped},
                                  {"frames_rejected", s.frames_rejected},
                                  {"pairing_failures", s.pairing_failures},
                                  {"timeouts", s.timeouts},
                                  {"run", run}};
  ground_cli::PrintJson(summary, -1);
  return written == a.pairs ? cli::kExitOk : cli::kExitFailed;
}

}  // namespace
}  // namespace swf::drivers

int main(int argc, char** argv) {
  CLI::App app{
      "swf-grab: lists cameras and grabs stereo pairs to PNG with timing and drop "
      "statistics (a JSON summary on stdout)"};
  swf::ground_cli::Adopt(&app, "swf-grab");
  app.require_subcommand(1);
  CLI::App* list = app.add_subcommand("list", "the Aravis cameras and V4L2 nodes found");
  CLI::App* grab = app.add_subcommand("grab", "grab --pairs stereo pairs into --out");
  swf::drivers::GrabArgs args;
  double timeout_ms = 1000.0;
  swf::drivers::AddGrabOptions(grab, &args, &timeout_ms);
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  if (list->parsed()) return swf::drivers::List();
  args.timeout_ns = static_cast<swf::core::TimeNs>(timeout_ms * 1e6);
  swf::cli::RemovePartialOutputsOnSignal();
  return swf::drivers::Grab(args, swf::ground_cli::RunEcho(app, "swf-grab", argc, argv));
}
