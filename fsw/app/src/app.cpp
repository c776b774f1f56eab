#include "swf/app/app.hpp"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <thread>

#include "swf/app/config.hpp"
#include "swf/app/evaluation.hpp"
#include "swf/app/flight_loop.hpp"
#include "swf/app/hazard_stage.hpp"
#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/app/realtime.hpp"
#include "swf/app/sim_world.hpp"
#if SWF_APP_HAVE_ARAVIS
#include <arv.h>

#include "swf/drivers/aravis_stereo_source.hpp"
#endif
#if SWF_APP_HAVE_V4L2
#include "swf/app/v4l2_source.hpp"
#endif
#include "swf/hazard_eval/hazard_eval.hpp"
#include "swf/image_io/image_io.hpp"
#include "swf/sim/rig.hpp"
#include "swf_msgs/nav_state_t.hpp"

namespace swf::app {

namespace {

FlightLoop* g_loop = nullptr;
void OnSignal(int /*sig*/) {
  if (g_loop != nullptr) g_loop->RequestStop();
}

int Usage(bool replay) {
  if (replay) {
    std::fprintf(stderr,
                 "usage: swf-replay --config FILE --log IN.lcmlog [--record OUT.lcmlog] "
                 "[--set 'key: value']... [--progress]\n");
  } else {
    std::fprintf(stderr, "usage: swf-fsw --config FILE [--set 'key: value']... [--progress]\n");
  }
  return 2;
}

// Progress on stderr: one line rewritten in place (a terminal) or every 10th frame (a file).
class Progress : public OutputObserver {
 public:
  Progress(std::int64_t total, bool enabled) : total_(total), enabled_(enabled) {}
  void OnNav(const NavRecord& r) override {
    if (!enabled_) return;
    ++navs_;
    const bool tty = isatty_;
    if (!tty && navs_ % 10 != 0 && navs_ != total_) return;
    std::fprintf(stderr, "%sswf-fsw: frame %lld/%lld  altitude %.1f m  landmarks in map %d%s",
                 tty ? "\r" : "", static_cast<long long>(r.nav.frame_seq + 1),
                 static_cast<long long>(total_), r.nav.position_world_m[2], landmarks_,
                 tty ? "   " : "\n");
  }
  void OnMap(const MapRecord& r) override { landmarks_ = r.map.num_landmarks; }
  void Finish() {
    if (enabled_ && isatty_) std::fprintf(stderr, "\n");
  }
  bool isatty_ = false;

