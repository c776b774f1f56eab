// FlightLoop: the rate groups of the flight process.
//
//   frame group (real-time thread, the caller of Run()): at camera rate
//       acquire -> rectify -> track -> estimate -> navigation output [-> map snapshot]
//     Pacing kRealtime: cycles start on an absolute tick grid t0 + k T (clock_nanosleep,
//     TIMER_ABSTIME); a cycle that ends after its deadline t_k + T is an overrun ("slip") and the
//     next cycle starts on the first grid tick after it, so the group keeps its rate.
//     Pacing kLockstep: a cycle starts when the source delivers a pair (a camera is the clock,
//     or a log replayed as fast as possible); a cycle whose processing exceeds T is an overrun.
//   hazard group (second real-time thread, lower priority): every hazard_every frames the frame
//     group publishes the landmark map and copies the rectified pair, the newest pose with its
//     covariance and the landmarks into a HazardInput slot and queues it; the hazard thread runs
//     the HazardStage on every queued snapshot in order and hands the hazard map to the output
//     thread. Snapshots are taken at fixed frame counts; under lockstep pacing the frame group
//     waits for a free snapshot slot instead of skipping, so published hazard maps are
//     deterministic (realtime pacing skips and counts, LoopCounters::hazard_skipped).
//   output thread (normal priority, not here): drains OutputChannels (see records.hpp).
//
// After Run() starts nothing allocates or blocks on I/O on the real-time threads: outputs go to
// preallocated slots, a full pool is a counted drop.
#pragma once

#include <atomic>
#include <cstdint>
#include <semaphore>
#include <thread>

#include "swf/app/motion.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/app/records.hpp"
#include "swf/app/stage_timer.hpp"
#include "swf/core/status.hpp"
#include "swf/drivers/stereo_source.hpp"

namespace swf::app {

enum class Pacing : std::uint8_t { kRealtime, kLockstep };

struct LoopOptions {
  double rate_hz = 10.0;
  Pacing pacing = Pacing::kRealtime;
  std::int32_t hazard_every = 5;   // frames per hazard-group cycle (>= 1)
  std::int32_t health_every = 10;  // frames per health message (>= 1)
  bool record_frames = true;       // copy every input pair to the output thread
  std::int64_t max_frames = 0;     // stop after this many frames (0: until the source ends)
  std::int8_t nav_mode = 0;        // nav_state_t.MODE_*
  core::TimeNs acquire_timeout_ns = core::kNsPerS;  // lockstep: wait this long for a pair
  std::int32_t max_consecutive_timeouts = 10;       // then the source is declared lost
  // Thread set-up of the hazard group (the frame group runs on the caller's thread).
  int hazard_priority = 0;  // SCHED_FIFO priority, 0 = normal scheduling
  // Fault injection for tests: busy-wait inject_ms in stage inject_stage for frames
  // [inject_first_frame, inject_first_frame + inject_frames).
  int inject_stage = -1;
  std::int64_t inject_first_frame = -1;
  std::int64_t inject_frames = 1;
  double inject_ms = 0.0;
};

// The hazard group's work on a snapshot (rectified pair, newest pose + covariance, landmarks with
// covariances of one frame); fills the hazard_map_t record. MapperHazardStage (hazard_stage.hpp)
// runs the hazard mapper. Called on the hazard thread (or inline by Step()); must not allocate.
class HazardStage {
 public:
  virtual ~HazardStage() = default;
  virtual core::Status Process(const HazardInput& input, HazardRecord* out) = 0;
};

struct LoopCounters {
  std::int64_t frames = 0;
  std::int64_t frames_dropped = 0;  // reported by the source (dropped_before + device drops)
  std::int64_t overruns = 0;
  std::int64_t ticks_skipped = 0;  // grid ticks passed over after overruns (realtime pacing)
  std::int64_t outputs_dropped = 0;
  std::int64_t source_timeouts = 0;
  std::int64_t source_errors = 0;
  std::int64_t hazard_skipped = 0;  // realtime pacing: snapshots not taken, hazard group busy
  std::int64_t stage_errors = 0;    // frames whose rectify/track/estimate stage failed
};

class FlightLoop {
 public:
  FlightLoop() = default;
  ~FlightLoop();
  FlightLoop(const FlightLoop&) = delete;
  FlightLoop& operator=(const FlightLoop&) = delete;

  // The pointed-to objects must outlive the loop. kInvalidArgument for bad options.
  core::Status Configure(const LoopOptions& options, Pipeline* pipeline,
                         drivers::StereoSource* source, OutputChannels* outputs,
                         MotionProvider* motion = nullptr, HazardStage* hazard = nullptr);

  // Starts the hazard group, runs the frame group on this thread until the source ends, fails
  // or RequestStop(); publishes a final health message; stops the hazard group. Returns kOk at
  // the end of a finite source, else the source's error.
  core::Status Run();
  void RequestStop() { stop_.store(true); }

  // One frame-group cycle without pacing and without the hazard thread (the map snapshot is
  // handed over synchronously). kOk, kEmpty at the end of the source, kTimeout, or an error.
  core::Status Step();
  // Queues a health message now.
  void PublishHealth();

  const LoopCounters& Counters() const { return counters_; }
  std::int64_t HazardErrors() const { return hazard_errors_.load(); }
  StageSummary Summary(int stage) { return stages_[stage].Summarize(); }

 private:
  core::Status Cycle(core::TimeNs acquire_timeout_ns, bool synchronous_hazard,
                     core::TimeNs* processing_ns);
  void Inject(int stage);
  void Push(core::SpscQueue<RecordRef, kOrderQueueSize>* q, RecordRef ref);
  void HazardMain();
  void TakeSnapshot(bool synchronous, std::int32_t hazard_slot);
  std::int32_t AcquireHazardInput(bool wait);
  void CopyRectified(HazardInput* h);
  void RunHazard(std::int32_t input_slot, core::SpscQueue<RecordRef, kOrderQueueSize>* q,
                 bool wait);

  LoopOptions options_;
  Pipeline* pipeline_ = nullptr;
  drivers::StereoSource* source_ = nullptr;
  OutputChannels* out_ = nullptr;
  HazardStage* hazard_ = nullptr;
  MotionProvider* motion_ = nullptr;
  bool configured_ = false;
  core::TimeNs period_ns_ = 0;

  StageStats stages_[kNumStages];
  LoopCounters counters_;
  std::int64_t nav_seq_ = 0;
  std::int64_t map_seq_ = 0;
  std::int64_t hazard_seq_ = 0;          // hazard thread (or Step()) only
  std::int32_t hazard_spare_slot_ = -1;  // hazards slot kept after a failed update
  std::int64_t health_seq_ = 0;
  std::int32_t consecutive_timeouts_ = 0;
  std::int64_t last_frame_utime_ = 0;

  std::atomic<bool> stop_{false};
  std::atomic<bool> hazard_quit_{false};
  // Hazard-group timing: written by the hazard thread, read by PublishHealth under the flag.
  StageStats hazard_stage_;
  StageSummary hazard_summary_;
  std::atomic_flag hazard_summary_lock_ = ATOMIC_FLAG_INIT;
  std::atomic<std::int64_t> hazard_errors_{0};
  std::counting_semaphore<1024> hazard_wake_{0};
  std::atomic<std::int64_t> hazard_outputs_dropped_{0};
  std::thread hazard_thread_;
};

}  // namespace swf::app
