// StereoSource over Aravis: two GigE Vision (or USB3 Vision) cameras, or one stereo head that
// delivers [left | right] side by side. Buffers are allocated at Start() and cycle between the
// Aravis stream thread and the caller; Mono8 images are handed out in place (the ArvBuffer is held
// until Release), deeper Mono formats are converted into pair slots.
//
// Pairing: GigE cameras have independent clocks, so free-running and hardware-triggered frames are
// paired by host arrival time (the buffer's system time stamp) within a tolerance. With a software
// trigger Next() triggers both cameras back to back and pairs the two frames answering that trigger
// (answers to earlier triggers are discarded as stale). Bad buffers (missing packets, timeouts,
// size mismatch) are counted and recycled, block-id gaps are counted as drops, and a camera that
// stops delivering or loses its control channel gives kDeviceLost naming that camera (not its
// healthy partner) in LastError(); Stop() + Start() reconnects when it is back.
//
// Packet loss: with packet_resend the GigE stream asks the camera to resend missing packets
// (GVCP PACKETRESEND) and its socket buffer is sized to the payload, so a loss rate the resend
// can repair costs nothing; a frame it cannot repair in time arrives with MISSING_PACKETS and
// costs that frame only (counted in AravisStats, the stream goes on).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "swf/drivers/pairing.hpp"
#include "swf/drivers/stereo_source.hpp"

// Aravis/GLib types stay out of this header so users need not see GLib.
struct _ArvCamera;
struct _ArvStream;
struct _ArvBuffer;

namespace swf::drivers {

enum class TriggerMode : std::uint8_t {
  kFreeRun,   // cameras run at frame_rate_hz on their own clocks
  kSoftware,  // Next() has a worker thread fire TriggerSoftware on both cameras
  kHardware,  // both cameras wait for a shared hardware line (hardware_trigger_source)
};

struct AravisStereoOptions {
  const char* left_id = nullptr;       // Aravis device id, IP address or serial number (looked up)
  const char* right_id = nullptr;      // ignored when side_by_side
  bool side_by_side = false;           // one stereo head delivering [left | right]
  const char* pixel_format = "Mono8";  // Mono8 (in place), Mono10/Mono12/Mono16 (converted)
  // Region of interest; width/height 0 keep the camera's current values.
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
  double frame_rate_hz = 0.0;    // 0 keeps the camera's value (free run only)
  double exposure_us = -1.0;     // < 0 keeps the camera's value
  double gain = -1.0;            // < 0 keeps the camera's value
  std::int32_t packet_size = 0;  // GigE: 0 negotiates the largest size the path allows
  bool packet_resend = true;     // GigE: ask the camera to resend missing packets
  TriggerMode trigger = TriggerMode::kFreeRun;
  const char* hardware_trigger_source = "Line1";
  // Software trigger: fire again when no pair arrived this long after a trigger.
  core::TimeNs trigger_retry_ns = 100 * core::kNsPerMs;
  // Generic GenICam features for everything else, "Name=Value Name2=Value2", applied last to
  // both cameras one at a time (arv_device_set_features_from_string syntax); a refusal names
  // its feature in LastError(). nullptr for none.
  const char* features = nullptr;
  std::int32_t buffer_count = 8;                        // per camera
  std::int32_t max_pairs_held = 2;                      // pairs the caller may hold at once
  core::TimeNs pair_tolerance_ns = 5 * core::kNsPerMs;  // free run and hardware trigger
  // A running camera that delivers nothing (not even bad frames) for this long is declared lost.
  // 0 disables the check (e.g. hardware trigger from an external source that may pause).
  core::TimeNs device_lost_after_ns = 2 * core::kNsPerS;
};

// Buffer outcomes beyond SourceStats, for health telemetry.
struct AravisStats {
  std::uint64_t missing_packets = 0;   // ARV_BUFFER_STATUS_MISSING_PACKETS
  std::uint64_t buffer_timeouts = 0;   // ARV_BUFFER_STATUS_TIMEOUT
  std::uint64_t other_bad = 0;         // size mismatch, wrong packet id, aborted, ...
  std::uint64_t stream_underruns = 0;  // frames Aravis dropped for lack of a free buffer (at Stop)
  std::uint64_t resent_packets = 0;    // GVSP packets the camera resent on request (at Stop)
  std::uint64_t devices_lost = 0;      // kDeviceLost returned by Next() (silence, control lost)
};

// The Aravis device id of the discovered camera with this serial number, "" when none (Aravis
// opens by device id, physical id or address only). Discovery allocates: not for the flight loop.
std::string DeviceIdOfSerial(const char* serial);
// Whether `id` is a dotted IPv4 address (an id that is none is a serial number or device id).
bool IsIpv4Address(const char* id);

class AravisStereoSource final : public StereoSource {
 public:
  static constexpr std::int32_t kMaxPairsHeld = 8;
  static constexpr std::int32_t kMaxBuffers = 64;