 private:
  std::int64_t total_;
  bool enabled_;
  std::int64_t navs_ = 0;
  int landmarks_ = 0;
};

class HazardCounter : public OutputObserver {
 public:
  void OnHazard(const HazardRecord& r) override {
    ++maps;
    last_site_valid = r.safe_site_valid;
  }
  std::int64_t maps = 0;
  bool last_site_valid = false;
};

class LastHealth : public OutputObserver {
 public:
  void OnHealth(const HealthRecord& r) override { last = r; }
  HealthRecord last;
};

frontend::FrontendOptions FrontendFor(const FswConfig& c, int width, int height) {
  frontend::FrontendOptions o;
  o.harris.bucket_cols = std::max(1, std::min(64, width / 40));
  o.harris.bucket_rows = std::max(1, std::min(64, height / 40));
  o.max_tracks = static_cast<std::size_t>(c.max_tracks);
  o.stereo.max_disparity = std::min(c.max_disparity_px, width / 2);
  return o;
}

estimator::SwfOptions SwfFor(const FswConfig& c, std::int8_t* nav_mode) {
  estimator::SwfOptions o;
  o.window_size = c.window;
  o.max_iterations = c.max_iterations;
  using Nav = swf_msgs::nav_state_t;
  if (c.mode == "vo") {
    o.mode = estimator::SwfMode::kVisualOdometry;
    *nav_mode = Nav::MODE_VO;
  } else if (c.mode == "vsdf") {
    o.mode = estimator::SwfMode::kVsdf;
    *nav_mode = Nav::MODE_VSDF;
  } else {
    o.mode = estimator::SwfMode::kSlidingWindow;
    *nav_mode = c.mode == "ekf" ? Nav::MODE_EKF : Nav::MODE_SWF;
  }
  return o;
}

// The run's verdict, computed from the numbers (fsw/app/README.md "Results and exit codes"):
//   failed   (exit 1) the run could not do its job: the loop or the source failed, the log was
//            damaged, outputs were lost, the final estimate is INVALID, or (with truth) a VALID
//            output's true error exceeded its protection level
//   degraded (exit 3) it did, with reservations: an INVALID frame, a restart of the filter,
//            more than kMaxDegradedFraction of the frames DEGRADED, an output lost to a full
//            publisher queue, more than kMaxLostFraction of the frames dropped, refused by the
//            source or failed in a stage, or (a replayed log) any frame missing from the log or
//            refused as duplicated or out of order: a log is a record, and a record with a hole
//            or a swapped frame does not replay the run it recorded
//   ok       (exit 0) none of those
struct Verdict {
  const char* result = "ok";
  int exit_code = 0;
  std::string reasons;  // comma-separated, for the summary and the log
};
constexpr double kMaxLostFraction = 0.01;
constexpr double kMaxDegradedFraction = 0.10;

void Fail(Verdict* v, const std::string& reason) {
  v->result = "failed";
  v->exit_code = 1;
  v->reasons += (v->reasons.empty() ? "" : ", ") + reason;
}
void Degrade(Verdict* v, const std::string& reason) {
  if (v->exit_code == 0) {
    v->result = "degraded";
    v->exit_code = 3;
  }
  v->reasons += (v->reasons.empty() ? "" : ", ") + reason;
}

Verdict JudgeRun(const LoopCounters& counters, const HealthRecord& health,
                 const IntegrityCounters& integrity, estimator::NavIntegrity final_status,
                 const EvaluationResult* eval, const LogStreamStats* log) {
  Verdict v;
  const double frames = static_cast<double>(std::max<std::int64_t>(1, counters.frames));
  if (counters.frames == 0) Fail(&v, "no frame was processed");
  if (counters.frames > 0 && final_status == estimator::NavIntegrity::kInvalid)
    Fail(&v, "the final estimate is INVALID");
  if (eval != nullptr && eval->protection_violations > 0) {
    Fail(&v, std::to_string(eval->protection_violations) +
                 " VALID outputs erred beyond their protection level");
  }
  if (integrity.frames_invalid > 0)
    Degrade(&v, std::to_string(integrity.frames_invalid) + " INVALID frames");
  if (integrity.restarts > 0) Degrade(&v, std::to_string(integrity.restarts) + " filter restarts");
  if (integrity.frames_degraded > kMaxDegradedFraction * frames)
    Degrade(&v, std::to_string(integrity.frames_degraded) + " DEGRADED frames");
  if (health.outputs_dropped > 0)
    Degrade(&v, std::to_string(health.outputs_dropped) + " outputs dropped (publisher queue full)");
  const std::int64_t lost = health.frames_dropped + health.frames_rejected + counters.stage_errors;
  if (lost > kMaxLostFraction * frames)
    Degrade(&v, std::to_string(lost) + " frames dropped, refused or failed");
  if (log != nullptr && log->frames_missing > 0)
    Degrade(&v, "log: " + std::to_string(log->frames_missing) + " frames missing (sequence gaps)");
  if (log != nullptr && log->duplicates > 0)
    Degrade(&v, "log: " + std::to_string(log->duplicates) + " duplicated frames refused");
  if (log != nullptr && log->out_of_order > 0)
    Degrade(&v, "log: " + std::to_string(log->out_of_order) + " out-of-order frames refused");
  return v;
}

void WriteIntegrity(std::FILE* f, const IntegrityCounters& c, const EvaluationResult* eval) {
  std::fprintf(f,
               "  \"integrity\": {\"frames_valid\": %lld, \"frames_degraded\": %lld, "
               "\"frames_invalid\": %lld, \"restarts\": %lld, \"last_recovery_frames\": %d, "
               "\"measurements_gated\": %lld, \"measurements_rejected\": %lld, "
               "\"landmarks_rejected\": %lld, \"new_landmarks_refused\": %lld, "
               "\"gate_suspensions\": %lld, \"motion_refused\": %lld, \"motion_overruled\": %lld, "
               "\"frames_coasted\": %lld, \"frames_blind\": %lld, \"longest_outage_frames\": %d",
               static_cast<long long>(c.frames_valid), static_cast<long long>(c.frames_degraded),
               static_cast<long long>(c.frames_invalid), static_cast<long long>(c.restarts),
               c.last_recovery_frames, static_cast<long long>(c.measurements_gated),
               static_cast<long long>(c.measurements_rejected),
               static_cast<long long>(c.landmarks_rejected),
               static_cast<long long>(c.new_landmarks_refused),
               static_cast<long long>(c.gate_suspensions), static_cast<long long>(c.motion_refused),
               static_cast<long long>(c.motion_overruled), static_cast<long long>(c.frames_coasted),
               static_cast<long long>(c.frames_blind), c.longest_outage_frames);
  std::fprintf(f, ", \"flag_counts\": [");
  for (int b = 0; b < estimator::kNumIntegrityFlags; ++b)
    std::fprintf(f, "%s%lld", b > 0 ? ", " : "", static_cast<long long>(c.flag_counts[b]));
  std::fprintf(f, "]");
  if (eval != nullptr) {
    std::fprintf(f,
                 ", \"valid_outputs_vs_truth\": %lld, \"protection_violations\": %lld, "
                 "\"max_error_over_protection\": %.4f",
                 static_cast<long long>(eval->valid_navs),
                 static_cast<long long>(eval->protection_violations),
                 eval->max_error_over_protection);
  }
  std::fprintf(f, "},\n");
}

// A JSON number, or null when not finite (JSON has no inf/nan).
std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

// The IMU of a stereo-inertial run: its stream's counts and, in the simulator, the biases the
// filter ended with against the unit's true ones.
struct ImuReport {
  ImuCounts counts;
  bool has_biases = false;
  estimator::ImuBiases<double> estimated;
  bool has_truth = false;
  estimator::ImuBiases<double> truth;
  double imu_only_pose_rms_m = NAN;  // the unit alone from the same start (simulator)
  bool has_lcm = false;              // the IMU came over LCM: what the subscription lost
  LcmImuCounters lcm;
};

void WriteImu(std::FILE* f, const FswConfig& c, const ImuReport& r) {
  const estimator::ImuStreamCounts& s = r.counts.stream;
  std::fprintf(f,
               "  \"imu\": {\"unit\": \"%s\", \"accepted\": %lld, \"out_of_order\": %lld, "
               "\"duplicated\": %lld, \"invalid\": %lld, \"saturated\": %lld, "
               "\"missing\": %lld, \"overflowed\": %lld, \"intervals_bridged\": %lld, "
               "\"static_start\": %d, \"static_tilt_correction_rad\": %s",
               c.sim.imu_unit != "none" ? c.sim.imu_unit.c_str() : "external",
               static_cast<long long>(s.accepted), static_cast<long long>(s.out_of_order),
               static_cast<long long>(s.duplicated), static_cast<long long>(s.invalid),
               static_cast<long long>(s.saturated), static_cast<long long>(s.missing_samples),
               static_cast<long long>(r.counts.overflowed),
               static_cast<long long>(r.counts.intervals_bridged), r.counts.static_start,
               JsonNumber(r.counts.static_tilt_correction_rad).c_str());
  const auto vec = [&](const char* key, const estimator::Vec3<double>& v) {
    std::fprintf(f, ", \"%s\": [%s, %s, %s]", key, JsonNumber(v.x()).c_str(),
                 JsonNumber(v.y()).c_str(), JsonNumber(v.z()).c_str());
  };
  if (r.has_biases) {
    vec("gyro_bias_radps", r.estimated.gyro_radps);
    vec("accel_bias_mps2", r.estimated.accel_mps2);
  }
  if (r.has_biases && r.has_truth) {
    vec("true_gyro_bias_radps", r.truth.gyro_radps);
    vec("true_accel_bias_mps2", r.truth.accel_mps2);
    std::fprintf(f, ", \"gyro_bias_error_radps\": %s, \"accel_bias_error_mps2\": %s",
                 JsonNumber((r.estimated.gyro_radps - r.truth.gyro_radps).norm()).c_str(),
                 JsonNumber((r.estimated.accel_mps2 - r.truth.accel_mps2).norm()).c_str());
  }
  if (r.has_truth) {
    std::fprintf(f, ", \"imu_only_pose_rms_error_m\": %s",
                 JsonNumber(r.imu_only_pose_rms_m).c_str());
  }
  if (r.has_lcm) {
    std::fprintf(f,
                 ", \"lcm\": {\"received\": %lld, \"undecodable\": %lld, \"queue_full\": %lld, "
                 "\"future_dropped\": %lld}",
                 static_cast<long long>(r.lcm.received), static_cast<long long>(r.lcm.undecodable),
                 static_cast<long long>(r.lcm.queue_full),
                 static_cast<long long>(r.lcm.future_dropped));
  }
  std::fprintf(f, "},\n");
}

void WriteSummary(const std::string& path, const FswConfig& c, const LoopCounters& counters,
                  const HealthRecord& health, const EvaluationResult* eval,
                  const HazardEvaluation* hazard, std::int64_t hazard_maps, bool locked, bool fifo,
                  const Verdict& verdict, const IntegrityCounters& integrity,
                  const sim::Trajectory* trajectory, const sim::OrbitalTarget* target,
                  const LogStreamStats* log, const ImuReport* imu) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    std::fprintf(stderr, "swf-fsw: cannot write %s\n", path.c_str());
    return;
  }
  std::fprintf(f, "{\n  \"result\": \"%s\",\n  \"result_reasons\": \"%s\",\n", verdict.result,
               verdict.reasons.c_str());
  std::fprintf(f, "  \"source\": \"%s\",\n", SourceName(c.source));
  std::fprintf(f, "  \"frames\": %lld,\n", static_cast<long long>(counters.frames));
  std::fprintf(f, "  \"rate_hz\": %.3f,\n  \"window\": %d,\n  \"mode\": \"%s\",\n", c.rate_hz,
               c.window, c.mode.c_str());
  if (c.source == SourceKind::kSim) {
    std::fprintf(f, "  \"image_width_px\": %d,\n  \"image_height_px\": %d,\n", c.sim.width_px,
                 c.sim.height_px);
    std::fprintf(f, "  \"terrain\": \"%s\",\n  \"seed\": %llu,\n", c.sim.terrain.c_str(),
                 static_cast<unsigned long long>(c.sim.seed));
  }
  // Where the simulated descent went: the nadir of the first frame, and for `sim.target:
  // orbital` the pre-selection's clearance from orbit-visible hazards.
  if (imu != nullptr) WriteImu(f, c, *imu);
  if (trajectory != nullptr && trajectory->NumFrames() > 0) {
    const Eigen::Vector3d& p = trajectory->WorldTCamera(0).t;
    std::fprintf(f, "  \"descent_target\": {\"mode\": \"%s\", \"x_m\": %.3f, \"y_m\": %.3f",
                 c.sim.target.c_str(), p.x(), p.y());
    if (target != nullptr && c.sim.target == "orbital") {
      std::fprintf(f,
                   ", \"search_radius_m\": %.1f, \"orbital_clearance_m\": %.3f, "
                   "\"distance_from_nominal_m\": %.3f",
                   c.sim.target_search_m, target->clearance_m, target->distance_m);
    }
    std::fprintf(f, "},\n");
  }
  if (eval != nullptr) {
    // Landmark errors come from the published landmark maps; with none evaluated they are null,
    // not a perfect 0.
    if (eval->landmarks_evaluated > 0) {
      std::fprintf(f, "  \"landmark_rms_error_m\": %.6f,\n  \"landmark_median_error_m\": %.6f,\n",
                   eval->landmark_rms_error_m, eval->landmark_median_error_m);
    } else {
      std::fprintf(f, "  \"landmark_rms_error_m\": null,\n  \"landmark_median_error_m\": null,\n");
    }
    std::fprintf(f,
                 "  \"landmarks_evaluated\": %lld,\n  \"pose_rms_error_m\": %.6f,\n"
                 "  \"final_pose_error_m\": %.6f,\n  \"nav_outputs\": %lld,\n"
                 "  \"landmark_maps\": %lld,\n",
                 static_cast<long long>(eval->landmarks_evaluated), eval->pose_rms_error_m,
                 eval->final_pose_error_m, static_cast<long long>(eval->navs),
                 static_cast<long long>(eval->maps));
    std::fprintf(f, "  \"mean_position_nees\": %s,\n  \"position_nees\": [",
                 JsonNumber(eval->mean_position_nees).c_str());
    for (std::size_t k = 0; k < eval->position_nees.size(); ++k)
      std::fprintf(f, "%s%s", k > 0 ? ", " : "", JsonNumber(eval->position_nees[k]).c_str());
    std::fprintf(f, "],\n");
  }
  WriteIntegrity(f, integrity, eval);
  std::fprintf(f, "  \"stages\": {\n");
  for (int i = 0; i < kNumStages; ++i) {
    std::fprintf(f, "    \"%s\": {\"p50_ms\": %.3f, \"p99_ms\": %.3f, \"max_ms\": %.3f}%s\n",
                 StageName(i), health.stages[i].p50_ms, health.stages[i].p99_ms,
                 health.stages[i].max_ms, i + 1 < kNumStages ? "," : "");
  }
  std::fprintf(f, "  },\n");
  std::fprintf(
      f,
      "  \"overruns\": %lld,\n  \"allocations_after_start\": %lld,\n"
      "  \"outputs_dropped\": %lld,\n  \"frames_dropped\": %lld,\n"
      "  \"frames_rejected\": %lld,\n"
      "  \"stage_errors\": %lld,\n  \"fault_bits\": %d,\n  \"num_landmarks\": %d,\n"
      "  \"mlockall\": %s,\n  \"sched_fifo\": %s,\n",
      static_cast<long long>(counters.overruns),
      static_cast<long long>(health.allocations_after_start),
      static_cast<long long>(health.outputs_dropped), static_cast<long long>(health.frames_dropped),
      static_cast<long long>(health.frames_rejected), static_cast<long long>(counters.stage_errors),
      health.fault_bits, health.num_landmarks, locked ? "true" : "false", fifo ? "true" : "false");
  if (log != nullptr) {
    std::fprintf(f,
                 "  \"log\": {\"frames_missing\": %lld, \"duplicates_refused\": %lld, "
                 "\"out_of_order_refused\": %lld},\n",
                 static_cast<long long>(log->frames_missing),
                 static_cast<long long>(log->duplicates),
                 static_cast<long long>(log->out_of_order));
  }
  if (hazard == nullptr) {
    std::fprintf(f, "  \"hazard_maps\": %lld,\n  \"hazard\": null,\n  \"safe_site\": null\n}\n",
                 static_cast<long long>(hazard_maps));
  } else {
    const HazardEvaluation& h = *hazard;
    std::fprintf(f, "  \"hazard_maps\": %lld,\n", static_cast<long long>(hazard_maps));
    std::fprintf(f,
                 "  \"hazard\": {\"known_cells\": %d, \"rocks_resolved\": %d, "
                 "\"rocks_detected\": %d, ",
                 h.known_cells, h.rocks_resolved, h.rocks_detected);
    if (h.detection_probability >= 0.0) {
      std::fprintf(f, "\"detection_probability\": %.4f, ", h.detection_probability);
    } else {
      std::fprintf(f, "\"detection_probability\": null, ");
    }
    std::fprintf(f,
                 "\"rock_free_cells\": %d, \"false_rock_cells\": %d, "
                 "\"false_alarm_rate\": %.5f},\n",
                 h.rock_free_cells, h.false_rock_cells, h.false_alarm_rate);
    if (h.site_valid) {
      std::fprintf(f,
                   "  \"safe_site\": {\"x_m\": %.3f, \"y_m\": %.3f, \"score\": %.4f, "
                   "\"clearance_to_truth_hazard_m\": %.3f, \"on_truth_hazard\": %s}\n}\n",
                   h.site_x_m, h.site_y_m, h.site_score, h.site_clearance_m,
                   h.site_on_hazard ? "true" : "false");
    } else {
      std::fprintf(f, "  \"safe_site\": null\n}\n");
    }
  }
  std::fclose(f);
}

