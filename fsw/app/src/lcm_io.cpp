#include "swf/app/lcm_io.hpp"

#include <Eigen/Geometry>

#include <lcm/eventlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <lcm/lcm-cpp.hpp>

#include "swf/drivers/imu_message.hpp"
#include "swf/messages/checked_decode.hpp"
#include "swf_msgs/feature_set_t.hpp"
#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/health_t.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::app {

struct OutputThread::Impl {
  std::unique_ptr<lcm::LCM> lcm;
  lcm_eventlog_t* log = nullptr;
  std::string prefix;
  Route frame_route = Route::kBusAndLog;
  std::vector<std::uint8_t> buffer;  // encode target, sized at Open
  std::string channel;               // reused: capacity reserved at Open
  swf_msgs::stereo_frame_t frame;
  swf_msgs::imu_t imu;
  swf_msgs::nav_state_t nav;
  swf_msgs::landmark_map_t map;
  swf_msgs::health_t health;
  swf_msgs::hazard_map_t hazard;
  swf_msgs::feature_set_t features;
  std::int64_t features_seq = 0;
};

OutputThread::OutputThread() : impl_(new Impl()) {}

OutputThread::~OutputThread() {
  StopAndDrain();
  if (impl_->log != nullptr) lcm_eventlog_destroy(impl_->log);
}

bool OutputThread::Open(const OutputOptions& options, OutputChannels* channels,
                        std::string* error) {
  channels_ = channels;
  impl_->prefix = options.channel_prefix;
  impl_->frame_route = options.record_frames ? Route::kBusAndLog : Route::kBusOnly;
  impl_->channel.reserve(64);
  if (!options.lcm_url.empty()) {
    impl_->lcm = std::make_unique<lcm::LCM>(options.lcm_url);
    if (!impl_->lcm->good()) {
      *error = "lcm.url: cannot open LCM at '" + options.lcm_url +
               "' (udpm needs a multicast route; see RECIPES.md)";
      return false;
    }
  }
  if (!options.record_path.empty()) {
    impl_->log = lcm_eventlog_create(options.record_path.c_str(), "w");
    if (impl_->log == nullptr) {
      *error = "record.path: cannot create '" + options.record_path + "'";
      return false;
    }
  }
  // Worst cases: a frame of the largest size, a full landmark map; reserve every vector now.
  const std::size_t pixels = static_cast<std::size_t>(options.max_width) * options.max_height;
  impl_->frame.left.reserve(pixels);
  impl_->frame.right.reserve(pixels);
  impl_->map.id.reserve(kMaxMapLandmarks);
  impl_->map.position_world_m.reserve(kMaxMapLandmarks);
  impl_->map.covariance_m2.reserve(kMaxMapLandmarks);
  impl_->map.num_observations.reserve(kMaxMapLandmarks);
  impl_->features.id.reserve(kMaxFeatureMarks);
  impl_->features.u_px.reserve(kMaxFeatureMarks);
  impl_->features.v_px.reserve(kMaxFeatureMarks);
  impl_->features.status.reserve(kMaxFeatureMarks);
  impl_->health.stage_name.reserve(kNumStages);
  impl_->health.stage_p50_ms.reserve(kNumStages);
  impl_->health.stage_p99_ms.reserve(kNumStages);
  impl_->health.stage_max_ms.reserve(kNumStages);
  const std::size_t cells =
      static_cast<std::size_t>(options.max_hazard_cells) * options.max_hazard_cells;
  impl_->hazard.elevation_m.reserve(cells);
  impl_->hazard.sigma_m.reserve(cells);
  impl_->hazard.relief_sigma_m.reserve(cells);
  impl_->hazard.slope_deg.reserve(cells);
  impl_->hazard.roughness_m.reserve(cells);
  impl_->hazard.hazard_class.reserve(cells);
  impl_->buffer.assign(std::max(2 * pixels, 21 * cells) + 128 * kMaxMapLandmarks + 65536, 0);
  return true;
}

