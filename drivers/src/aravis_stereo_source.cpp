#include "swf/drivers/aravis_stereo_source.hpp"

#include <arpa/inet.h>
#include <arv.h>

#include <chrono>
#include <condition_variable>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <mutex>
#include <new>
#include <sstream>
#include <string>
#include <thread>

#include "swf/drivers/image_format.hpp"

namespace swf::drivers {
namespace {

// Longest single blocking pop: bounds how long one side can starve the other's queue.
constexpr std::int64_t kMaxPopWaitUs = 2000;
constexpr int kMaxRoundsPerNext = 4096;

bool ParsePixelFormat(const char* name, SourceImageDesc* desc) {
  if (std::strcmp(name, "Mono8") == 0) {
    desc->format = PixelFormat::kGray8;
    return true;
  }
  const struct {
    const char* name;
    std::int32_t bits;
  } deep[] = {{"Mono10", 10}, {"Mono12", 12}, {"Mono14", 14}, {"Mono16", 16}};
  for (const auto& d : deep) {
    if (std::strcmp(name, d.name) == 0) {
      desc->format = PixelFormat::kGray16Le;
      desc->significant_bits = d.bits;
      return true;
    }
  }
  return false;
}

core::TimeNs RealtimeNs() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<core::TimeNs>(ts.tv_sec) * core::kNsPerS + ts.tv_nsec;
}

}  // namespace

struct AravisStereoSource::Camera {
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  gulong control_lost_handler = 0;
  std::atomic<bool> control_lost{false};
  bool lost = false;  // declared lost by Next(): do not wait on control traffic to a dead camera
  // Set by the helper thread once a lost camera's old connection is closed (see ~Camera).
  std::shared_ptr<std::atomic<bool>> closed = std::make_shared<std::atomic<bool>>(false);
  // Set by this camera's trigger worker once it has dropped its reference (Stop() hands it
  // over): until then the worker can still be inside a trigger to the lost camera.
  std::shared_ptr<std::atomic<bool>> trigger_released;
  SourceImageDesc desc;
  std::size_t payload = 0;

  static void OnControlLost(ArvDevice* /*device*/, gpointer self) {
    // Runs on Aravis's heartbeat thread: only a flag, read by Next().
    static_cast<Camera*>(self)->control_lost.store(true);
  }

  ~Camera() {
    if (camera == nullptr) {
      if (stream != nullptr) g_object_unref(stream);
      return;
    }
    if (control_lost_handler != 0) {
      g_signal_handler_disconnect(arv_camera_get_device(camera), control_lost_handler);
    }
    if (lost || control_lost.load()) {
      // Closing a GigE stream and device talks GVCP to the camera, which a dead camera answers
      // only with seconds of timeouts and retries: a helper thread waits for that, not Stop().
      // The connection closes with the device's last reference. The trigger worker may hold
      // one, blocked in a trigger to the stalled camera until it answers again; were it the
      // last, the close would reach the camera after a restart had reconnected and cut off the
      // new stream (seen under load). So the helper drops its references after the worker's
      // (bounded by Aravis's GVCP timeouts and retries; 60 s is only a backstop).
      std::thread([dead_stream = stream, dead_camera = camera, done = closed,
                   worker = trigger_released] {
        for (int i = 0; i < 6000 && worker != nullptr && !worker->load(std::memory_order_acquire);
             ++i) {
          std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        if (dead_stream != nullptr) g_object_unref(dead_stream);
        g_object_unref(dead_camera);
        done->store(true, std::memory_order_release);
      }).detach();
      return;
    }
    GError* error = nullptr;
    arv_camera_stop_acquisition(camera, &error);
    g_clear_error(&error);
    if (stream != nullptr) g_object_unref(stream);  // frees every buffer it still owns
    // Give up control now rather than when the last reference goes: the trigger worker may still
    // hold one (blocked on the other, dead camera) and a restart must be able to take control.
    ArvDevice* device = arv_camera_get_device(camera);
    if (ARV_IS_GV_DEVICE(device)) {
      (void)arv_gv_device_leave_control(ARV_GV_DEVICE(device), &error);
      g_clear_error(&error);
    }
    g_object_unref(camera);
  }
};

// Fires software triggers on one camera for Next(). Owns a reference to the camera and shares its
// state with the source through a shared_ptr, so Stop() can detach it even while a trigger to a
// dead camera is still timing out.
struct AravisStereoSource::TriggerWorker {
  std::mutex mutex;
  std::condition_variable wake;
  bool request = false;
  bool quit = false;
  ArvCamera* camera = nullptr;
  // True once Run() has dropped its camera reference (read by the lost camera's closer).
  std::shared_ptr<std::atomic<bool>> released = std::make_shared<std::atomic<bool>>(false);