void PrintRenderProgress(int done, int total) {
  std::fprintf(stderr, "\rswf-fsw: rendering the descent %d/%d", done, total);
  if (done == total) std::fprintf(stderr, "\n");
}

}  // namespace

void ApplyEstimatorConfig(const FswConfig& config, PipelineOptions* po, std::int8_t* nav_mode) {
  po->frontend = FrontendFor(config, po->width_px, po->height_px);
  po->swf = SwfFor(config, nav_mode);
  po->measurement_sigma_px = config.measurement_sigma_px;
  po->min_quality = static_cast<float>(config.min_quality);
  po->process_sigma_m = config.process_sigma_m;
  po->process_sigma_rad = config.process_sigma_rad;
}

int RunFlightProcess(int argc, char** argv, bool replay) {
  const char* tool = replay ? "swf-replay" : "swf-fsw";
  std::string config_path;
  std::string log_path;
  std::string record_override;
  bool record_given = false;
  bool progress = false;
  std::vector<std::string> sets;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    const bool has_value = a + 1 < argc;
    if (arg == "--config" && has_value) {
      config_path = argv[++a];
    } else if (arg == "--set" && has_value) {
      sets.emplace_back(argv[++a]);
    } else if (replay && arg == "--log" && has_value) {
      log_path = argv[++a];
    } else if (replay && arg == "--record" && has_value) {
      record_override = argv[++a];
      record_given = true;
    } else if (arg == "--progress") {
      progress = true;
    } else {
      return Usage(replay);
    }
  }
  if (config_path.empty() || (replay && log_path.empty())) return Usage(replay);

  // ---- configuration: refused before anything starts ------------------------------------------
  FswConfig config;
  std::string error;
  const auto refuse = [&]() {
    std::fprintf(stderr, "%s: configuration refused: %s\n", tool, error.c_str());
    return 2;
  };
  // The file and every --set are validated once, as a whole, so their order does not matter.
  if (!LoadConfig(config_path, sets, &config, &error)) return refuse();
  if (replay) {
    config.source = SourceKind::kLog;
    config.log_path = log_path;
    config.record_frames = false;
    const auto record = config.origins.keys.find("record.path");
    if (record_given) {
      config.record_path = record_override;
    } else if (record == config.origins.keys.end() || record->second != "--set") {
      config.record_path = "";
    }
    if (!ValidateConfig(config, config_path, &error)) return refuse();
  }
  // Output paths are checked now, not discovered unwritable after the whole descent.
  if (!CheckOutputPaths(config, &error)) return refuse();

  // ---- source and pipeline options --------------------------------------------------------------
  PipelineOptions po;
  std::unique_ptr<SimWorld> world;
  std::unique_ptr<drivers::StereoSource> source;
  LogStereoSource* log_source = nullptr;
  drivers::StereoSource* aravis_source = nullptr;
  std::string aravis_left_id;
  std::string aravis_right_id;
  (void)aravis_source;  // used only when built with Aravis
  drivers::StereoSource* v4l2_source = nullptr;
  (void)v4l2_source;  // used only when built with V4L2