  AravisStereoSource();
  ~AravisStereoSource() override;
  AravisStereoSource(const AravisStereoSource&) = delete;
  AravisStereoSource& operator=(const AravisStereoSource&) = delete;

  core::Status Configure(const AravisStereoOptions& options);

  core::Status Start() override;
  core::Status Next(core::TimeNs timeout_ns, StereoPair* pair) override;
  void Release(const StereoPair& pair) override;
  void Stop() override;
  SourceStats Stats() const override { return stats_; }
  const char* Name() const override { return "aravis"; }

  AravisStats ExtraStats() const { return extra_; }
  const char* LastError() const override { return last_error_; }

  // Generic GenICam access on a running camera (side 0 = left, 1 = right) for features the
  // options do not cover. Not for the flight loop: GenICam access allocates.
  core::Status SetFeature(int side, const char* name, const char* value);
  core::Status GetFeature(int side, const char* name, char* value, std::int32_t capacity);

 private:
  struct Camera;
  struct TriggerWorker;
  struct Held {
    _ArvBuffer* buffer = nullptr;
    core::TimeNs arrival_ns = 0;
  };
  struct Slot {
    bool in_use = false;
    _ArvBuffer* left_buffer = nullptr;  // held for an in-place pair, else nullptr
    _ArvBuffer* right_buffer = nullptr;
    std::unique_ptr<std::uint8_t[]> left_gray;
    std::unique_ptr<std::uint8_t[]> right_gray;
  };

  int SideCount() const { return options_.side_by_side ? 1 : 2; }
  core::Status OpenCamera(int side, const char* id);
  core::Status Fail(core::Status status, const char* format, ...);
  // Pops at most one buffer for a side within wait_us; bad buffers are counted and recycled.
  core::Status Fill(int side, std::int64_t wait_us);
  void Recycle(int side, _ArvBuffer* buffer);
  core::Status Emit(std::int32_t slot_index, StereoPair* pair);
  // kDeviceLost naming the camera(s) that delivered nothing for device_lost_after_ns, else kOk.
  core::Status CheckSilence(int side);
  void FireTriggers();
  const char* Id(int side) const { return side == 0 ? options_.left_id : options_.right_id; }

  std::unique_ptr<Camera> cameras_[2];
  // Set when a lost camera's old connection has been closed by its helper thread; Start() waits
  // for it before reconnecting.
  std::shared_ptr<std::atomic<bool>> closing_[2];
  AravisStereoOptions options_;
  bool configured_ = false;
  bool started_ = false;
  Held held_[2];
  SequenceTracker sequence_[2];
  PairNumbering numbering_;
  core::TimeNs last_frame_ns_[2] = {0, 0};
  // One trigger worker per camera: a GVCP write to a dead camera blocks its worker for seconds of
  // retries and must not hold back the other camera's trigger (whose silence would then be
  // blamed on the wrong camera).
  std::shared_ptr<TriggerWorker> trigger_[2];
  bool trigger_pending_ = false;
  core::TimeNs trigger_time_ns_ = 0;
  Slot slots_[kMaxPairsHeld];
  core::TimeNs realtime_to_monotonic_ns_ = 0;
  SourceStats stats_;
  AravisStats extra_;
  char last_error_[256] = "";
};

}  // namespace swf::drivers
