// What the real-time threads hand to the output thread, and how: fixed pools of slots (sized
// before start) passed by index through lock-free single-producer/single-consumer queues. The
// producer acquires a free slot, fills it, and pushes {kind, slot} to its order queue; the output
// thread encodes and publishes/records it, then returns the slot. No allocation, no blocking on
// either side; an exhausted pool is a counted drop (health_t.outputs_dropped).
#pragma once

#include <cstdint>
#include <memory>
#include <new>

#include "swf/app/pipeline.hpp"
#include "swf/app/stage_timer.hpp"
#include "swf/core/slot_pool.hpp"
#include "swf/core/spsc_queue.hpp"
#include "swf/core/status.hpp"
#include "swf/drivers/process_input.hpp"
#include "swf/hazard/hazard_mapper.hpp"

namespace swf::app {

// Frame-group stages, in order (health_t.stage_name).
enum Stage : int {
  kStageAcquire = 0,  // waiting for and taking the pair from the source
  kStageRectify,
  kStageTrack,
  kStageEstimate,
  kStageOutput,  // navigation output (incl. covariance) and queueing
  kStageMap,     // landmark map snapshot for the hazard group (every hazard_every frames)
  kStageCycle,   // the whole cycle after acquisition
  kStageHazard,  // hazard group: HazardStage::Process (dense stereo + map + site), its own thread
  kNumStages
};
const char* StageName(int stage);

// An input pair copied for recording (stereo_frame_t).
struct FrameRecord {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int64_t left_exposure_utime = 0;
  std::int64_t right_exposure_utime = 0;
  std::int32_t dropped_before = 0;
  bool rectified = true;
  bool has_motion = false;
  drivers::MotionInput motion;  // camera_prev_T_camera from the navigation system
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::unique_ptr<std::uint8_t[]> left;  // capacity fixed at start (FramePoolCapacity)
  std::unique_ptr<std::uint8_t[]> right;
  std::int32_t capacity_bytes = 0;
};

// IMU samples the frame group handed to the pipeline, in that order (imu_t, one per sample),
// recorded ahead of the frame they precede.
inline constexpr int kImuRecordSamples = 64;
struct ImuRecord {
  std::int32_t count = 0;
  estimator::ImuSample<double> samples[kImuRecordSamples];
};

struct NavRecord {
  std::int64_t seq = 0;
  std::int8_t mode = 0;
  NavOutput nav;
  // The landmarks the frame started (not published: for observers of the output thread).
  std::int32_t num_new_sightings = 0;
  NewSighting new_sightings[kMaxNewSightings];
  // The frame's features and their fate (feature_set_t, published beside the estimate).
  std::int32_t num_features = 0;
  FeatureMark features[kMaxFeatureMarks];
};

struct MapRecord {
  std::int64_t seq = 0;
  MapOutput map;
};

struct HealthRecord {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int64_t frames = 0;
  std::int64_t frames_dropped = 0;
  std::int64_t frames_rejected = 0;  // received but refused by the source (SourceStats)
  // The camera's own counters (SourceStats; health_t.camera_*).
  std::int64_t camera_missing_packets = 0;
  std::int64_t camera_pairing_failures = 0;
  std::int64_t camera_timeouts = 0;
  std::int64_t overruns = 0;
  std::int64_t outputs_dropped = 0;
  std::int64_t allocations_after_start = 0;  // -1 when this binary does not count them
  std::int32_t fault_bits = 0;
  std::int8_t estimator_status = 0;
  std::int32_t num_features = 0;
  std::int32_t num_landmarks = 0;
  IntegrityCounters integrity;
  StageSummary stages[kNumStages];
  ImuCounts imu;
};

// What the frame group hands to the hazard group every hazard_every frames: the rectified pair
// (copied into buffers sized at start), the newest pose with its 6x6 covariance and the landmark
// map with covariances, all of the same frame.
struct HazardInput {
  std::int64_t utime = 0;
  std::int64_t frame_seq = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::unique_ptr<std::uint8_t[]> left;  // width * height, capacity fixed at start
  std::unique_ptr<std::uint8_t[]> right;
  std::int32_t capacity_bytes = 0;
  bool pose_valid = false;
  estimator::Pose<double> world_T_camera;
  Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  std::int32_t num_landmarks = 0;
  hazard::HazardLandmark landmarks[kMaxMapLandmarks];
};

// hazard_map_t without the transport fields; arrays sized at start (cells = grid_cells^2).
struct HazardRecord {
  std::int64_t seq = 0;
  std::int64_t utime = 0;
  std::int64_t frame_seq = 0;
  double origin_world_m[2] = {0.0, 0.0};
  double cell_size_m = 0.0;
  std::int32_t cells_per_side = 0;
  std::int32_t capacity_cells = 0;
  std::unique_ptr<float[]> elevation_m;
  std::unique_ptr<float[]> sigma_m;
  std::unique_ptr<float[]> relief_sigma_m;
  std::unique_ptr<float[]> slope_deg;
  std::unique_ptr<float[]> roughness_m;
  std::unique_ptr<std::int8_t[]> hazard_class;
  bool safe_site_valid = false;
  double safe_site_world_m[2] = {0.0, 0.0};
  double safe_site_score = 0.0;
  std::int64_t outliers_rejected = 0;  // the mapper's outlier gate since start (HazardStats)
  std::int64_t cells_replaced = 0;
  float update_ms = 0.0f;  // wall time of the hazard update (not published; not deterministic)