#if SWF_APP_HAVE_ARAVIS
  struct FakeCameras {
    std::vector<ArvGvFakeCamera*> cameras;
    void push_back(ArvGvFakeCamera* c) { cameras.push_back(c); }
    ~FakeCameras() {
      for (ArvGvFakeCamera* c : cameras) g_object_unref(c);
    }
  } fake_cameras;
#endif
  std::int64_t total_frames = 0;
  if (config.initial == "truth" &&
      (config.source != SourceKind::kSim || config.sim.target != "orbital")) {
    // (The simulator's orbital target needs the terrain: taken from the world once built.)
    sim::Trajectory trajectory;
    sim::RigOptions rig;
    if (!SimTrajectory(config, &trajectory, &rig, &error)) {
      std::fprintf(stderr, "%s: configuration refused: %s\n", tool, error.c_str());
      return 2;
    }
    po.initial_world_T_camera = trajectory.WorldTCamera(0);
    po.imu = ImuOptionsFor(config, &trajectory);
  } else if (config.initial != "truth") {
    po.initial_world_T_camera.R = sim::NadirRotation(0.0);
    po.initial_world_T_camera.t = Eigen::Vector3d(
        config.initial_position_m[0], config.initial_position_m[1], config.initial_position_m[2]);
    po.imu = ImuOptionsFor(config, nullptr);
  }
  const std::string imu_channel =
      config.imu.channel.empty() ? config.channel_prefix + kImuSuffix : config.imu.channel;
  // Raw frames (aravis, v4l2, an unrectified log): the calibrations give the image size and the
  // pipeline rectifies. Loaded here, once.
  auto use_camera_calibrations = [&]() {
    if (config.camera.left_calibration.empty() || config.camera.right_calibration.empty() ||
        !image_io::LoadCalibration(config.camera.left_calibration, &po.left_calibration, &error) ||
        !image_io::LoadCalibration(config.camera.right_calibration, &po.right_calibration,
                                   &error)) {
      std::fprintf(stderr, "%s: configuration refused: camera calibration: %s\n", tool,
                   error.empty() ? "both calibration files are required" : error.c_str());
      return false;
    }
    po.rectify = true;
    po.width_px = po.left_calibration.width;
    po.height_px = po.left_calibration.height;
    return true;
  };
  switch (config.source) {
    case SourceKind::kSim: {
      world = std::make_unique<SimWorld>();
      std::fprintf(stderr, "%s: building the simulated world (terrain %s, %dx%d px) ...\n", tool,
                   config.sim.terrain.c_str(), config.sim.width_px, config.sim.height_px);
      if (!world->Build(config, &error) ||
          !world->RenderAll(config.sim.render_threads, progress ? PrintRenderProgress : nullptr,
                            &error)) {
        std::fprintf(stderr, "%s: %s\n", tool, error.c_str());
        return 1;
      }
      if (config.initial == "truth") {
        po.initial_world_T_camera = world->Trajectory().WorldTCamera(0);
        po.imu = ImuOptionsFor(config, &world->Trajectory());
      }
      if (config.sim.target == "orbital") {
        const sim::OrbitalTarget& t = world->Target();
        std::fprintf(stderr,
                     "%s: orbital target (%.1f, %.1f) m, %.1f m from the nominal, orbital "
                     "clearance %.1f m\n",
                     tool, t.target_m.x(), t.target_m.y(), t.distance_m, t.clearance_m);
      }
      po.camera = world->Camera();
      po.width_px = world->Width();
      po.height_px = world->Height();
      total_frames = world->NumFrames();
      source = std::make_unique<PrerenderedSimSource>(world.get());
      break;
    }
    case SourceKind::kLog: {
      auto log = std::make_unique<LogStereoSource>();
      if (config.imu.enabled) log->SetImuChannel(imu_channel);
      if (!log->Load(config.log_path, config.channel_prefix + kStereoSuffix, &error)) {
        std::fprintf(stderr, "%s: %s\n", tool, error.c_str());
        return 1;
      }
      if (log->NumFrames() == 0 && !log->LoadError().empty()) {
        std::fprintf(stderr, "%s: %s (no frame before it)\n", tool, log->LoadError().c_str());
        return 1;
      }
      if (log->NumFrames() == 0) {
        std::fprintf(stderr, "%s: %s: no %s%s records\n", tool, config.log_path.c_str(),
                     config.channel_prefix.c_str(), kStereoSuffix);
        return 1;
      }
      po.width_px = log->Width();
      po.height_px = log->Height();
      if (log->Rectified()) {
        sim::RigOptions rig = SimRig(config);
        rig.width_px = log->Width();
        rig.height_px = log->Height();
        po.camera = sim::MakeStereoCamera(rig);
      } else {
        if (!use_camera_calibrations()) return 2;
        if (po.width_px != log->Width() || po.height_px != log->Height()) {
          std::fprintf(stderr,
                       "%s: configuration refused: camera.left_calibration: %s is for %dx%d px, "
                       "the log's frames are %dx%d px\n",
                       tool, config.camera.left_calibration.c_str(), po.width_px, po.height_px,
                       log->Width(), log->Height());
          return 2;
        }
      }
      total_frames = static_cast<std::int64_t>(log->NumFrames());
      log_source = log.get();
      source = std::move(log);
      break;
    }
    case SourceKind::kAravis: {
#if SWF_APP_HAVE_ARAVIS
      if (!use_camera_calibrations()) return 2;
      // The source keeps the id pointers: the strings live as long as this function.
      aravis_left_id = config.camera.left.empty() ? "127.0.0.1" : config.camera.left;
      aravis_right_id = config.camera.right.empty() ? "127.0.0.2" : config.camera.right;
      const std::string& left_id = aravis_left_id;
      const std::string& right_id = aravis_right_id;
      if (config.camera.fake) {
        // Aravis's GigE Vision fake cameras served by this process (tests, no hardware).
        for (const std::string& address : {left_id, right_id}) {
          ArvGvFakeCamera* fake = arv_gv_fake_camera_new(address.c_str(), nullptr);
          if (fake == nullptr || !arv_gv_fake_camera_is_running(fake)) {
            std::fprintf(stderr, "%s: cannot serve a fake GigE camera on %s\n", tool,
                         address.c_str());
            return 1;
          }
          fake_cameras.push_back(fake);
        }
      }
      auto aravis = std::make_unique<drivers::AravisStereoSource>();
      drivers::AravisStereoOptions ao;
      ao.left_id = left_id.c_str();
      ao.right_id = right_id.c_str();
      ao.width = po.left_calibration.width;
      ao.height = po.left_calibration.height;
      ao.trigger =
          config.camera.fake ? drivers::TriggerMode::kSoftware : drivers::TriggerMode::kFreeRun;
      ao.frame_rate_hz = config.camera.fake ? 0.0 : config.rate_hz;
      if (const core::Status s = aravis->Configure(ao); s != core::Status::kOk) {
        std::fprintf(stderr, "%s: the aravis source refused its options (%s): %s\n", tool,
                     core::ToString(s), aravis->LastError());
        return 2;
      }
      total_frames = config.max_frames;
      aravis_source = aravis.get();
      source = std::move(aravis);
      break;
#else
      std::fprintf(stderr,
                   "%s: configuration refused: source: aravis: this build has no Aravis "
                   "(SWF_WITH_ARAVIS=OFF)\n",
                   tool);
      return 2;
#endif
    }
    case SourceKind::kV4l2: {
#if SWF_APP_HAVE_V4L2
      if (!use_camera_calibrations()) return 2;
      // The device paths stay in `config`, which outlives the source.
      std::unique_ptr<drivers::V4l2StereoSource> v4l2 =
          MakeV4l2Source(config, po.left_calibration.width, po.left_calibration.height,
                         drivers::LinuxV4l2Kernel(), &error);
      if (v4l2 == nullptr) {
        std::fprintf(stderr, "%s: configuration refused: %s\n", tool, error.c_str());
        return 2;
      }
      total_frames = config.max_frames;
      v4l2_source = v4l2.get();
      source = std::move(v4l2);
      break;
#else
      std::fprintf(stderr,
                   "%s: configuration refused: source: v4l2: this build has no V4L2 "
                   "(SWF_WITH_V4L2=OFF)\n",
                   tool);
      return 2;
#endif
    }
  }
  std::int8_t nav_mode = 0;
  ApplyEstimatorConfig(config, &po, &nav_mode);

  // ---- preallocation ----------------------------------------------------------------------------
  auto pipeline = std::make_unique<Pipeline>();
  if (const core::Status s = pipeline->Configure(po); s != core::Status::kOk) {
    std::fprintf(stderr,
                 "%s: configuration refused: the pipeline rejected it (%s): check window, "
                 "max_tracks, max_disparity_px and the rig\n",
                 tool, core::ToString(s));
    return 2;
  }
  if (!CheckEnvelopeDisparity(config, pipeline->Camera().fx, pipeline->Camera().baseline_m,
                              po.width_px, &error)) {
    return refuse();
  }
  // Hazard mapping on the rectified pair (all of its memory now).
  auto hazard_stage = std::make_unique<MapperHazardStage>();
  {
    hazard::HazardMapperOptions ho;
    ho.camera = pipeline->Camera();
    ho.image_width = po.width_px;
    ho.image_height = po.height_px;
    ho.max_disparities = config.hazard_max_disparities;
    ho.downsample = config.hazard_downsample;
    if (const core::Status s = hazard_stage->Configure(ho); s != core::Status::kOk) {
      std::fprintf(stderr,
                   "%s: configuration refused: hazard.max_disparities / hazard.downsample: the "
                   "hazard mapper rejected them for %dx%d images (%s)\n",
                   tool, po.width_px, po.height_px, core::ToString(s));
      return 2;
    }
  }
  auto channels = std::make_unique<OutputChannels>();
  if (channels->Allocate(po.width_px, po.height_px, hazard_stage->GridCells()) !=
      core::Status::kOk) {
    std::fprintf(stderr, "%s: out of memory for the output pools\n", tool);
    return 1;
  }
  OutputOptions oo;
  oo.lcm_url = config.publish ? config.lcm_url : "";
  oo.channel_prefix = config.channel_prefix;
  oo.record_path = config.record_path;
  oo.max_width = po.width_px;
  oo.max_height = po.height_px;
  oo.max_hazard_cells = hazard_stage->GridCells();
  OutputThread output;
  if (!output.Open(oo, channels.get(), &error)) {
    std::fprintf(stderr, "%s: %s\n", tool, error.c_str());
    return 1;
  }
  Evaluation evaluation;
  const bool evaluate = config.source == SourceKind::kSim && world != nullptr;
  if (evaluate) output.AddObserver(&evaluation);
  Progress progress_display(
      config.max_frames > 0 ? std::min(config.max_frames, total_frames) : total_frames, progress);
  progress_display.isatty_ = isatty(2) != 0;
  output.AddObserver(&progress_display);
  LastHealth last_health;
  output.AddObserver(&last_health);
  HazardCounter hazard_counter;
  output.AddObserver(&hazard_counter);

  LoopOptions lo;
  lo.rate_hz = config.rate_hz;
  lo.pacing = replay && config.pacing == Pacing::kRealtime ? Pacing::kLockstep : config.pacing;
  lo.hazard_every = config.hazard_every;
  lo.health_every = config.health_every;
  lo.record_frames = config.record_frames && !config.record_path.empty();
  lo.max_frames = config.max_frames;
  lo.nav_mode = nav_mode;
  lo.hazard_priority = config.priority > 1 ? config.priority - 1 : 0;
  lo.inject_stage = config.inject_stage.empty() ? -1 : StageIndex(config.inject_stage);
  lo.inject_first_frame = config.inject_frame;
  lo.inject_frames = config.inject_frames;
  lo.inject_ms = config.inject_ms;
  FlightLoop loop;
  MotionProvider* motion = world != nullptr ? static_cast<MotionProvider*>(world.get())
                                            : static_cast<MotionProvider*>(log_source);
  // The IMU: the simulator's unit, the log's recording, or (cameras) imu_t over LCM.
  ImuProvider* imu = nullptr;
  LcmImuInput lcm_imu;
  if (config.imu.enabled) {
    if (world != nullptr) {
      imu = world.get();
    } else if (log_source != nullptr) {
      imu = log_source;
      if (log_source->NumImuSamples() == 0) {
        std::fprintf(stderr, "%s: %s: imu.enabled but no %s records in the log\n", tool,
                     config.log_path.c_str(), imu_channel.c_str());
        return 1;
      }
    } else if (!lcm_imu.Start(config.lcm_url, imu_channel, &error)) {
      std::fprintf(stderr, "%s: %s\n", tool, error.c_str());
      return 1;
    } else {
      imu = &lcm_imu;
    }
  }
  if (loop.Configure(lo, pipeline.get(), source.get(), channels.get(), motion, hazard_stage.get(),
                     imu) != core::Status::kOk) {
    std::fprintf(stderr,
                 "%s: configuration refused: rate groups (rate_hz, hazard_every, "
                 "health_every)\n",
                 tool);
    return 2;
  }
  if (source->Start() != core::Status::kOk) {
#if SWF_APP_HAVE_ARAVIS
    if (aravis_source != nullptr) {
      std::fprintf(stderr, "%s: the aravis source did not start: %s\n", tool,
                   static_cast<drivers::AravisStereoSource*>(aravis_source)->LastError());
      return 1;
    }
#endif
#if SWF_APP_HAVE_V4L2
    if (v4l2_source != nullptr) {
      std::fprintf(stderr, "%s: the v4l2 source did not start: %s\n", tool,
                   static_cast<drivers::V4l2StereoSource*>(v4l2_source)->LastError());
      return 1;
    }
#endif
    std::fprintf(stderr, "%s: the %s source did not start\n", tool, source->Name());
    return 1;
  }

  // ---- real time ----------------------------------------------------------------------------
  char message[200];
  bool locked = false;
  if (config.mlockall) {
    locked = LockMemory(message, sizeof message);
    std::fprintf(stderr, "%s: %s\n", tool, message);
  }
  output.Start();
  g_loop = &loop;
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  core::Status run_status = core::Status::kOk;
  bool fifo = false;
  std::thread rt([&] {
    char m[200];
    fifo = MakeThreadRealtime(config.priority, m, sizeof m);
    std::fprintf(stderr, "%s: frame group: %s\n", tool, m);
    if (config.cpu >= 0) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(config.cpu, &set);
      if (pthread_setaffinity_np(pthread_self(), sizeof set, &set) != 0) {
        std::fprintf(stderr, "%s: pinning to CPU %d refused: continuing unpinned\n", tool,
                     config.cpu);
      }
    }
#if SWF_APP_HAVE_ARAVIS
    // GLib gives a thread it did not create its GThread record on first use (one allocation
    // inside the first Aravis call of the frame group): take it here, before counting starts.
    if (aravis_source != nullptr) (void)g_thread_self();
#endif
    run_status = loop.Run();
  });
  rt.join();
  g_loop = nullptr;
  source->Stop();
  output.StopAndDrain();
  progress_display.Finish();

  // ---- report ---------------------------------------------------------------------------------
  const LoopCounters& counters = loop.Counters();
  const bool damaged_log = log_source != nullptr && !log_source->LoadError().empty();
  if (damaged_log) {
    std::fprintf(stderr,
                 "%s: stopped at a damaged log: %s (the %zu frames before it were "
                 "replayed)\n",
                 tool, log_source->LoadError().c_str(), log_source->NumFrames());
  }
