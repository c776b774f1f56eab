#include "swf/app/flight_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <latch>

#include "swf/app/alloc_meter.hpp"
#include "swf/app/realtime.hpp"

namespace swf::app {
namespace {

// A free slot of a pool another thread empties. Under lockstep pacing the frame group waits
// (bounded, 20 s) instead of dropping, and adds the time waited to *waited_ns: a lockstep run is
// a reference run and must lose no output, whatever the machine's load, and it runs faster than
// the camera rate, so that wait is the simulator's, not frame-group work. Real-time pacing never
// waits: a full pool is a counted drop.
template <typename Pool>
std::int32_t AcquireSlot(Pool* pool, bool lockstep, core::TimeNs* waited_ns) {
  std::int32_t slot = pool->Acquire();
  if (slot >= 0 || !lockstep) return slot;
  const core::TimeNs start = core::MonotonicNs();
  for (int i = 0; slot < 0 && i < 200000; ++i) {
    std::this_thread::sleep_for(std::chrono::microseconds(100));
    slot = pool->Acquire();
  }
  *waited_ns += core::MonotonicNs() - start;
  return slot;
}

// AcquireSlot for an output that is dropped whole when no slot is free: -1 is counted.
template <typename Pool>
std::int32_t AcquireOutputOrCountDrop(Pool* pool, bool lockstep, std::int64_t* outputs_dropped,
                                      core::TimeNs* waited_ns) {
  const std::int32_t slot = AcquireSlot(pool, lockstep, waited_ns);
  if (slot < 0) ++*outputs_dropped;
  return slot;
}

}  // namespace

using core::Status;
using core::TimeNs;

const char* StageName(int stage) {
  switch (stage) {
    case kStageAcquire: return "acquire";
    case kStageRectify: return "rectify";
    case kStageTrack: return "track";
    case kStageEstimate: return "estimate";
    case kStageOutput: return "output";
    case kStageMap: return "map";
    case kStageCycle: return "cycle";
    case kStageHazard: return "hazard";
    default: return "?";
  }
}

FlightLoop::~FlightLoop() {
  if (hazard_thread_.joinable()) {
    hazard_quit_.store(true);
    hazard_wake_.release();
    hazard_thread_.join();
  }
  StopRecoveryThread();
}

Status FlightLoop::Configure(const LoopOptions& options, Pipeline* pipeline,
                             drivers::StereoSource* source, OutputChannels* outputs,
                             drivers::MotionProvider* motion, HazardStage* hazard,
                             drivers::ImuProvider* imu) {
  if (pipeline == nullptr || source == nullptr || outputs == nullptr ||
      !(options.rate_hz > 0.0 && options.rate_hz <= 1000.0) || options.hazard_every < 1 ||
      options.health_every < 1 || options.max_frames < 0 || options.acquire_timeout_ns <= 0 ||
      options.restart_after_ns <= 0 || options.restart_interval_ns <= 0 ||
      options.max_outage_ns < options.restart_after_ns) {
    return Status::kInvalidArgument;
  }
  options_ = options;
  pipeline_ = pipeline;
  source_ = source;
  out_ = outputs;
  hazard_ = hazard;
  motion_ = motion;
  imu_ = imu;
  period_ns_ = static_cast<TimeNs>(1e9 / options.rate_hz + 0.5);
  for (StageStats& s : stages_) s.Reset();
  hazard_stage_.Reset();
  hazard_spare_slot_ = -1;
  hazard_summary_ = StageSummary{};
  counters_ = LoopCounters{};
  cycles_ = 0;
  outage_cycles_ = 0;
  cycles_since_restart_ = 0;
  expected_seq_ = 0;
  seq_offset_ = 0;
  source_fault_[0] = '\0';
  source_down_.store(false);
  configured_ = true;
  return Status::kOk;
}

void FlightLoop::Inject(int stage) {
  if (stage != options_.inject_stage || options_.inject_ms <= 0.0) return;
  const std::int64_t f = counters_.frames;
  if (f < options_.inject_first_frame || f >= options_.inject_first_frame + options_.inject_frames)
    return;
  Spin(static_cast<TimeNs>(options_.inject_ms * 1e6));
}

// An IMU whose clock runs ahead of the cameras' (a positive time offset) stamps an exposure's
// samples later: the frame waits for them up to its exposure plus the offset.
std::int64_t FlightLoop::ImuLeadUs() const {
  return std::max<std::int64_t>(0, std::llround(pipeline_->ImuTimeOffsetS() * 1e6));
}

void FlightLoop::FeedImu(std::int64_t until_utime) {
  if (imu_ == nullptr) return;
  const bool lockstep = options_.pacing == Pacing::kLockstep;
  std::int32_t slot = -1;
  estimator::ImuSample<double> sample;
  // Covered: the newest sample is within one IMU period of the exposure.
  const std::int64_t covered_utime = until_utime - options_.imu_period_ns / 1000;
  const TimeNs deadline = core::MonotonicNs() + options_.imu_wait_ns;
  bool waited = false;
  for (;;) {
    if (!imu_->NextImu(until_utime, &sample)) {
      if (last_imu_utime_ >= covered_utime || options_.imu_wait_ns <= 0) break;
      if (core::MonotonicNs() >= deadline) {
        ++counters_.imu_wait_timeouts;
        break;
      }
      if (!waited) ++counters_.imu_waits;
      waited = true;
      std::this_thread::sleep_for(std::chrono::microseconds(200));  // a sample is 2.5-5 ms
      continue;
    }
    last_imu_utime_ = sample.t_us;
    pipeline_->AddImu(sample);
    ++counters_.imu_samples;
    if (!options_.record_frames) continue;
    if (slot < 0) {
      slot = AcquireOutputOrCountDrop(&out_->imus, lockstep, &counters_.outputs_dropped,
                                      &lockstep_wait_ns_);
      if (slot < 0) continue;
      out_->imus[slot].count = 0;
    }
    ImuRecord& r = out_->imus[slot];
    r.samples[r.count++] = sample;
    if (r.count == kImuRecordSamples) {
      Push(&out_->frame_group, RecordRef{RecordKind::kImu, slot});
      slot = -1;
    }
  }
  if (slot >= 0) Push(&out_->frame_group, RecordRef{RecordKind::kImu, slot});
}

void FlightLoop::Push(core::SpscQueue<RecordRef, kOrderQueueSize>* q, RecordRef ref) {
  // The order queue is longer than all pools together, so this cannot fail while slots are
  // accounted for; a failure would be a software bug.
  if (q->TryPush(ref) != Status::kOk) ++counters_.outputs_dropped;
}

Status FlightLoop::Cycle(TimeNs acquire_timeout_ns, bool synchronous_hazard,
                         TimeNs* processing_ns) {
  *processing_ns = 0;
  lockstep_wait_ns_ = 0;
  const TimeNs t0 = core::MonotonicNs();
  // kNotConfigured: the source is down (being restarted, or its last restart failed).
  if (SourceDown()) return MissCycle(Status::kNotConfigured, synchronous_hazard);
  // A camera outage waits one period per missed cycle, whatever the pacing.
  drivers::StereoPair pair;
  Status s = source_->Next(outage_cycles_ > 0 ? period_ns_ : acquire_timeout_ns, &pair);
  const TimeNs t1 = core::MonotonicNs();
  stages_[kStageAcquire].Add(t1 - t0);
  if (s == Status::kTimeout || s == Status::kDeviceLost || s == Status::kIoError) {
    return MissCycle(s, synchronous_hazard);
  }
  if (s != Status::kOk) {
    if (s != Status::kEmpty) ++counters_.source_errors;
    return s;
  }
  EndOutage();
  counters_.frames_dropped += pair.dropped_before;

  PipelineFrame frame;
  frame.left =
      frontend::GrayView{pair.left.data, pair.left.width, pair.left.height, pair.left.stride};
  frame.right =
      frontend::GrayView{pair.right.data, pair.right.width, pair.right.height, pair.right.stride};
  frame.utime = pair.left_exposure_ns / core::kNsPerUs;
  // Frame numbers continue across outages: a source that numbers only the pairs it served (not
  // the frames its camera missed) is shifted past the cycles coasted in between.
  frame.seq = static_cast<std::int64_t>(pair.seq) + seq_offset_;
  if (frame.seq < expected_seq_) {
    seq_offset_ += expected_seq_ - frame.seq;
    frame.seq = expected_seq_;
  }
  expected_seq_ = frame.seq + 1;
  last_frame_utime_ = frame.utime;
  FeedImu(frame.utime + ImuLeadUs());
  drivers::MotionInput motion;
  frame.has_motion =
      motion_ != nullptr && motion_->Motion(static_cast<std::uint64_t>(frame.seq), &motion);
  if (frame.has_motion) {
    frame.motion.t = estimator::Vec3<double>(motion.translation_m[0], motion.translation_m[1],
                                             motion.translation_m[2]);
    frame.motion.R = estimator::ExpSO3<double>(estimator::Vec3<double>(
        motion.rotation_rad[0], motion.rotation_rad[1], motion.rotation_rad[2]));
  }

  Inject(kStageRectify);
  Status stage = pipeline_->Rectify(frame);
  const TimeNs t2 = core::MonotonicNs();
  stages_[kStageRectify].Add(t2 - t1 - lockstep_wait_ns_);
  Inject(kStageTrack);
  if (stage == Status::kOk) stage = pipeline_->Track();
  const TimeNs t3 = core::MonotonicNs();
  stages_[kStageTrack].Add(t3 - t2);
  Inject(kStageEstimate);
  if (stage == Status::kOk) stage = pipeline_->Estimate(frame.has_motion ? &frame.motion : nullptr);
  const TimeNs t4 = core::MonotonicNs();
  stages_[kStageEstimate].Add(t4 - t3);
  if (stage != Status::kOk) ++counters_.stage_errors;

  Inject(kStageOutput);
  const TimeNs waited_before_output = lockstep_wait_ns_;
  if (options_.record_frames) RecordFrame(frame, pair, motion);
  // The hazard snapshot's images are copied before the source gets its buffer back.
  const bool snapshot_frame = (counters_.frames + 1) % options_.hazard_every == 0;
  std::int32_t hazard_slot = -1;
  if (snapshot_frame && hazard_ != nullptr && stage == Status::kOk) {
    hazard_slot = AcquireHazardInput(synchronous_hazard || options_.pacing == Pacing::kLockstep);
    if (hazard_slot >= 0) CopyRectified(&out_->hazard_inputs[hazard_slot]);
  }
  source_->Release(pair);
  if (pipeline_->FramesEstimated() > 0 &&
      (stage == Status::kOk || stage == Status::kNumericalFailure)) {
    PublishNav();
  }
  const TimeNs t5 = core::MonotonicNs();
  const TimeNs waited_before_map = lockstep_wait_ns_;
  stages_[kStageOutput].Add(t5 - t4 - (waited_before_map - waited_before_output));

  ++counters_.frames;
  TimeNs t6 = t5;
  if (snapshot_frame) {
    Inject(kStageMap);
    TakeSnapshot(synchronous_hazard, hazard_slot);
    t6 = core::MonotonicNs();
    stages_[kStageMap].Add(t6 - t5 - (lockstep_wait_ns_ - waited_before_map));
  }
  // The frame group's own work: a lockstep wait for another thread is counted apart.
  *processing_ns = t6 - t1 - lockstep_wait_ns_;
  stages_[kStageCycle].Add(*processing_ns);
  if (++cycles_ % options_.health_every == 0) PublishHealth();
  CountLockstepWait();
  return Status::kOk;
}

// Copies the pair into a frame record for the output thread. A pair the record cannot hold (larger
// than the pool was sized for, or left and right of different sizes) is a counted drop, and its
// slot goes back to the pool at once (kept, every such pair would shrink the pool for good).
void FlightLoop::RecordFrame(const PipelineFrame& frame, const drivers::StereoPair& pair,
                             const drivers::MotionInput& motion) {
  const std::int32_t slot =
      AcquireSlot(&out_->frames, options_.pacing == Pacing::kLockstep, &lockstep_wait_ns_);
  if (slot < 0) {
    ++counters_.outputs_dropped;
    return;
  }
  const std::int32_t w = pair.left.width;
  const std::int32_t h = pair.left.height;
  if (w * h > out_->frames[slot].capacity_bytes || pair.right.width != w ||
      pair.right.height != h) {
    out_->frames.Release(slot);
    ++counters_.outputs_dropped;
    return;
  }
  FrameRecord& r = out_->frames[slot];
  r.utime = frame.utime;
  r.seq = frame.seq;
  r.left_exposure_utime = pair.left_exposure_ns / core::kNsPerUs;
  r.right_exposure_utime = pair.right_exposure_ns / core::kNsPerUs;
  r.dropped_before = static_cast<std::int32_t>(pair.dropped_before);
  r.rectified = !pipeline_->Rectifies();
  r.has_motion = frame.has_motion;
  r.motion = motion;
  r.width = w;
  r.height = h;
  for (std::int32_t y = 0; y < h; ++y) {
    std::memcpy(r.left.get() + static_cast<std::size_t>(y) * w,
                pair.left.data + static_cast<std::size_t>(y) * pair.left.stride,
                static_cast<std::size_t>(w));
    std::memcpy(r.right.get() + static_cast<std::size_t>(y) * w,
                pair.right.data + static_cast<std::size_t>(y) * pair.right.stride,
                static_cast<std::size_t>(w));
  }
  Push(&out_->frame_group, RecordRef{RecordKind::kFrame, slot});
}

void FlightLoop::PublishNav() {
  const std::int32_t slot =
      AcquireOutputOrCountDrop(&out_->navs, options_.pacing == Pacing::kLockstep,
                               &counters_.outputs_dropped, &lockstep_wait_ns_);
  if (slot < 0) return;
  NavRecord& r = out_->navs[slot];
  r.seq = nav_seq_++;
  r.mode = options_.nav_mode;
  pipeline_->MakeNav(&r.nav);
  r.num_new_sightings = pipeline_->NumNewSightings();
  std::copy_n(pipeline_->NewSightings(), r.num_new_sightings, r.new_sightings);
  r.num_features = pipeline_->NumFeatureMarks();
  std::copy_n(pipeline_->FeatureMarks(), r.num_features, r.features);
  Push(&out_->frame_group, RecordRef{RecordKind::kNav, slot});
}

std::int64_t FlightLoop::CyclesOf(TimeNs duration_ns) const {
  const std::int64_t cycles = (duration_ns + period_ns_ - 1) / period_ns_;
  return cycles < 1 ? 1 : cycles;
}

Status FlightLoop::MissCycle(Status source_status, bool synchronous) {
  if (source_status == Status::kTimeout) {
    ++counters_.source_timeouts;
  } else if (source_status != Status::kNotConfigured) {
    ++counters_.source_errors;
  }
  if (outage_cycles_ == 0) {
    ++counters_.camera_outages;
    cycles_since_restart_ = 0;
  }
  ++outage_cycles_;
  ++cycles_since_restart_;
  ++counters_.cycles_missed;
  if (outage_cycles_ > counters_.longest_outage_cycles) {
    counters_.longest_outage_cycles = outage_cycles_;
  }
  // The source's own words name the camera and the cause (kept from before any restart).
  if (source_status != Status::kNotConfigured && source_->LastError()[0] != '\0') {
    std::snprintf(source_fault_, sizeof source_fault_, "%s", source_->LastError());
  }
  if (RestartDue(source_status)) RequestRestart(synchronous);
  if (outage_cycles_ > CyclesOf(options_.max_outage_ns)) return Status::kDeviceLost;

  // The cycle the missing frame would have had: its motion input, a coasted state, its output.
  const TimeNs t1 = core::MonotonicNs();
  drivers::MotionInput motion;
  estimator::Pose<double> camera_prev_T_camera;
  const bool has_motion =
      motion_ != nullptr && motion_->Motion(static_cast<std::uint64_t>(expected_seq_), &motion);
  if (has_motion) {
    camera_prev_T_camera.t = estimator::Vec3<double>(
        motion.translation_m[0], motion.translation_m[1], motion.translation_m[2]);
    camera_prev_T_camera.R = estimator::ExpSO3<double>(estimator::Vec3<double>(
        motion.rotation_rad[0], motion.rotation_rad[1], motion.rotation_rad[2]));
  }
  ++expected_seq_;
  FeedImu(pipeline_->CoastUtime() + ImuLeadUs());
  if (pipeline_->Coast(has_motion ? &camera_prev_T_camera : nullptr) == Status::kOk) {
    ++counters_.cycles_coasted;
    PublishNav();
  }
  stages_[kStageOutput].Add(core::MonotonicNs() - t1 - lockstep_wait_ns_);
  if (++cycles_ % options_.health_every == 0) PublishHealth();
  CountLockstepWait();
  // A lockstep group has no clock but the camera's: a cycle that did not wait a period in
  // Next() waits it here.
  if (options_.pacing == Pacing::kLockstep && !synchronous && source_status != Status::kTimeout) {
    SleepUntil(t1 + period_ns_);
  }
  return Status::kTimeout;
}

bool FlightLoop::RestartDue(Status source_status) const {
  if (restart_busy_.load(std::memory_order_acquire)) return false;
  if (source_down_.load(std::memory_order_acquire)) {
    return cycles_since_restart_ >= CyclesOf(options_.restart_interval_ns);
  }
  return source_status == Status::kDeviceLost || source_status == Status::kIoError ||
         cycles_since_restart_ >= CyclesOf(options_.restart_after_ns);
}

void FlightLoop::EndOutage() {
  if (outage_cycles_ == 0) return;
  ++counters_.source_recoveries;
  outage_cycles_ = 0;
  cycles_since_restart_ = 0;
}

bool FlightLoop::SourceDown() const {
  return restart_busy_.load(std::memory_order_acquire) ||
         source_down_.load(std::memory_order_acquire);
}

void FlightLoop::RequestRestart(bool synchronous) {
  ++counters_.source_restarts;
  cycles_since_restart_ = 0;
  source_down_.store(true, std::memory_order_release);
  if (synchronous) {
    // Step(): no threads; the caller accepts that a restart blocks and allocates.
    source_->Stop();
    source_down_.store(source_->Start() != Status::kOk, std::memory_order_release);
    return;
  }
  restart_busy_.store(true, std::memory_order_release);
  recovery_wake_.release();
}

void FlightLoop::RecoveryMain() {
  for (;;) {
    recovery_wake_.acquire();
    if (recovery_quit_.load(std::memory_order_acquire)) return;
    char fault[sizeof source_fault_];
    std::snprintf(fault, sizeof fault, "%s", source_->LastError());
    source_->Stop();
    const Status s = source_->Start();
    source_down_.store(s != Status::kOk, std::memory_order_release);
    if (s == Status::kOk) {
      std::fprintf(stderr, "frame group: camera fault (%s): the %s source restarted\n", fault,
                   source_->Name());
    } else {
      std::fprintf(stderr, "frame group: camera fault (%s): restarting the %s source: %s: %s\n",
                   fault, source_->Name(), core::ToString(s), source_->LastError());
    }
    restart_busy_.store(false, std::memory_order_release);
  }
}

void FlightLoop::StopRecoveryThread() {
  if (!recovery_thread_.joinable()) return;
  recovery_quit_.store(true, std::memory_order_release);
  recovery_wake_.release();
  recovery_thread_.join();
}

void FlightLoop::CountLockstepWait() {
  if (lockstep_wait_ns_ <= 0) return;
  ++counters_.lockstep_waits;
  counters_.lockstep_wait_ns += lockstep_wait_ns_;
  counters_.lockstep_wait_max_ns = std::max(counters_.lockstep_wait_max_ns, lockstep_wait_ns_);
}

std::int32_t FlightLoop::AcquireHazardInput(bool wait) {
  // Lockstep: wait for the hazard group (bounded) so every snapshot frame is mapped.
  const std::int32_t slot = AcquireSlot(&out_->hazard_inputs, wait, &lockstep_wait_ns_);
  if (slot < 0) ++counters_.hazard_skipped;
  return slot;
}

void FlightLoop::CopyRectified(HazardInput* h) {
  const frontend::GrayView& l = pipeline_->RectifiedLeft();
  const frontend::GrayView& r = pipeline_->RectifiedRight();
  h->width = 0;
  h->height = 0;
  if (!l.Valid() || !r.Valid() || l.width != r.width || l.height != r.height ||
      l.width * l.height > h->capacity_bytes) {
    return;
  }
  h->width = l.width;
  h->height = l.height;
  for (std::int32_t y = 0; y < l.height; ++y) {
    std::memcpy(h->left.get() + static_cast<std::size_t>(y) * l.width,
                l.data + static_cast<std::size_t>(y) * l.stride, static_cast<std::size_t>(l.width));
    std::memcpy(h->right.get() + static_cast<std::size_t>(y) * r.width,
                r.data + static_cast<std::size_t>(y) * r.stride, static_cast<std::size_t>(r.width));
  }
}

void FlightLoop::TakeSnapshot(bool synchronous, std::int32_t hazard_slot) {
  const std::int32_t slot =
      AcquireOutputOrCountDrop(&out_->maps, options_.pacing == Pacing::kLockstep,
                               &counters_.outputs_dropped, &lockstep_wait_ns_);
  if (slot < 0) {
    if (hazard_slot >= 0) out_->hazard_inputs.Release(hazard_slot);
    return;
  }
  MapRecord& r = out_->maps[slot];
  if (pipeline_->MakeMap(&r.map) != Status::kOk) r.map.num_landmarks = 0;
  r.seq = map_seq_++;
  if (hazard_slot >= 0) {
    HazardInput& h = out_->hazard_inputs[hazard_slot];
    h.utime = r.map.utime;
    h.frame_seq = r.map.frame_seq;
    estimator::Mat6<double> cov;
    h.pose_valid = h.width > 0 && pipeline_->NewestPose(&h.world_T_camera, &cov) == Status::kOk;
    h.pose_covariance = cov;
    h.num_landmarks = 0;
    for (std::int32_t i = 0; i < r.map.num_landmarks && i < kMaxMapLandmarks; ++i) {
      const MapLandmark& l = r.map.landmarks[i];
      hazard::HazardLandmark& d = h.landmarks[h.num_landmarks++];
      d.id = l.id;  // the mapper enters each landmark once, as its newest estimate
      d.position_world_m =
          Eigen::Vector3d(l.position_world_m[0], l.position_world_m[1], l.position_world_m[2]);
      const double* c = l.covariance_m2;
      d.covariance << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
    }
  }
  Push(&out_->frame_group, RecordRef{RecordKind::kMap, slot});
  if (hazard_slot < 0) return;
  if (synchronous) {
    RunHazard(hazard_slot, &out_->frame_group, true);
    return;
  }
  if (out_->hazard_work.TryPush(hazard_slot) != Status::kOk) {
    out_->hazard_inputs.Release(hazard_slot);  // cannot happen: the queue holds every slot
    ++counters_.hazard_skipped;
    return;
  }
  hazard_wake_.release();
}

void FlightLoop::RunHazard(std::int32_t input_slot, core::SpscQueue<RecordRef, kOrderQueueSize>* q,
                           bool wait) {
  // A slot kept from a failed update first (only the output thread may give slots back).
  std::int32_t slot = hazard_spare_slot_;
  hazard_spare_slot_ = -1;
  if (slot < 0) slot = out_->hazards.Acquire();
  for (int i = 0; slot < 0 && wait && i < 200000; ++i) {
    std::this_thread::sleep_for(std::chrono::microseconds(100));
    slot = out_->hazards.Acquire();
  }
  const HazardInput& in = out_->hazard_inputs[input_slot];
  if (slot < 0) {
    hazard_outputs_dropped_.fetch_add(1, std::memory_order_relaxed);
    out_->hazard_inputs.Release(input_slot);
    return;
  }
  HazardRecord& rec = out_->hazards[slot];
  const TimeNs t0 = core::MonotonicNs();
  const Status s = hazard_->Process(in, &rec);
  const TimeNs t1 = core::MonotonicNs();
  out_->hazard_inputs.Release(input_slot);
  hazard_stage_.Add(t1 - t0);
  // Slower than the snapshots come at the camera rate: in real time the next would be skipped.
  if (t1 - t0 > options_.hazard_every * period_ns_) {
    hazard_overruns_.fetch_add(1, std::memory_order_relaxed);
  }
  const StageSummary summary = hazard_stage_.Summarize();
  while (hazard_summary_lock_.test_and_set(std::memory_order_acquire)) {
  }
  hazard_summary_ = summary;
  hazard_summary_lock_.clear(std::memory_order_release);
  if (s != Status::kOk) {
    hazard_errors_.fetch_add(1, std::memory_order_relaxed);
    hazard_spare_slot_ = slot;
    return;
  }
  rec.update_ms = static_cast<float>(core::NsToMs(t1 - t0));
  rec.seq = hazard_seq_++;
  if (q->TryPush(RecordRef{RecordKind::kHazard, slot}) != Status::kOk) {
    hazard_outputs_dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

void FlightLoop::HazardMain() {
  char message[160];
  (void)MakeThreadRealtime(options_.hazard_priority, message, sizeof message);
  BeginRealtimeAllocationCounting();
  const bool wait = options_.pacing == Pacing::kLockstep;
  for (;;) {
    hazard_wake_.acquire();
    std::int32_t slot = -1;
    while (out_->hazard_work.TryPop(&slot) == Status::kOk) {
      RunHazard(slot, &out_->hazard_group, wait);
    }
    if (hazard_quit_.load(std::memory_order_acquire) && out_->hazard_work.SizeApprox() == 0) return;
  }
}

void FlightLoop::PublishHealth() {
  const std::int32_t slot =
      AcquireOutputOrCountDrop(&out_->healths, options_.pacing == Pacing::kLockstep,
                               &counters_.outputs_dropped, &lockstep_wait_ns_);
  if (slot < 0) return;
  HealthRecord& h = out_->healths[slot];
  h.utime = last_frame_utime_;
  h.seq = health_seq_++;
  h.frames = counters_.frames;
  const drivers::SourceStats source = source_->Stats();
  h.frames_dropped = counters_.frames_dropped + static_cast<std::int64_t>(source.frames_dropped);
  h.frames_rejected = static_cast<std::int64_t>(source.frames_rejected);
  h.camera_missing_packets = static_cast<std::int64_t>(source.missing_packets);
  h.camera_pairing_failures = static_cast<std::int64_t>(source.pairing_failures);
  h.camera_timeouts = static_cast<std::int64_t>(source.timeouts);
  h.overruns = counters_.overruns;
  h.outputs_dropped =
      counters_.outputs_dropped + hazard_outputs_dropped_.load() + counters_.hazard_skipped;
  h.allocations_after_start = RealtimeAllocations();
  h.fault_bits = static_cast<std::int32_t>(pipeline_->FaultBits());
  if (counters_.source_errors > 0 || counters_.source_timeouts > 0) h.fault_bits |= 64;
  if (h.outputs_dropped > 0) h.fault_bits |= 32;
  h.estimator_status = static_cast<std::int8_t>(pipeline_->LastStatus());
  h.num_features = pipeline_->NumFeatures();
  h.num_landmarks = pipeline_->NumLandmarks();
  h.integrity = pipeline_->Integrity();
  h.imu = pipeline_->ImuStreamCounts();
  for (int i = 0; i < kNumStages; ++i) {
    if (i != kStageHazard) h.stages[i] = stages_[i].Summarize();
  }
  while (hazard_summary_lock_.test_and_set(std::memory_order_acquire)) {
  }
  h.stages[kStageHazard] = hazard_summary_;
  hazard_summary_lock_.clear(std::memory_order_release);
  Push(&out_->frame_group, RecordRef{RecordKind::kHealth, slot});
}

Status FlightLoop::Step() {
  if (!configured_) return Status::kNotConfigured;
  TimeNs processing = 0;
  const Status s = Cycle(options_.acquire_timeout_ns, true, &processing);
  if (s == Status::kOk && processing > period_ns_) ++counters_.overruns;
  counters_.hazard_overruns = hazard_overruns_.load();
  return s;
}

Status FlightLoop::Run() {
  if (!configured_) return Status::kNotConfigured;
  stop_.store(false);
  hazard_quit_.store(false);
  recovery_quit_.store(false);
  restart_busy_.store(false);
  // Each thread paints its stack before the start figures are taken (the painting's page faults
  // are part of starting, not of running).
  memory_.frame_group.Paint();
  std::latch painted(2);
  hazard_thread_ = std::thread([this, &painted] {
    memory_.hazard.Paint();
    painted.count_down();
    HazardMain();
    memory_.hazard.Measure();
  });
  recovery_thread_ = std::thread([this, &painted] {
    memory_.recovery.Paint();
    painted.count_down();
    RecoveryMain();
    memory_.recovery.Measure();
  });
  painted.wait();
  memory_.at_start = core::ReadProcessMemory();
  BeginRealtimeAllocationCounting();
  Status result = Status::kOk;
  TimeNs next = core::MonotonicNs();
  const bool realtime = options_.pacing == Pacing::kRealtime;
  while (!stop_.load(std::memory_order_relaxed)) {
    if (options_.max_frames > 0 && counters_.frames >= options_.max_frames) break;
    if (realtime) SleepUntil(next);
    const TimeNs tick = realtime ? next : core::MonotonicNs();
    TimeNs processing = 0;
    const Status s = Cycle(realtime ? period_ns_ : options_.acquire_timeout_ns, false, &processing);
    const TimeNs end = core::MonotonicNs();
    if (s == Status::kEmpty) break;
    if (s != Status::kOk && s != Status::kTimeout) {
      result = s;
      break;
    }
    if (realtime) {
      if (s == Status::kOk && end > tick + period_ns_) {
        ++counters_.overruns;
        const TimeNs ticks = (end - tick) / period_ns_ + 1;  // to the first grid tick after end
        counters_.ticks_skipped += ticks - 1;
        next = tick + ticks * period_ns_;
      } else {
        next = tick + period_ns_;
      }
    } else if (s == Status::kOk && processing > period_ns_) {
      ++counters_.overruns;
    }
  }
  // Let the hazard group finish its last snapshot, then report.
  hazard_quit_.store(true, std::memory_order_release);
  hazard_wake_.release();
  hazard_thread_.join();
  counters_.hazard_overruns = hazard_overruns_.load();
  StopRecoveryThread();
  memory_.frame_group.Measure();
  memory_.at_end = core::ReadProcessMemory();
  PublishHealth();
  if (result == Status::kDeviceLost) {
    std::fprintf(stderr,
                 "frame group: camera lost for %lld cycles (max_outage %.1f s): %s; navigation "
                 "ended\n",
                 static_cast<long long>(outage_cycles_), core::NsToMs(options_.max_outage_ns) / 1e3,
                 source_fault_);
  }
  return result;
}

}  // namespace swf::app
