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
//   source recovery thread (normal priority): restarts a lost camera (Stop + Start: GVCP
//     discovery, buffer and stream allocation, seconds of retries to a dead camera), which the
//     real-time thread may neither wait for nor do.
//
// Camera outage (a stall, a loss, a restart): the frame group keeps its rate. Each cycle without a
// pair is a missed cycle: the pipeline coasts (Pipeline::Coast, the motion input the missing frame
// would have carried, else bounded constant velocity) and the coasted state is published
// (CAMERA_OUTAGE, DEGRADED or INVALID). A lost source (kDeviceLost, kIoError) or one silent for
// restart_after_ns is restarted on the recovery thread every restart_interval_ns until it is back;
// only an outage longer than max_outage_ns ends the run (kDeviceLost), with the source's own
// words naming the camera in SourceFault(). Outage lengths are counted in missed cycles of the
// frame group (one period each), not measured on the clock, so a loaded machine cannot change
// the verdict of a test.
//
// After Run() starts nothing allocates or blocks on I/O on the real-time threads: outputs go to
// preallocated slots, a full pool is a counted drop.
#pragma once

#include <atomic>
#include <cstdint>
#include <semaphore>
#include <thread>

#include "swf/app/pipeline.hpp"
#include "swf/app/records.hpp"
#include "swf/app/stage_timer.hpp"
#include "swf/core/memory_use.hpp"
#include "swf/core/status.hpp"
#include "swf/drivers/process_input.hpp"
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
  // Lockstep: wait this long for a pair (a camera outage then waits one period per cycle).
  core::TimeNs acquire_timeout_ns = core::kNsPerS;
  // Camera outage (see above), in time at rate_hz, counted in frame-group cycles.
  core::TimeNs restart_after_ns = core::kNsPerS;         // silent this long: restart the source
  core::TimeNs restart_interval_ns = core::kNsPerS / 2;  // between restart attempts
  core::TimeNs max_outage_ns = 30 * core::kNsPerS;       // lost this long: end the run
  // A live IMU stream (imu_t over LCM) runs on its own thread and its newest samples may arrive
  // after the pair they precede: the frame group waits at most this long for the samples up to
  // the exposure (one IMU period short of it) before it integrates what it has (0: never waits;
  // the simulator and logs hand every sample at once).
  core::TimeNs imu_wait_ns = 0;
  core::TimeNs imu_period_ns = core::kNsPerS / 200;
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
  // Camera outages: cycles without a pair (each coasted, published if there was a state).
  std::int64_t camera_outages = 0;         // outages begun (first missed cycle after a pair)
  std::int64_t cycles_missed = 0;          // frame-group cycles without a pair
  std::int64_t cycles_coasted = 0;         // of those, navigation outputs carried by Coast()
  std::int64_t source_restarts = 0;        // restart attempts (Stop + Start) of a lost source
  std::int64_t source_recoveries = 0;      // outages ended by a pair
  std::int64_t longest_outage_cycles = 0;  // missed cycles of the longest outage
  std::int64_t imu_samples = 0;            // handed to the pipeline (before its checks)
  std::int64_t imu_waits = 0;              // cycles that waited for a live IMU's samples
  std::int64_t imu_wait_timeouts = 0;      // ... and integrated without them (imu_wait_ns)
  // Lockstep pacing: cycles whose frame group waited for a slot the output thread or the hazard
  // group had not given back yet, and how long. A lockstep run goes as fast as the frame group
  // can, so that wait is not frame-group work: it is left out of the stages and of `overruns`.
  std::int64_t lockstep_waits = 0;
  core::TimeNs lockstep_wait_ns = 0;
  core::TimeNs lockstep_wait_max_ns = 0;
  // Hazard updates that took longer than hazard_every periods: at the camera rate the snapshot
  // after each would have been skipped (either pacing; set when Run() or Step() returns).
  std::int64_t hazard_overruns = 0;
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
                         drivers::MotionProvider* motion = nullptr, HazardStage* hazard = nullptr,
                         drivers::ImuProvider* imu = nullptr);

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
  // The source's description of the newest camera fault ("" if none): which camera, what
  // happened. Read it after Run()/Step() returned.
  const char* SourceFault() const { return source_fault_; }
  std::int64_t HazardErrors() const { return hazard_errors_.load(); }
  StageSummary Summary(int stage) { return stages_[stage].Summarize(); }
  // Memory figures of the last Run() (core/memory_use.hpp): its threads' stack high-water and
  // the process's resident memory and page faults when allocation counting began and at the end.
  struct Memory {
    core::StackWatermark frame_group;
    core::StackWatermark hazard;
    core::StackWatermark recovery;
    core::ProcessMemory at_start;
    core::ProcessMemory at_end;
  };
  const Memory& MemoryUse() const { return memory_; }

 private:
  core::Status Cycle(core::TimeNs acquire_timeout_ns, bool synchronous_hazard,
                     core::TimeNs* processing_ns);
  void Inject(int stage);
  void CountLockstepWait();
  void Push(core::SpscQueue<RecordRef, kOrderQueueSize>* q, RecordRef ref);
  void HazardMain();
  void TakeSnapshot(bool synchronous, std::int32_t hazard_slot);
  std::int32_t AcquireHazardInput(bool wait);
  void CopyRectified(HazardInput* h);
  void RunHazard(std::int32_t input_slot, core::SpscQueue<RecordRef, kOrderQueueSize>* q,
                 bool wait);
  void RecordFrame(const PipelineFrame& frame, const drivers::StereoPair& pair,
                   const drivers::MotionInput& motion);
  void PublishNav();
  // Hands the IMU samples due by until_utime to the pipeline and queues them for recording.
  void FeedImu(std::int64_t until_utime);
  std::int64_t ImuLeadUs() const;
  // A cycle without a pair: count it, restart the source when due, coast and publish. kTimeout
  // to go on, kDeviceLost once the outage is longer than max_outage_ns.
  core::Status MissCycle(core::Status source_status, bool synchronous);
  bool SourceDown() const;
  bool RestartDue(core::Status source_status) const;
  void RequestRestart(bool synchronous);
  void EndOutage();
  void RecoveryMain();
  void StopRecoveryThread();
  std::int64_t CyclesOf(core::TimeNs duration_ns) const;

  LoopOptions options_;
  Pipeline* pipeline_ = nullptr;
  drivers::StereoSource* source_ = nullptr;
  OutputChannels* out_ = nullptr;
  HazardStage* hazard_ = nullptr;
  drivers::MotionProvider* motion_ = nullptr;
  drivers::ImuProvider* imu_ = nullptr;
  std::int64_t last_imu_utime_ = 0;  // the newest sample handed to the pipeline
  bool configured_ = false;
  core::TimeNs period_ns_ = 0;

  StageStats stages_[kNumStages];
  LoopCounters counters_;
  std::int64_t nav_seq_ = 0;
  std::int64_t map_seq_ = 0;
  std::int64_t hazard_seq_ = 0;          // hazard thread (or Step()) only
  std::int32_t hazard_spare_slot_ = -1;  // hazards slot kept after a failed update
  std::int64_t health_seq_ = 0;
  std::int64_t last_frame_utime_ = 0;
  std::int64_t cycles_ = 0;            // frame-group cycles, missed ones included (health cadence)
  core::TimeNs lockstep_wait_ns_ = 0;  // this cycle's lockstep waits (LoopCounters)

  // Camera outage state (frame group) and the recovery thread's hand-over: while restart_busy_
  // the recovery thread owns the source and the frame group does not touch it; source_down_ from
  // a restart request until a Start() succeeded.
  std::int64_t outage_cycles_ = 0;         // missed cycles of the current outage
  std::int64_t cycles_since_restart_ = 0;  // missed cycles since the last restart request
  std::int64_t expected_seq_ = 0;          // sequence number of the next frame
  std::int64_t seq_offset_ = 0;            // added to pair.seq after outages the source skipped
  char source_fault_[256] = "";
  std::atomic<bool> restart_busy_{false};
  std::atomic<bool> source_down_{false};
  std::atomic<bool> recovery_quit_{false};
  std::binary_semaphore recovery_wake_{0};
  std::thread recovery_thread_;

  std::atomic<bool> stop_{false};
  std::atomic<bool> hazard_quit_{false};
  // Hazard-group timing: written by the hazard thread, read by PublishHealth under the flag.
  StageStats hazard_stage_;
  StageSummary hazard_summary_;
  std::atomic_flag hazard_summary_lock_ = ATOMIC_FLAG_INIT;
  std::atomic<std::int64_t> hazard_errors_{0};
  std::counting_semaphore<1024> hazard_wake_{0};
  std::atomic<std::int64_t> hazard_outputs_dropped_{0};
  std::atomic<std::int64_t> hazard_overruns_{0};
  std::thread hazard_thread_;
  Memory memory_;
};

}  // namespace swf::app