void OutputThread::Start() {
  quit_.store(false);
  thread_ = std::thread([this] {
    stack_.Paint();
    while (!quit_.load(std::memory_order_acquire)) {
      DrainOnce();
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    DrainOnce();
    stack_.Measure();
  });
}

void OutputThread::StopAndDrain() {
  if (thread_.joinable()) {
    quit_.store(true, std::memory_order_release);
    thread_.join();
  }
  if (channels_ != nullptr) DrainOnce();
  if (impl_->log != nullptr) std::fflush(impl_->log->f);
}

void OutputThread::DrainOnce() {
  RecordRef ref;
  while (channels_->frame_group.TryPop(&ref) == core::Status::kOk) Handle(ref);
  while (channels_->hazard_group.TryPop(&ref) == core::Status::kOk) Handle(ref);
}

void OutputThread::Emit(const char* suffix, std::int64_t utime, const std::uint8_t* data, int size,
                        Route route) {
  impl_->channel.assign(impl_->prefix);
  impl_->channel.append(suffix);
  EmitOn(impl_->channel, utime, data, size, route);
}

void OutputThread::Send(const std::string& channel, std::int64_t utime, const std::uint8_t* data,
                        int size) {
  EmitOn(channel, utime, data, size, Route::kBusAndLog);
}

void OutputThread::EmitOn(const std::string& channel, std::int64_t utime, const std::uint8_t* data,
                          int size, Route route) {
  for (OutputObserver* o : observers_) o->OnMessage(channel, data, size);
  if (impl_->lcm && route != Route::kLogOnly) {
    if (impl_->lcm->publish(channel, data, static_cast<unsigned>(size)) == 0) {
      ++counters_.published;
    } else {
      ++counters_.publish_errors;
    }
  }
  if (impl_->log != nullptr && route != Route::kBusOnly) {
    lcm_eventlog_event_t event{};
    event.timestamp = utime;  // the data's own time: logs of identical runs are identical
    event.channellen = static_cast<std::int32_t>(channel.size());
    event.datalen = size;
    event.channel = const_cast<char*>(channel.data());
    event.data = const_cast<std::uint8_t*>(data);
    if (lcm_eventlog_write_event(impl_->log, &event) == 0) {
      ++counters_.recorded;
    } else {
      ++counters_.record_errors;
    }
  }
}

namespace {

// Record -> message, one function per kind; the messages' buffers were sized at Open.
void FillFrame(const FrameRecord& r, swf_msgs::stereo_frame_t* m) {
  m->utime = r.utime;
  m->seq = r.seq;
  m->left_exposure_utime = r.left_exposure_utime;
  m->right_exposure_utime = r.right_exposure_utime;
  m->dropped_before = r.dropped_before;
  m->rectified = r.rectified;
  m->has_motion = r.has_motion;
  for (int i = 0; i < 3; ++i) {
    m->motion_translation_m[i] = r.has_motion ? r.motion.translation_m[i] : 0.0;
    m->motion_rotation_rad[i] = r.has_motion ? r.motion.rotation_rad[i] : 0.0;
  }
  m->width = r.width;
  m->height = r.height;
  m->num_bytes = r.width * r.height;
  m->left.assign(r.left.get(), r.left.get() + m->num_bytes);
  m->right.assign(r.right.get(), r.right.get() + m->num_bytes);
}

void FillNav(const NavRecord& r, swf_msgs::nav_state_t* m) {
  m->utime = r.nav.utime;
  m->seq = r.seq;
  m->frame_seq = r.nav.frame_seq;
  std::memcpy(m->position_world_m, r.nav.position_world_m, sizeof m->position_world_m);
  std::memcpy(m->orientation_world_q, r.nav.orientation_world_q, sizeof m->orientation_world_q);
  std::memcpy(m->velocity_world_mps, r.nav.velocity_world_mps, sizeof m->velocity_world_mps);
  std::memcpy(m->covariance, r.nav.covariance, sizeof m->covariance);
  m->mode = r.mode;
  m->status = r.nav.status;
  m->integrity_flags = r.nav.integrity_flags;
  m->horizontal_protection_m = r.nav.horizontal_protection_m;
  m->vertical_protection_m = r.nav.vertical_protection_m;
  m->integrity_risk = r.nav.integrity_risk;
  m->update_status = r.nav.update_status;
  m->fault_bits = r.nav.fault_bits;
  m->iterations = r.nav.iterations;
  m->num_measurements = r.nav.num_measurements;
}

void FillMap(const MapRecord& r, swf_msgs::landmark_map_t* m) {
  m->utime = r.map.utime;
  m->seq = r.seq;
  m->frame_seq = r.map.frame_seq;
  m->num_landmarks = r.map.num_landmarks;
  m->id.resize(m->num_landmarks);
  m->position_world_m.resize(m->num_landmarks);
  m->covariance_m2.resize(m->num_landmarks);
  m->num_observations.resize(m->num_landmarks);
  for (int i = 0; i < m->num_landmarks; ++i) {
    const MapLandmark& l = r.map.landmarks[i];
    m->id[i] = l.id;
    m->position_world_m[i].assign(l.position_world_m, l.position_world_m + 3);
    m->covariance_m2[i].assign(l.covariance_m2, l.covariance_m2 + 6);
    m->num_observations[i] = l.num_observations;
  }
}

void FillFeatures(const NavRecord& r, std::int64_t seq, swf_msgs::feature_set_t* m) {
  m->utime = r.nav.utime;
  m->seq = seq;
  m->frame_seq = r.nav.frame_seq;
  m->num_features = r.num_features;
  m->id.resize(r.num_features);
  m->u_px.resize(r.num_features);
  m->v_px.resize(r.num_features);
  m->status.resize(r.num_features);
  for (int i = 0; i < r.num_features; ++i) {
    m->id[i] = r.features[i].id;
    m->u_px[i] = r.features[i].u_px;
    m->v_px[i] = r.features[i].v_px;
    m->status[i] = static_cast<std::int8_t>(r.features[i].fate);
  }
}

void FillHazard(const HazardRecord& r, swf_msgs::hazard_map_t* m) {
  m->utime = r.utime;
  m->seq = r.seq;
  m->frame_seq = r.frame_seq;
  m->origin_world_m[0] = r.origin_world_m[0];
  m->origin_world_m[1] = r.origin_world_m[1];
  m->up_world[0] = 0.0;  // the estimator's world frame is local level, z up
  m->up_world[1] = 0.0;
  m->up_world[2] = 1.0;
  m->cell_size_m = r.cell_size_m;
  m->rows = r.cells_per_side;
  m->cols = r.cells_per_side;
  m->num_cells = r.cells_per_side * r.cells_per_side;
  m->elevation_m.assign(r.elevation_m.get(), r.elevation_m.get() + m->num_cells);
  m->sigma_m.assign(r.sigma_m.get(), r.sigma_m.get() + m->num_cells);
  m->relief_sigma_m.assign(r.relief_sigma_m.get(), r.relief_sigma_m.get() + m->num_cells);
  m->slope_deg.assign(r.slope_deg.get(), r.slope_deg.get() + m->num_cells);
  m->roughness_m.assign(r.roughness_m.get(), r.roughness_m.get() + m->num_cells);
  m->hazard_class.assign(r.hazard_class.get(), r.hazard_class.get() + m->num_cells);
  m->safe_site_valid = r.safe_site_valid;
  m->safe_site_world_m[0] = r.safe_site_world_m[0];
  m->safe_site_world_m[1] = r.safe_site_world_m[1];
  m->safe_site_score = r.safe_site_score;
  m->outliers_rejected = r.outliers_rejected;
  m->cells_replaced = r.cells_replaced;
}

void FillHealth(const HealthRecord& r, swf_msgs::health_t* m) {
  m->utime = r.utime;
  m->seq = r.seq;
  m->frames = r.frames;
  m->frames_dropped = r.frames_dropped;
  m->frames_rejected = r.frames_rejected;
  m->overruns = r.overruns;
  m->outputs_dropped = r.outputs_dropped;
  m->allocations_after_start = r.allocations_after_start;
  m->fault_bits = r.fault_bits;
  m->estimator_status = r.estimator_status;
  m->num_features = r.num_features;
  m->num_landmarks = r.num_landmarks;
  const IntegrityCounters& ic = r.integrity;
  m->frames_valid = ic.frames_valid;
  m->frames_degraded = ic.frames_degraded;
  m->frames_invalid = ic.frames_invalid;
  m->restarts = ic.restarts;
  m->last_recovery_frames = ic.last_recovery_frames;
  m->measurements_gated = ic.measurements_gated;
  m->measurements_rejected = ic.measurements_rejected;
  m->landmarks_rejected = ic.landmarks_rejected;
  m->new_landmarks_refused = ic.new_landmarks_refused;
  m->gate_suspensions = ic.gate_suspensions;
  m->num_integrity_flags = estimator::kNumIntegrityFlags;
  m->integrity_flag_counts.assign(ic.flag_counts, ic.flag_counts + estimator::kNumIntegrityFlags);
  m->num_stages = kNumStages;
  m->stage_name.resize(kNumStages);
  m->stage_p50_ms.resize(kNumStages);
  m->stage_p99_ms.resize(kNumStages);
  m->stage_max_ms.resize(kNumStages);
  for (int i = 0; i < kNumStages; ++i) {
    m->stage_name[i] = StageName(i);
    m->stage_p50_ms[i] = r.stages[i].p50_ms;
    m->stage_p99_ms[i] = r.stages[i].p99_ms;
    m->stage_max_ms[i] = r.stages[i].max_ms;
  }
  const estimator::ImuStreamCounts& imu = r.imu.stream;
  m->imu_accepted = imu.accepted;
  m->imu_out_of_order = imu.out_of_order;
  m->imu_duplicated = imu.duplicated;
  m->imu_invalid = imu.invalid;
  m->imu_saturated = imu.saturated;
  m->imu_missing = imu.missing_samples + r.imu.overflowed;
  m->imu_intervals_bridged = r.imu.intervals_bridged;
  m->camera_missing_packets = r.camera_missing_packets;
  m->camera_pairing_failures = r.camera_pairing_failures;
  m->camera_timeouts = r.camera_timeouts;
}

}  // namespace

// Each record: observers see it, it is encoded and its slot goes back to the producer, then it
// is published and recorded. The IMU's records carry many samples, each recorded (not
// published: the IMU's own publisher owns that channel).
void OutputThread::Handle(const RecordRef& ref) {
  std::uint8_t* buf = impl_->buffer.data();
  const int max = static_cast<int>(impl_->buffer.size());
  const auto publish = [&](auto& message, auto& pool, const char* suffix,
                           Route route = Route::kBusAndLog) {
    const int n = message.encode(buf, 0, max);
    pool.Release(ref.slot);
    if (n < 0) {
      ++counters_.encode_errors;
      return;
    }
    Emit(suffix, message.utime, buf, n, route);
  };
  // The records the observers see: filled into their message, shown to them, then published.
  const auto observe_and_publish = [&](auto& pool, auto fill, auto on_record, auto& message,
                                       const char* suffix) {
    const auto& r = pool[ref.slot];
    fill(r, &message);
    for (OutputObserver* o : observers_) (o->*on_record)(r);
    publish(message, pool, suffix);
  };
  switch (ref.kind) {
    case RecordKind::kFrame:
      FillFrame(channels_->frames[ref.slot], &impl_->frame);
      publish(impl_->frame, channels_->frames, kStereoSuffix, impl_->frame_route);
      return;
    case RecordKind::kImu: {
      const ImuRecord& r = channels_->imus[ref.slot];
      swf_msgs::imu_t& m = impl_->imu;
      for (std::int32_t k = 0; k < r.count; ++k) {
        drivers::ImuMessageOf(r.samples[k], &m);
        const int n = m.encode(buf, 0, max);
        if (n < 0) {
          ++counters_.encode_errors;
          continue;
        }
        Emit(kImuSuffix, m.utime, buf, n, Route::kLogOnly);
      }
      channels_->imus.Release(ref.slot);
      return;
    }
    case RecordKind::kNav: {
      // The frame's features go out after its estimate (filled before the slot is released).
      FillFeatures(channels_->navs[ref.slot], impl_->features_seq++, &impl_->features);
      observe_and_publish(channels_->navs, FillNav, &OutputObserver::OnNav, impl_->nav, kNavSuffix);
      const int n = impl_->features.encode(buf, 0, max);
      if (n < 0) {
        ++counters_.encode_errors;
        return;
      }
      Emit(kFeaturesSuffix, impl_->features.utime, buf, n);
      return;
    }
    case RecordKind::kMap:
      observe_and_publish(channels_->maps, FillMap, &OutputObserver::OnMap, impl_->map,
                          kLandmarksSuffix);
      return;
    case RecordKind::kHazard:
      observe_and_publish(channels_->hazards, FillHazard, &OutputObserver::OnHazard, impl_->hazard,
                          kHazardSuffix);
      return;
    case RecordKind::kHealth:
      observe_and_publish(channels_->healths, FillHealth, &OutputObserver::OnHealth, impl_->health,
                          kHealthSuffix);
      return;
  }
}

struct LcmImuInput::Impl {
  std::unique_ptr<lcm::LCM> lcm;
};

LcmImuInput::LcmImuInput() = default;
LcmImuInput::~LcmImuInput() { Stop(); }

bool LcmImuInput::Start(const std::string& lcm_url, const std::string& channel,
                        std::string* error) {
  impl_ = std::make_unique<Impl>();
  impl_->lcm = std::make_unique<lcm::LCM>(lcm_url);
  if (!impl_->lcm->good()) {
    *error = "imu: cannot open LCM at '" + lcm_url + "' to receive " + channel;
    return false;
  }
  impl_->lcm->subscribeFunction(
      channel,
      +[](const lcm::ReceiveBuffer* rbuf, const std::string&, LcmImuInput* self) {
        self->received_.fetch_add(1, std::memory_order_relaxed);
        swf_msgs::imu_t m;
        if (!messages::CheckedDecode(rbuf->data, rbuf->data_size, &m).Ok()) {
          self->undecodable_.fetch_add(1, std::memory_order_relaxed);
          return;
        }
        if (self->queue_.TryPush(drivers::ImuSampleOf(m)) != core::Status::kOk)
          self->queue_full_.fetch_add(1, std::memory_order_relaxed);
      },
      this);
  quit_.store(false);
  thread_ = std::thread([this] {
    while (!quit_.load()) impl_->lcm->handleTimeout(50);
  });
  return true;
}

void LcmImuInput::Stop() {
  quit_.store(true);
  if (thread_.joinable()) thread_.join();
}

bool LcmImuInput::NextImu(std::int64_t until_utime, estimator::ImuSample<double>* sample) {
  for (;;) {
    if (!held_) {
      if (queue_.TryPop(&held_sample_) != core::Status::kOk) return false;
      held_ = true;
    }
    // Unsigned difference: no overflow on a corrupt stamp.
    const bool far_ahead =
        held_sample_.t_us > until_utime &&
        static_cast<std::uint64_t>(held_sample_.t_us) - static_cast<std::uint64_t>(until_utime) >
            static_cast<std::uint64_t>(kMaxImuLeadUs);
    if (far_ahead) {
      held_ = false;
      ++future_dropped_;
      continue;
    }
    if (held_sample_.t_us > until_utime) return false;
    *sample = held_sample_;
    held_ = false;
    return true;
  }
}

LcmImuCounters LcmImuInput::Counters() const {
  LcmImuCounters c;
  c.received = received_.load();
  c.undecodable = undecodable_.load();
  c.queue_full = queue_full_.load();
  c.future_dropped = future_dropped_;
  return c;
}

}  // namespace swf::app
