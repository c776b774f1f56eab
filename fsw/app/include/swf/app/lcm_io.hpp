// The flight process's LCM side, all on the normal-priority output thread: encoding records
// into preallocated buffers, publishing them and recording them (with every input frame) to an
// LCM log readable by lcm-logplayer. Reading such logs back: log_reader.hpp.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "swf/app/flight_loop.hpp"
#include "swf/app/records.hpp"
#include "swf/core/memory_use.hpp"
#include "swf/core/spsc_queue.hpp"
#include "swf/drivers/log_stereo_source.hpp"
#include "swf/drivers/stereo_source.hpp"

namespace swf::app {

// Channel names: prefix + suffix.
inline constexpr const char* kStereoSuffix = "STEREO";
inline constexpr const char* kNavSuffix = "NAV";
inline constexpr const char* kLandmarksSuffix = "LANDMARKS";
inline constexpr const char* kHazardSuffix = "HAZARD";
inline constexpr const char* kHealthSuffix = "HEALTH";
// The frame's features with their fate (feature_set_t), beside each estimate: for display only.
inline constexpr const char* kFeaturesSuffix = "FEATURES";
// The IMU stream (imu_t): subscribed to by a flight process on cameras, recorded (not
// re-published) with the samples the pipeline used, replayed from a log.
inline constexpr const char* kImuSuffix = "IMU";

// Sees every output as it is published (evaluation, progress display). Output thread only.
// OnMessage sees every message the thread emits, as encoded for the bus and the log (outputs,
// inputs being recorded, and what observers send).
class OutputObserver {
 public:
  virtual ~OutputObserver() = default;
  virtual void OnNav(const NavRecord& /*r*/) {}
  virtual void OnMap(const MapRecord& /*r*/) {}
  virtual void OnHealth(const HealthRecord& /*r*/) {}
  virtual void OnHazard(const HazardRecord& /*r*/) {}
  virtual void OnMessage(const std::string& /*channel*/, const std::uint8_t* /*data*/,
                         int /*size*/) {}
};

struct OutputOptions {
  std::string lcm_url;  // "" = do not publish
  std::string channel_prefix = "SWF_";
  std::string record_path;     // "" = do not record
  std::int32_t max_width = 0;  // largest frame recorded (sizes the encode buffer)
  std::int32_t max_height = 0;
  std::int32_t max_hazard_cells = 0;  // cells per side of the largest hazard map
  // False: the input frames are published but not recorded (a replay's frames are in the log it
  // replays already; a viewer on the bus still wants them).
  bool record_frames = true;
};

struct OutputCounters {
  std::int64_t published = 0;
  std::int64_t recorded = 0;
  std::int64_t publish_errors = 0;
  std::int64_t record_errors = 0;
  std::int64_t encode_errors = 0;
};

class OutputThread {
 public:
  OutputThread();
  ~OutputThread();
  OutputThread(const OutputThread&) = delete;
  OutputThread& operator=(const OutputThread&) = delete;

  // Opens LCM and the log and sizes the buffers. False with a message.
  bool Open(const OutputOptions& options, OutputChannels* channels, std::string* error);
  void AddObserver(OutputObserver* observer) { observers_.push_back(observer); }
  // Publishes and records a message an observer made (from its On* callbacks: output thread
  // only) on a channel of its own, e.g. a simulator's truth beside the estimates.
  void Send(const std::string& channel, std::int64_t utime, const std::uint8_t* data, int size);
  void Start();
  // Drains everything queued, then stops and closes the log.
  void StopAndDrain();
  // Drains what is queued now on the calling thread (tests and Step()-driven runs).
  void DrainOnce();
  const OutputCounters& Counters() const { return counters_; }
  // The output thread's stack high-water (after StopAndDrain).
  const core::StackWatermark& Stack() const { return stack_; }

 private:
  struct Impl;
  void Handle(const RecordRef& ref);
  // Where one encoded message goes: the bus, the recording, or both.
  enum class Route { kBusAndLog, kLogOnly, kBusOnly };
  void Emit(const char* suffix, std::int64_t utime, const std::uint8_t* data, int size,
            Route route = Route::kBusAndLog);
  void EmitOn(const std::string& channel, std::int64_t utime, const std::uint8_t* data, int size,
              Route route);

  std::unique_ptr<Impl> impl_;
  OutputChannels* channels_ = nullptr;
  std::vector<OutputObserver*> observers_;
  OutputCounters counters_;
  std::atomic<bool> quit_{false};
  std::thread thread_;
  core::StackWatermark stack_;
};

// The IMU over LCM for a flight process on cameras: a normal-priority thread receives imu_t on
// one channel, checks each message (swf/messages/checked_decode.hpp: lengths and flags) and
// queues the sample for the frame group, which takes them as an drivers::ImuProvider (stamped at or
// before each exposure, in arrival order). What cannot be used is counted, never fatal: a
// message that does not decode, a full queue (the frame group fell behind), a sample stamped
// more than kMaxImuLeadUs after the exposure asked for (a corrupt stamp that would otherwise
// hold back every sample behind it). Ordering, gaps and saturation are ImuStreamChecker's.
inline constexpr std::int64_t kMaxImuLeadUs = 2'000'000;
inline constexpr std::size_t kImuQueueSize = 8192;

struct LcmImuCounters {
  std::int64_t received = 0;
  std::int64_t undecodable = 0;
  std::int64_t queue_full = 0;
  std::int64_t future_dropped = 0;
};

class LcmImuInput final : public drivers::ImuProvider {
 public:
  LcmImuInput();
  ~LcmImuInput() override;
  LcmImuInput(const LcmImuInput&) = delete;
  LcmImuInput& operator=(const LcmImuInput&) = delete;

  // Subscribes and starts the receiving thread. False with a message.
  bool Start(const std::string& lcm_url, const std::string& channel, std::string* error);
  void Stop();
  bool NextImu(std::int64_t until_utime, estimator::ImuSample<double>* sample) override;
  // Receiving-thread counts (read after Stop, or as a snapshot) and the frame group's drops.
  LcmImuCounters Counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  core::SpscQueue<estimator::ImuSample<double>, kImuQueueSize> queue_;
  bool held_ = false;  // frame group: the sample taken from the queue but not yet due
  estimator::ImuSample<double> held_sample_;
  std::int64_t future_dropped_ = 0;
  std::atomic<std::int64_t> received_{0};
  std::atomic<std::int64_t> undecodable_{0};
  std::atomic<std::int64_t> queue_full_{0};
  std::atomic<bool> quit_{false};
  std::thread thread_;
};

}  // namespace swf::app