  static void Run(const std::shared_ptr<TriggerWorker>& self) {
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(self->mutex);
        self->wake.wait(lock, [&] { return self->request || self->quit; });
        if (self->quit) break;
        self->request = false;
      }
      GError* error = nullptr;
      arv_camera_software_trigger(self->camera, &error);
      g_clear_error(&error);  // a lost trigger shows up as a retry, a timeout or a lost camera
    }
    g_object_unref(self->camera);
    self->released->store(true, std::memory_order_release);
  }

  void Request() {
    {
      const std::lock_guard<std::mutex> lock(mutex);
      request = true;
    }
    wake.notify_one();
  }

  void Quit() {
    {
      const std::lock_guard<std::mutex> lock(mutex);
      quit = true;
    }
    wake.notify_one();
  }
};

AravisStereoSource::AravisStereoSource()
    : sequence_{SequenceTracker(16, true), SequenceTracker(16, true)} {}

AravisStereoSource::~AravisStereoSource() { Stop(); }

std::string DeviceIdOfSerial(const char* serial) {
  arv_update_device_list();
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    const char* s = arv_get_device_serial_nbr(i);
    if (s != nullptr && std::strcmp(s, serial) == 0) return arv_get_device_id(i);
  }
  return "";
}

bool IsIpv4Address(const char* id) {
  in_addr address{};
  return id != nullptr && inet_pton(AF_INET, id, &address) == 1;
}

core::Status AravisStereoSource::Fail(core::Status status, const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::vsnprintf(last_error_, sizeof(last_error_), format, args);
  va_end(args);
  return status;
}

core::Status AravisStereoSource::Configure(const AravisStereoOptions& options) {
  configured_ = false;
  SourceImageDesc probe;
  if (options.left_id == nullptr || (!options.side_by_side && options.right_id == nullptr) ||
      options.pixel_format == nullptr || !ParsePixelFormat(options.pixel_format, &probe) ||
      options.max_pairs_held < 1 || options.max_pairs_held > kMaxPairsHeld ||
      options.buffer_count < options.max_pairs_held + 2 || options.buffer_count > kMaxBuffers ||
      options.pair_tolerance_ns < 0 || options.width < 0 || options.height < 0 ||
      options.device_lost_after_ns < 0) {
    return Fail(core::Status::kInvalidArgument, "aravis: invalid options");
  }
  options_ = options;
  configured_ = true;
  return core::Status::kOk;
}