#if SWF_APP_HAVE_V4L2
  if (v4l2_source != nullptr && run_status != core::Status::kOk) {
    std::fprintf(stderr, "%s: the v4l2 source failed: %s\n", tool,
                 static_cast<drivers::V4l2StereoSource*>(v4l2_source)->LastError());
  }
#endif
  EvaluationResult eval;
  if (evaluate) {
    eval = evaluation.Evaluate(*pipeline, world->Trajectory(), world->Terrain(), config.plot_dir);
  }
  HazardEvaluation hazard_eval;
  if (evaluate) {
    hazard_eval = EvaluateHazard(hazard_stage->Mapper(), world->Terrain(), hazard_counter.maps);
  }
  if (!config.plot_dir.empty() && hazard_counter.maps > 0) {
    const std::string png = config.plot_dir + "/hazard.png";
    if (hazard_eval::WriteHazardMapPng(hazard_stage->Mapper(), png) != core::Status::kOk) {
      std::fprintf(stderr, "%s: cannot write %s\n", tool, png.c_str());
    }
  }
  const HealthRecord& h = last_health.last;
  std::fprintf(stderr,
               "%s: %lld frames, %lld overruns, %lld outputs dropped, %lld allocations after "
               "start, cycle p50 %.1f ms p99 %.1f ms max %.1f ms",
               tool, static_cast<long long>(counters.frames),
               static_cast<long long>(counters.overruns), static_cast<long long>(h.outputs_dropped),
               static_cast<long long>(h.allocations_after_start), h.stages[kStageCycle].p50_ms,
               h.stages[kStageCycle].p99_ms, h.stages[kStageCycle].max_ms);
  if (evaluate) {
    if (eval.landmarks_evaluated > 0) {
      std::fprintf(stderr, ", landmark RMS error %.3f m", eval.landmark_rms_error_m);
    } else {
      std::fprintf(stderr, ", no landmark map to evaluate");
    }
    std::fprintf(stderr, ", pose RMS error %.3f m", eval.pose_rms_error_m);
  }
  std::fprintf(stderr, ", %lld hazard maps (%lld skipped, %lld failed), hazard p50 %.1f ms",
               static_cast<long long>(hazard_counter.maps),
               static_cast<long long>(counters.hazard_skipped),
               static_cast<long long>(loop.HazardErrors()), h.stages[kStageHazard].p50_ms);
  std::fprintf(stderr, "\n");
  const IntegrityCounters& integrity = pipeline->Integrity();
  const LogStreamStats* log_stream = log_source != nullptr ? &log_source->StreamStats() : nullptr;
  if (log_stream != nullptr && (log_stream->frames_missing > 0 || log_stream->Refused() > 0)) {
    std::fprintf(stderr,
                 "%s: log: %lld frames missing (sequence gaps), %lld duplicated and %lld "
                 "out-of-order frames refused\n",
                 tool, static_cast<long long>(log_stream->frames_missing),
                 static_cast<long long>(log_stream->duplicates),
                 static_cast<long long>(log_stream->out_of_order));
  }
  Verdict verdict = JudgeRun(counters, h, integrity, pipeline->LastIntegrity().status,
                             evaluate ? &eval : nullptr, log_stream);
  if (run_status != core::Status::kOk)
    Fail(&verdict, std::string("the frame group stopped: ") + core::ToString(run_status));
  if (damaged_log) Fail(&verdict, "damaged log");
  if (output.Counters().record_errors > 0 || output.Counters().encode_errors > 0) {
    std::fprintf(stderr, "%s: %lld records could not be written, %lld not encoded\n", tool,
                 static_cast<long long>(output.Counters().record_errors),
                 static_cast<long long>(output.Counters().encode_errors));
    Fail(&verdict, "records lost");
  }
  std::fprintf(stderr,
               "%s: integrity: %lld VALID, %lld DEGRADED, %lld INVALID frames, %lld restarts, "
               "%lld measurements gated, %lld rejected, %lld landmarks rejected\n",
               tool, static_cast<long long>(integrity.frames_valid),
               static_cast<long long>(integrity.frames_degraded),
               static_cast<long long>(integrity.frames_invalid),
               static_cast<long long>(integrity.restarts),
               static_cast<long long>(integrity.measurements_gated),
               static_cast<long long>(integrity.measurements_rejected),
               static_cast<long long>(integrity.landmarks_rejected));
  std::fprintf(stderr, "%s: result: %s%s%s\n", tool, verdict.result,
               verdict.reasons.empty() ? "" : ": ", verdict.reasons.c_str());
  ImuReport imu_report;
  if (pipeline->Inertial()) {
    imu_report.counts = pipeline->ImuStreamCounts();
    if (imu == &lcm_imu) {
      lcm_imu.Stop();
      imu_report.has_lcm = true;
      imu_report.lcm = lcm_imu.Counters();
      std::fprintf(stderr,
                   "%s: imu over LCM: %lld received, %lld undecodable, %lld lost to a full "
                   "queue, %lld stamped too far ahead\n",
                   tool, static_cast<long long>(imu_report.lcm.received),
                   static_cast<long long>(imu_report.lcm.undecodable),
                   static_cast<long long>(imu_report.lcm.queue_full),
                   static_cast<long long>(imu_report.lcm.future_dropped));
    }
    if (const estimator::NavState<double>* x = pipeline->NewestNavState()) {
      imu_report.has_biases = true;
      imu_report.estimated = x->biases;
    }
    // The unit's true bias at the last sample the pipeline took.
    const sim::ImuModel* unit = world ? world->ImuUnit() : nullptr;
    const std::int64_t taken = counters.imu_samples;
    if (unit != nullptr && taken > 0 &&
        taken <= static_cast<std::int64_t>(unit->TrueBiases().size())) {
      imu_report.has_truth = true;
      imu_report.truth = unit->TrueBiases()[static_cast<std::size_t>(taken - 1)];
      imu_report.imu_only_pose_rms_m =
          ImuOnlyPoseRms(*unit, world->Trajectory(), po.imu, po.initial_world_T_camera);
    }
    std::fprintf(stderr, "%s: imu: %lld samples integrated, %lld dropped, %lld intervals bridged\n",
                 tool, static_cast<long long>(imu_report.counts.stream.accepted),
                 static_cast<long long>(
                     imu_report.counts.stream.out_of_order + imu_report.counts.stream.duplicated +
                     imu_report.counts.stream.invalid + imu_report.counts.stream.saturated),
                 static_cast<long long>(imu_report.counts.intervals_bridged));
  }
  if (!config.summary_path.empty()) {
    WriteSummary(config.summary_path, config, counters, h, evaluate ? &eval : nullptr,
                 evaluate && hazard_counter.maps > 0 ? &hazard_eval : nullptr, hazard_counter.maps,
                 locked, fifo, verdict, integrity, world ? &world->Trajectory() : nullptr,
                 world ? &world->Target() : nullptr, log_stream,
                 pipeline->Inertial() ? &imu_report : nullptr);
  }
  return verdict.exit_code;
}

}  // namespace swf::app