  // Sizes the arrays for `cells` cells (grid_cells^2); before start only (it allocates).
  core::Status Allocate(std::int32_t cells) {
    elevation_m.reset(new (std::nothrow) float[cells]);
    sigma_m.reset(new (std::nothrow) float[cells]);
    relief_sigma_m.reset(new (std::nothrow) float[cells]);
    slope_deg.reset(new (std::nothrow) float[cells]);
    roughness_m.reset(new (std::nothrow) float[cells]);
    hazard_class.reset(new (std::nothrow) std::int8_t[cells]);
    if (!elevation_m || !sigma_m || !relief_sigma_m || !slope_deg || !roughness_m ||
        !hazard_class) {
      capacity_cells = 0;
      return core::Status::kFull;
    }
    capacity_cells = cells;
    return core::Status::kOk;
  }
};

enum class RecordKind : std::uint8_t { kFrame, kNav, kMap, kHealth, kHazard, kImu };
struct RecordRef {
  RecordKind kind = RecordKind::kNav;
  std::int32_t slot = -1;
};

inline constexpr std::size_t kFramePoolSize = 16;
inline constexpr std::size_t kImuPoolSize = 64;
inline constexpr std::size_t kNavPoolSize = 64;
inline constexpr std::size_t kMapPoolSize = 4;
inline constexpr std::size_t kHealthPoolSize = 8;
inline constexpr std::size_t kHazardInputPoolSize = 2;
inline constexpr std::size_t kHazardPoolSize = 3;
inline constexpr std::size_t kOrderQueueSize = 256;

// Everything the output thread consumes. Two producers (the frame group and the hazard group),
// each with its own order queue; one consumer.
struct OutputChannels {
  core::SlotPool<FrameRecord, kFramePoolSize> frames;
  core::SlotPool<ImuRecord, kImuPoolSize> imus;
  core::SlotPool<NavRecord, kNavPoolSize> navs;
  core::SlotPool<MapRecord, kMapPoolSize> maps;
  core::SlotPool<HealthRecord, kHealthPoolSize> healths;
  core::SlotPool<HazardInput, kHazardInputPoolSize> hazard_inputs;  // frame group -> hazard group
  core::SlotPool<HazardRecord, kHazardPoolSize> hazards;            // hazard group -> output thread
  core::SpscQueue<std::int32_t, kHazardInputPoolSize + 1> hazard_work;  // filled HazardInputs
  core::SpscQueue<RecordRef, kOrderQueueSize> frame_group;
  core::SpscQueue<RecordRef, kOrderQueueSize> hazard_group;

  // Sizes every pool; frame slots hold width*height bytes per image, hazard maps
  // hazard_cells^2 cells (0: no hazard mapping).
  core::Status Allocate(std::int32_t width, std::int32_t height, std::int32_t hazard_cells = 0) {
    if (frames.Allocate() != core::Status::kOk || imus.Allocate() != core::Status::kOk ||
        navs.Allocate() != core::Status::kOk || maps.Allocate() != core::Status::kOk ||
        healths.Allocate() != core::Status::kOk || hazard_inputs.Allocate() != core::Status::kOk ||
        hazards.Allocate() != core::Status::kOk) {
      return core::Status::kFull;
    }
    const std::int32_t bytes = width * height;
    for (std::size_t i = 0; i < kHazardInputPoolSize; ++i) {
      HazardInput& h = hazard_inputs[static_cast<std::int32_t>(i)];
      h.left.reset(new (std::nothrow) std::uint8_t[bytes]);
      h.right.reset(new (std::nothrow) std::uint8_t[bytes]);
      if (!h.left || !h.right) return core::Status::kFull;
      h.capacity_bytes = bytes;
    }
    const std::int32_t cells = hazard_cells * hazard_cells;
    for (std::size_t i = 0; i < kHazardPoolSize && cells > 0; ++i) {
      if (hazards[static_cast<std::int32_t>(i)].Allocate(cells) != core::Status::kOk) {
        return core::Status::kFull;
      }
    }
    for (std::size_t i = 0; i < kFramePoolSize; ++i) {
      FrameRecord& f = frames[static_cast<std::int32_t>(i)];
      f.left.reset(new (std::nothrow) std::uint8_t[bytes]);
      f.right.reset(new (std::nothrow) std::uint8_t[bytes]);
      if (!f.left || !f.right) return core::Status::kFull;
      f.capacity_bytes = bytes;
    }
    return core::Status::kOk;
  }
};

}  // namespace swf::app