core::Status AravisStereoSource::OpenCamera(int side, const char* id) {
  auto cam = std::make_unique<Camera>();
  GError* error = nullptr;
  cam->camera = arv_camera_new(id, &error);
  if (cam->camera == nullptr) {
    // Aravis 0.8 opens by device id, physical id or address, not by the serial number a bench
    // labels its cameras with: that one is looked up among the discovered devices.
    const std::string device_id = DeviceIdOfSerial(id);
    if (!device_id.empty()) {
      g_clear_error(&error);
      cam->camera = arv_camera_new(device_id.c_str(), &error);
    }
  }
  if (cam->camera == nullptr) {
    const core::Status s = Fail(core::Status::kDeviceLost, "aravis %s: cannot open: %s", id,
                                error != nullptr ? error->message : "not found");
    g_clear_error(&error);
    return s;
  }
  // Each setting is checked: a camera that refuses one is misconfigured and must say so.
  auto check = [&](const char* what) {
    if (error == nullptr) return core::Status::kOk;
    const core::Status s =
        Fail(core::Status::kUnsupported, "aravis %s: %s: %s", id, what, error->message);
    g_clear_error(&error);
    return s;
  };
  core::Status s = core::Status::kOk;
  // A camera whose previous controller vanished (a lost connection, a crashed process) can still
  // be acquiring. Such a camera may latch its stream destination the moment we take control, i.e.
  // the old controller's port, before our stream channel is set up, and keep streaming there
  // (Aravis's fake camera does: the reconnect after a stall then got no frame, 2 in 50 loaded
  // soak runs). Stopping first makes the destination be read again at our AcquisitionStart.
  arv_camera_stop_acquisition(cam->camera, &error);
  if (!core::IsOk(s = check("AcquisitionStop"))) return s;
  arv_camera_set_acquisition_mode(cam->camera, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
  if (!core::IsOk(s = check("AcquisitionMode"))) return s;
  arv_camera_set_pixel_format_from_string(cam->camera, options_.pixel_format, &error);
  if (!core::IsOk(s = check("PixelFormat"))) return s;
  if (options_.width > 0 && options_.height > 0) {
    arv_camera_set_region(cam->camera, options_.x, options_.y, options_.width, options_.height,
                          &error);
    if (!core::IsOk(s = check("region of interest"))) return s;
  }
  switch (options_.trigger) {
    case TriggerMode::kFreeRun:
      arv_camera_clear_triggers(cam->camera, &error);
      if (!core::IsOk(s = check("clear triggers"))) return s;
      if (options_.frame_rate_hz > 0.0) {
        arv_camera_set_frame_rate(cam->camera, options_.frame_rate_hz, &error);
        if (!core::IsOk(s = check("AcquisitionFrameRate"))) return s;
      }
      break;
    case TriggerMode::kSoftware:
      arv_camera_set_trigger(cam->camera, "Software", &error);
      if (!core::IsOk(s = check("software trigger"))) return s;
      break;
    case TriggerMode::kHardware:
      arv_camera_set_trigger(cam->camera, options_.hardware_trigger_source, &error);
      if (!core::IsOk(s = check("hardware trigger"))) return s;
      break;
  }
  if (options_.exposure_us >= 0.0) {
    arv_camera_set_exposure_time(cam->camera, options_.exposure_us, &error);
    if (!core::IsOk(s = check("ExposureTime"))) return s;
  }
  if (options_.gain >= 0.0) {
    arv_camera_set_gain(cam->camera, options_.gain, &error);
    if (!core::IsOk(s = check("Gain"))) return s;
  }
  if (arv_camera_is_gv_device(cam->camera)) {
    if (options_.packet_size > 0) {
      arv_camera_gv_set_packet_size(cam->camera, options_.packet_size, &error);
    } else {
      arv_camera_gv_auto_packet_size(cam->camera, &error);
    }
    if (!core::IsOk(s = check("GevSCPSPacketSize"))) return s;
  }
  if (options_.features != nullptr) {
    // One at a time, so that a refusal names its feature.
    std::istringstream features(options_.features);
    std::string feature;
    while (features >> feature) {
      if (!arv_device_set_features_from_string(arv_camera_get_device(cam->camera), feature.c_str(),
                                               &error)) {
        s = Fail(core::Status::kUnsupported, "aravis %s: GenICam feature %s refused: %s", id,
                 feature.c_str(), error != nullptr ? error->message : "no such feature or value");
        g_clear_error(&error);
        return s;
      }
    }
  }

  gint x = 0, y = 0, width = 0, height = 0;
  arv_camera_get_region(cam->camera, &x, &y, &width, &height, &error);
  if (!core::IsOk(s = check("region"))) return s;
  cam->payload = arv_camera_get_payload(cam->camera, &error);
  if (!core::IsOk(s = check("PayloadSize"))) return s;
  (void)ParsePixelFormat(options_.pixel_format, &cam->desc);
  cam->desc.width = width;
  cam->desc.height = height;
  cam->desc.stride_bytes = width * BytesPerPixel(cam->desc.format);
  if (width <= 0 || height <= 0 || cam->payload < RequiredBytes(cam->desc)) {
    return Fail(core::Status::kUnsupported, "aravis %s: payload %zu too small for %dx%d %s", id,
                cam->payload, width, height, options_.pixel_format);
  }

  cam->stream = arv_camera_create_stream(cam->camera, nullptr, nullptr, &error);
  if (cam->stream == nullptr) {
    s = Fail(core::Status::kIoError, "aravis %s: cannot create stream: %s", id,
             error != nullptr ? error->message : "?");
    g_clear_error(&error);
    return s;
  }
  if (ARV_IS_GV_STREAM(cam->stream)) {
    // Resend repairs lost packets while the frame is still being received; a socket buffer of
    // one payload keeps a burst of a whole frame from overflowing it before the receive thread
    // runs (a loaded host).
    g_object_set(cam->stream, "packet-resend",
                 options_.packet_resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS
                                        : ARV_GV_STREAM_PACKET_RESEND_NEVER,
                 "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_AUTO, nullptr);
  }
  for (std::int32_t i = 0; i < options_.buffer_count; ++i) {
    arv_stream_push_buffer(cam->stream, arv_buffer_new_allocate(cam->payload));
  }
  cam->control_lost_handler = g_signal_connect(arv_camera_get_device(cam->camera), "control-lost",
                                               G_CALLBACK(&Camera::OnControlLost), cam.get());
  cameras_[side] = std::move(cam);
  return core::Status::kOk;
}

core::Status AravisStereoSource::Start() {
  if (!configured_) return Fail(core::Status::kNotConfigured, "aravis: not configured");
  Stop();
  // The old connection to a lost camera is closed on a helper thread; when the camera answers
  // again that close reaches it (stream channel and control released) and would cut off a new
  // connection opened meanwhile. So a restart waits for it (bounded; GVCP retries end).
  for (int side = 0; side < 2; ++side) {
    if (closing_[side] == nullptr) continue;
    for (int i = 0; i < 1000 && !closing_[side]->load(std::memory_order_acquire); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!closing_[side]->load(std::memory_order_acquire)) {
      return Fail(core::Status::kDeviceLost,
                  "aravis %s: the lost connection is still closing (no GVCP answer)", Id(side));
    }
    closing_[side].reset();
  }
  for (int side = 0; side < SideCount(); ++side) {
    const core::Status s = OpenCamera(side, side == 0 ? options_.left_id : options_.right_id);
    if (!core::IsOk(s)) {
      Stop();
      return s;
    }
  }
  for (std::int32_t i = 0; i < options_.max_pairs_held; ++i) {
    slots_[i] = Slot{};
    for (int side = 0; side < 2; ++side) {
      const SourceImageDesc& d = cameras_[options_.side_by_side ? 0 : side]->desc;
      auto& gray = side == 0 ? slots_[i].left_gray : slots_[i].right_gray;
      gray.reset(new (std::nothrow) std::uint8_t[static_cast<std::size_t>(d.width) * d.height]);
      if (!gray) {
        Stop();
        return Fail(core::Status::kFull, "aravis: out of memory for pair slots");
      }
    }
  }
  if (options_.side_by_side && cameras_[0]->desc.width % 2 != 0) {
    Stop();
    return Fail(core::Status::kUnsupported, "aravis: side-by-side width is odd");
  }
  realtime_to_monotonic_ns_ = core::MonotonicNs() - RealtimeNs();
  const core::TimeNs now = core::MonotonicNs();
  for (int side = 0; side < SideCount(); ++side) {
    GError* error = nullptr;
    arv_camera_start_acquisition(cameras_[side]->camera, &error);
    if (error != nullptr) {
      const core::Status s = Fail(core::Status::kIoError, "aravis %s: start acquisition: %s",
                                  side == 0 ? options_.left_id : options_.right_id, error->message);
      g_clear_error(&error);
      Stop();
      return s;
    }
    sequence_[side].Reset();
    numbering_.Restart(side);
    last_frame_ns_[side] = now;
    held_[side] = Held{};
  }
  trigger_pending_ = false;
  if (options_.trigger == TriggerMode::kSoftware) {
    for (int side = 0; side < SideCount(); ++side) {
      trigger_[side] = std::make_shared<TriggerWorker>();
      trigger_[side]->camera = static_cast<ArvCamera*>(g_object_ref(cameras_[side]->camera));
      std::thread([worker = trigger_[side]] { TriggerWorker::Run(worker); }).detach();
    }
  }
  started_ = true;
  return core::Status::kOk;
}

void AravisStereoSource::Recycle(int side, ArvBuffer* buffer) {
  if (buffer != nullptr && cameras_[side] != nullptr) {
    arv_stream_push_buffer(cameras_[side]->stream, buffer);
  }
}

core::Status AravisStereoSource::Fill(int side, std::int64_t wait_us) {
  if (held_[side].buffer != nullptr) return core::Status::kOk;
  Camera& cam = *cameras_[side];
  ArvBuffer* buffer = wait_us > 0 ? arv_stream_timeout_pop_buffer(cam.stream, wait_us)
                                  : arv_stream_try_pop_buffer(cam.stream);
  if (buffer == nullptr) return CheckSilence(side);
  last_frame_ns_[side] = core::MonotonicNs();
  // Block ids count every frame the camera sent, good or bad: gaps are frames lost entirely.
  const std::uint32_t lost = sequence_[side].Observe(arv_buffer_get_frame_id(buffer));
  stats_.frames_dropped += lost;
  numbering_.Lose(side, lost);
  const ArvBufferStatus status = arv_buffer_get_status(buffer);
  std::size_t size = 0;
  const void* data = arv_buffer_get_data(buffer, &size);
  if (status != ARV_BUFFER_STATUS_SUCCESS || data == nullptr || size < RequiredBytes(cam.desc)) {
    if (status == ARV_BUFFER_STATUS_MISSING_PACKETS) {
      ++extra_.missing_packets;
      ++stats_.missing_packets;
    } else if (status == ARV_BUFFER_STATUS_TIMEOUT) {
      ++extra_.buffer_timeouts;
    } else {
      ++extra_.other_bad;
    }
    ++stats_.frames_rejected;
    numbering_.Lose(side);
    Recycle(side, buffer);
    trigger_pending_ = false;  // a triggered frame was lost: trigger again
    return core::Status::kOk;
  }
  const core::TimeNs arrival_ns =
      static_cast<core::TimeNs>(arv_buffer_get_system_timestamp(buffer)) +
      realtime_to_monotonic_ns_;
  if (options_.trigger == TriggerMode::kSoftware && arrival_ns < trigger_time_ns_) {
    // Answers an earlier trigger whose partner was lost: it can never pair with this trigger's.
    ++stats_.pairing_failures;
    numbering_.Lose(side);
    Recycle(side, buffer);
    return core::Status::kOk;
  }
  held_[side].buffer = buffer;
  held_[side].arrival_ns = arrival_ns;
  return core::Status::kOk;
}

core::Status AravisStereoSource::CheckSilence(int side) {
  Camera& cam = *cameras_[side];
  if (cam.control_lost.load()) {
    cam.lost = true;
    ++extra_.devices_lost;
    return Fail(core::Status::kDeviceLost, "aravis %s: control channel lost (no GVCP answer)",
                Id(side));
  }
  const core::TimeNs now = core::MonotonicNs();
  if (options_.device_lost_after_ns <= 0 ||
      now - last_frame_ns_[side] <= options_.device_lost_after_ns) {
    return core::Status::kOk;
  }
  // Only a camera that the pair waits for can be silent: a side holding a frame has delivered.
  cam.lost = true;
  ++extra_.devices_lost;
  const int other = 1 - side;
  const bool other_silent = SideCount() == 2 && held_[other].buffer == nullptr &&
                            now - last_frame_ns_[other] > options_.device_lost_after_ns;
  if (other_silent) {
    cameras_[other]->lost = true;
    return Fail(core::Status::kDeviceLost,
                "aravis %s and %s: no frame from either for %lld ms (stalled, unplugged or "
                "powered off)",
                options_.left_id, options_.right_id,
                static_cast<long long>((now - last_frame_ns_[side]) / core::kNsPerMs));
  }
  return Fail(core::Status::kDeviceLost,
              "aravis %s: no frame for %lld ms (stalled, unplugged or powered off)", Id(side),
              static_cast<long long>((now - last_frame_ns_[side]) / core::kNsPerMs));
}

void AravisStereoSource::FireTriggers() {
  // The triggers go out on the worker threads: a GVCP write allocates and, to a dead camera,
  // blocks for seconds of retries, neither of which Next() may do.
  for (int side = 0; side < SideCount(); ++side) {
    if (trigger_[side] != nullptr) trigger_[side]->Request();
  }
  trigger_pending_ = true;
  trigger_time_ns_ = core::MonotonicNs();
}

core::Status AravisStereoSource::Emit(std::int32_t slot_index, StereoPair* pair) {
  Slot& slot = slots_[slot_index];
  *pair = StereoPair{};
  ArvBuffer* buffers[2] = {held_[0].buffer,
                           options_.side_by_side ? held_[0].buffer : held_[1].buffer};
  const core::TimeNs times[2] = {held_[0].arrival_ns,
                                 options_.side_by_side ? held_[0].arrival_ns : held_[1].arrival_ns};
  core::ImageView<const std::uint8_t>* views[2] = {&pair->left, &pair->right};
  std::uint8_t* grays[2] = {slot.left_gray.get(), slot.right_gray.get()};
  core::Status result = core::Status::kOk;
  for (int side = 0; side < 2; ++side) {
    const int cam_side = options_.side_by_side ? 0 : side;
    SourceImageDesc d = cameras_[cam_side]->desc;
    std::size_t size = 0;
    const auto* data = static_cast<const std::uint8_t*>(arv_buffer_get_data(buffers[side], &size));
    if (options_.side_by_side) {
      d.width /= 2;
      const std::size_t offset =
          side == 0 ? 0 : static_cast<std::size_t>(d.width) * BytesPerPixel(d.format);
      data += offset;
      size -= offset;
    }
    if (d.format == PixelFormat::kGray8) {
      *views[side] = {data, d.width, d.height, d.stride_bytes};
    } else {
      const core::Status s = ConvertToGray8(d, data, size, grays[side], d.width);
      if (!core::IsOk(s)) result = s;
      *views[side] = {grays[side], d.width, d.height, d.width};
    }
  }
  const bool in_place = cameras_[0]->desc.format == PixelFormat::kGray8;
  if (!core::IsOk(result) || !in_place) {
    for (int side = 0; side < SideCount(); ++side) Recycle(side, held_[side].buffer);
    slot.left_buffer = slot.right_buffer = nullptr;
  } else {
    slot.left_buffer = held_[0].buffer;
    slot.right_buffer = options_.side_by_side ? nullptr : held_[1].buffer;
  }
  held_[0] = Held{};
  held_[1] = Held{};
  if (!core::IsOk(result)) return result;
  pair->left_exposure_ns = times[0];
  pair->right_exposure_ns = times[1];
  ServePair(slot_index, &slot, &numbering_, &stats_, pair);
  trigger_pending_ = false;
  return core::Status::kOk;
}

core::Status AravisStereoSource::Next(core::TimeNs timeout_ns, StereoPair* pair) {
  if (!started_) return core::Status::kNotConfigured;
  if (pair == nullptr) return core::Status::kInvalidArgument;
  const std::int32_t slot_index = FreeSlot(slots_, options_.max_pairs_held);
  if (slot_index < 0) return Fail(core::Status::kFull, "aravis: all pair slots are held");
  const core::TimeNs deadline_ns = core::MonotonicNs() + (timeout_ns > 0 ? timeout_ns : 0);
  for (int round = 0; round < kMaxRoundsPerNext; ++round) {
    // A triggered frame that never arrives (its leader or trailer lost) must not stall the loop.
    if (trigger_pending_ && core::MonotonicNs() - trigger_time_ns_ > options_.trigger_retry_ns) {
      trigger_pending_ = false;
    }
    if (options_.trigger == TriggerMode::kSoftware && !trigger_pending_) FireTriggers();
    const core::TimeNs remaining_ns = deadline_ns - core::MonotonicNs();
    std::int64_t wait_us = remaining_ns / core::kNsPerUs;
    if (wait_us > kMaxPopWaitUs) wait_us = kMaxPopWaitUs;
    for (int side = 0; side < SideCount(); ++side) {
      const core::Status s = Fill(side, wait_us);
      if (!core::IsOk(s)) return s;
    }
    const bool both =
        held_[0].buffer != nullptr && (options_.side_by_side || held_[1].buffer != nullptr);
    if (both) {
      if (options_.side_by_side) return Emit(slot_index, pair);
      // Software trigger: one frame per camera per trigger, so the two frames that arrived after
      // the trigger are the pair, however differently the two cameras delay their exposure.
      const core::TimeNs tolerance_ns = options_.trigger == TriggerMode::kSoftware
                                            ? options_.trigger_retry_ns
                                            : options_.pair_tolerance_ns;
      const PairDecision decision =
          DecidePair(held_[0].arrival_ns, held_[1].arrival_ns, tolerance_ns);
      switch (decision) {
        case PairDecision::kPair: {
          const core::Status s = Emit(slot_index, pair);
          if (core::IsOk(s)) return s;
          ++stats_.frames_rejected;
          continue;
        }
        case PairDecision::kDiscardLeft:
        case PairDecision::kDiscardRight: {
          const int side = decision == PairDecision::kDiscardLeft ? 0 : 1;
          ++stats_.pairing_failures;
          numbering_.Lose(side);
          Recycle(side, held_[side].buffer);
          held_[side] = Held{};
          continue;
        }
      }
    }
    if (deadline_ns - core::MonotonicNs() <= 0) break;
  }
  ++stats_.timeouts;
  return core::Status::kTimeout;
}

void AravisStereoSource::Release(const StereoPair& pair) {
  if (pair.handle < 0 || pair.handle >= options_.max_pairs_held) return;
  Slot& slot = slots_[pair.handle];
  if (!slot.in_use) return;
  Recycle(0, slot.left_buffer);
  Recycle(1, slot.right_buffer);
  slot.left_buffer = slot.right_buffer = nullptr;
  slot.in_use = false;
}

void AravisStereoSource::Stop() {
  for (int side = 0; side < 2; ++side) {
    std::shared_ptr<TriggerWorker>& worker = trigger_[side];
    if (worker == nullptr) continue;
    if (cameras_[side] != nullptr) cameras_[side]->trigger_released = worker->released;
    worker->Quit();
    worker.reset();
  }
  // Held buffers go back to their stream so the stream frees them with itself.
  for (int side = 0; side < 2; ++side) {
    Recycle(side, held_[side].buffer);
    held_[side] = Held{};
  }
  for (Slot& slot : slots_) {
    Recycle(0, slot.left_buffer);
    Recycle(1, slot.right_buffer);
    slot.left_buffer = slot.right_buffer = nullptr;
    slot.in_use = false;
  }
  for (int side = 0; side < 2; ++side) {
    if (cameras_[side] == nullptr) continue;
    guint64 completed = 0, failures = 0, underruns = 0;
    arv_stream_get_statistics(cameras_[side]->stream, &completed, &failures, &underruns);
    extra_.stream_underruns += underruns;
    if (ARV_IS_GV_STREAM(cameras_[side]->stream)) {
      guint64 resent = 0, missing = 0;
      arv_gv_stream_get_statistics(ARV_GV_STREAM(cameras_[side]->stream), &resent, &missing);
      extra_.resent_packets += resent;
    }
    if (cameras_[side]->lost || cameras_[side]->control_lost.load()) {
      closing_[side] = cameras_[side]->closed;
    }
    cameras_[side].reset();
  }
  started_ = false;
}

core::Status AravisStereoSource::SetFeature(int side, const char* name, const char* value) {
  if (side < 0 || side > 1 || cameras_[side] == nullptr || name == nullptr || value == nullptr) {
    return core::Status::kInvalidArgument;
  }
  GError* error = nullptr;
  arv_camera_set_string(cameras_[side]->camera, name, value, &error);
  if (error != nullptr) {
    // Not a string feature: let GenICam parse the value for its own type.
    g_clear_error(&error);
    char setting[256];
    std::snprintf(setting, sizeof(setting), "%s=%s", name, value);
    if (!arv_device_set_features_from_string(arv_camera_get_device(cameras_[side]->camera), setting,
                                             &error)) {
      const core::Status s = Fail(core::Status::kUnsupported, "aravis: feature %s=%s: %s", name,
                                  value, error != nullptr ? error->message : "refused");
      g_clear_error(&error);
      return s;
    }
  }
  return core::Status::kOk;
}

core::Status AravisStereoSource::GetFeature(int side, const char* name, char* value,
                                            std::int32_t capacity) {
  if (side < 0 || side > 1 || cameras_[side] == nullptr || name == nullptr || value == nullptr ||
      capacity <= 0) {
    return core::Status::kInvalidArgument;
  }
  ArvGcNode* node = arv_device_get_feature(arv_camera_get_device(cameras_[side]->camera), name);
  if (node == nullptr || !ARV_IS_GC_FEATURE_NODE(node)) {
    return Fail(core::Status::kUnsupported, "aravis: no feature %s", name);
  }
  GError* error = nullptr;
  const char* text = arv_gc_feature_node_get_value_as_string(ARV_GC_FEATURE_NODE(node), &error);
  if (text == nullptr) {
    const core::Status s = Fail(core::Status::kIoError, "aravis: read %s: %s", name,
                                error != nullptr ? error->message : "?");
    g_clear_error(&error);
    return s;
  }
  std::snprintf(value, static_cast<std::size_t>(capacity), "%s", text);
  return core::Status::kOk;
}

}  // namespace swf::drivers
