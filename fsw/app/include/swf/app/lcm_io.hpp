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
#include "swf/app/log_reader.hpp"
#include "swf/app/records.hpp"
#include "swf/drivers/stereo_source.hpp"

namespace swf::app {

// Channel names: prefix + suffix.
inline constexpr const char* kStereoSuffix = "STEREO";
inline constexpr const char* kNavSuffix = "NAV";
inline constexpr const char* kLandmarksSuffix = "LANDMARKS";
inline constexpr const char* kHazardSuffix = "HAZARD";
inline constexpr const char* kHealthSuffix = "HEALTH";

// Sees every output as it is published (evaluation, progress display). Output thread only.
class OutputObserver {
 public:
  virtual ~OutputObserver() = default;
  virtual void OnNav(const NavRecord& /*r*/) {}
  virtual void OnMap(const MapRecord& /*r*/) {}
  virtual void OnHealth(const HealthRecord& /*r*/) {}
  virtual void OnHazard(const HazardRecord& /*r*/) {}
};

struct OutputOptions {
  std::string lcm_url;  // "" = do not publish
  std::string channel_prefix = "SWF_";
  std::string record_path;     // "" = do not record
  std::int32_t max_width = 0;  // largest frame recorded (sizes the encode buffer)
  std::int32_t max_height = 0;
  std::int32_t max_hazard_cells = 0;  // cells per side of the largest hazard map
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
  void Start();
  // Drains everything queued, then stops and closes the log.
  void StopAndDrain();
  // Drains what is queued now on the calling thread (tests and Step()-driven runs).
  void DrainOnce();
  const OutputCounters& Counters() const { return counters_; }

 private:
  struct Impl;
  void Handle(const RecordRef& ref);
  void Emit(const char* suffix, std::int64_t utime, const std::uint8_t* data, int size);

  std::unique_ptr<Impl> impl_;
  OutputChannels* channels_ = nullptr;
  std::vector<OutputObserver*> observers_;
  OutputCounters counters_;
  std::atomic<bool> quit_{false};
  std::thread thread_;
};

}  // namespace swf::app
