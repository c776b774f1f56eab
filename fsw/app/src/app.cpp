#include "swf/app/app.hpp"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "swf/app/config.hpp"
#include "swf/app/flight_loop.hpp"
#include "swf/app/hazard_stage.hpp"
#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/app/realtime.hpp"
#include "swf/cli/cli.hpp"
#include "swf/drivers/lcm_stereo_source.hpp"
#if SWF_APP_HAVE_ARAVIS
#include <arv.h>

#include "swf/drivers/aravis_stereo_source.hpp"
#endif
#if SWF_APP_HAVE_V4L2
#include "swf/app/v4l2_source.hpp"
#endif
#include "swf/image_io/image_io.hpp"
#include "swf_msgs/nav_state_t.hpp"

namespace swf::app {

namespace {

FlightLoop* g_loop = nullptr;
void OnSignal(int /*sig*/) {
  if (g_loop != nullptr) g_loop->RequestStop();
}

// Progress on stderr: one line rewritten in place (a terminal) or every 10th frame (a file).
class Progress : public OutputObserver {
 public:
  void Reset(const char* tool, std::int64_t total, bool enabled, bool tty) {
    tool_ = tool;
    total_ = total;
    enabled_ = enabled;
    tty_ = tty;
    navs_ = 0;
    landmarks_ = 0;
  }
  void OnNav(const NavRecord& r) override {
    if (!enabled_) return;
    ++navs_;
    if (!tty_ && navs_ % 10 != 0 && navs_ != total_) return;
    std::fprintf(stderr, "%s%s: frame %lld/%lld  altitude %.1f m  landmarks in map %d%s",
                 tty_ ? "\r" : "", tool_, static_cast<long long>(r.nav.frame_seq + 1),
                 static_cast<long long>(total_), r.nav.position_world_m[2], landmarks_,
                 tty_ ? "   " : "\n");
  }
  void OnMap(const MapRecord& r) override { landmarks_ = r.map.num_landmarks; }
  void Finish() {
    if (enabled_ && tty_) std::fprintf(stderr, "\n");
  }

 private:
  const char* tool_ = "";
  std::int64_t total_ = 0;
  bool enabled_ = false;
  bool tty_ = false;
  std::int64_t navs_ = 0;
  int landmarks_ = 0;
};

class HazardCounter : public OutputObserver {
 public:
  void OnHazard(const HazardRecord& r) override {
    ++maps;
    last_site_valid = r.safe_site_valid;
    outliers_rejected = r.outliers_rejected;
    cells_replaced = r.cells_replaced;
  }
  std::int64_t maps = 0;
  bool last_site_valid = false;
  // The mapper's outlier gate since start, as the last published map states it.
  std::int64_t outliers_rejected = 0;
  std::int64_t cells_replaced = 0;
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
  o.reference_from_estimate = c.frontend_reference_from_estimate;
  o.recover_lost_tracks = c.frontend_recover_lost_tracks;
  return o;
}

estimator::SwfOptions SwfFor(const FswConfig& c, std::int8_t* nav_mode) {
  estimator::SwfOptions o;
  o.window_size = c.window;
  o.max_iterations = c.max_iterations;
  o.hold_depth_precision = c.hold_depth_precision;
  using Nav = swf_msgs::nav_state_t;
  if (c.mode == "vo") {
    o.mode = estimator::SwfMode::kVisualOdometry;
    *nav_mode = Nav::MODE_VO;
  } else if (c.mode == "vsdf") {
    o.mode = estimator::SwfMode::kVsdf;
    o.vsdf_scalar_diagonal = c.vsdf_scalar_diagonal;
    *nav_mode = Nav::MODE_VSDF;
  } else {
    o.mode = estimator::SwfMode::kSlidingWindow;
    *nav_mode = c.mode == "ekf" ? Nav::MODE_EKF : Nav::MODE_SWF;
  }
  return o;
}

Verdict JudgeRun(const LoopCounters& counters, const HealthRecord& health,
                 const IntegrityCounters& integrity, estimator::NavIntegrity final_status,
                 const drivers::LogStreamStats* log) {
  Verdict v;
  const double frames = static_cast<double>(std::max<std::int64_t>(1, counters.frames));
  if (counters.frames == 0) Fail(&v, "no frame was processed");
  if (counters.frames > 0 && final_status == estimator::NavIntegrity::kInvalid)
    Fail(&v, "the final estimate is INVALID");
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

void WriteIntegrity(std::FILE* f, const IntegrityCounters& c, const ProcessExtension* truth) {
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
  if (truth != nullptr) truth->WriteIntegrityTruth(f);
  std::fprintf(f, "},\n");
}

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
  std::fprintf(f, ", \"time_offset_ms\": %s, \"time_offset_estimated\": %s",
               JsonNumber(r.time_offset_s * 1e3).c_str(),
               r.time_offset_estimated ? "true" : "false");
  if (r.time_offset_estimated) {
    std::fprintf(f, ", \"time_offset_sigma_ms\": %s, \"time_offset_readings\": %ld",
                 JsonNumber(r.time_offset_sigma_s * 1e3).c_str(), r.time_offset_readings);
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

// The hazard maps the run published; against truth when an extension has it.
void WriteHazard(std::FILE* f, const HazardCounter& hazard, const ProcessExtension* truth) {
  std::fprintf(f, "  \"hazard_maps\": %lld,\n", static_cast<long long>(hazard.maps));
  // The mapper's gross-outlier gate (docs/hazard.md): frame cells not fused, fused cells replaced.
  std::fprintf(f, "  \"hazard_outliers\": {\"rejected\": %lld, \"cells_replaced\": %lld},\n",
               static_cast<long long>(hazard.outliers_rejected),
               static_cast<long long>(hazard.cells_replaced));
  if (truth == nullptr || !truth->WriteHazardTruth(f))
    std::fprintf(f, "  \"hazard\": null,\n  \"hazard_by_map\": [],\n  \"safe_site\": null\n");
}

// A stack's high-water in bytes, or null when the thread did not run (or its stack was unknown).
void WriteStack(std::FILE* f, const char* name, const core::StackWatermark& stack, bool last) {
  if (stack.Measured()) {
    std::fprintf(f, "\"%s\": %lld%s", name, static_cast<long long>(stack.HighWaterBytes()),
                 last ? "" : ", ");
  } else {
    std::fprintf(f, "\"%s\": null%s", name, last ? "" : ", ");
  }
}

// The process's memory when the frame group started and when it stopped, the page faults in
// between and each thread's stack high-water (core/memory_use.hpp); null where not measured.
void WriteMemory(std::FILE* f, const FlightLoop::Memory& m, const core::StackWatermark& output) {
  std::fprintf(f, "  \"memory\": {");
  if (m.at_start.valid && m.at_end.valid) {
    std::fprintf(f,
                 "\"resident_bytes_at_start\": %lld, \"resident_bytes_at_end\": %lld, "
                 "\"peak_resident_bytes\": %lld, \"minor_faults_after_start\": %lld, "
                 "\"major_faults_after_start\": %lld,\n",
                 static_cast<long long>(m.at_start.resident_bytes),
                 static_cast<long long>(m.at_end.resident_bytes),
                 static_cast<long long>(m.at_end.peak_resident_bytes),
                 static_cast<long long>(m.at_end.minor_faults - m.at_start.minor_faults),
                 static_cast<long long>(m.at_end.major_faults - m.at_start.major_faults));
  } else {
    std::fprintf(f,
                 "\"resident_bytes_at_start\": null, \"resident_bytes_at_end\": null, "
                 "\"peak_resident_bytes\": null, \"minor_faults_after_start\": null, "
                 "\"major_faults_after_start\": null,\n");
  }
  const bool saturated = m.frame_group.Saturated() || m.hazard.Saturated() ||
                         m.recovery.Saturated() || output.Saturated();
  std::fprintf(f, "    \"stack_painted_bytes\": %lld, \"stack_saturated\": %s,\n",
               static_cast<long long>(core::StackWatermark::kDefaultDepth),
               saturated ? "true" : "false");
  std::fprintf(f, "    \"stack_high_water_bytes\": {");
  WriteStack(f, "frame_group", m.frame_group, false);
  WriteStack(f, "hazard", m.hazard, false);
  WriteStack(f, "recovery", m.recovery, false);
  WriteStack(f, "output", output, true);
  std::fprintf(f, "}},\n");
}

// False when the file could not be written whole (a full disk, an I/O error). `truth`: the
// extension that evaluated the run (or nullptr).
// The run as given, echoed into the summary: the program, its version and commit, its arguments
// and every configuration key given (file line or --set) with its value as written; the keys not
// given are that version's defaults (fsw/app/README.md).
struct RunEcho {
  const char* tool = "";
  std::vector<std::string> arguments;
};

void WriteRunEcho(std::FILE* f, const RunEcho& run, const FswConfig& c) {
  std::fprintf(f, "  \"run\": {\"tool\": %s, \"version\": %s, \"commit\": %s, \"arguments\": [",
               JsonString(run.tool).c_str(), JsonString(cli::Version()).c_str(),
               JsonString(cli::Commit()).c_str());
  for (std::size_t i = 0; i < run.arguments.size(); ++i)
    std::fprintf(f, "%s%s", i > 0 ? ", " : "", JsonString(run.arguments[i]).c_str());
  std::fprintf(f, "],\n    \"config\": {\"file\": %s, \"keys\": {",
               JsonString(c.origins.file).c_str());
  const char* separator = "";
  for (const auto& [key, value] : c.origins.values) {
    const auto where = c.origins.keys.find(key);
    std::fprintf(f, "%s\n      %s: {\"value\": %s, \"from\": %s}", separator,
                 JsonString(key).c_str(), JsonString(value).c_str(),
                 JsonString(where != c.origins.keys.end() ? where->second : "").c_str());
    separator = ",";
  }
  std::fprintf(f, "}}},\n");
}

bool WriteSummary(const std::string& path, const RunEcho& run, const FswConfig& c,
                  const LoopCounters& counters, const OutputCounters& output,
                  const HealthRecord& health, const HazardCounter& hazard, bool locked, bool fifo,
                  const Verdict& verdict, const IntegrityCounters& integrity,
                  const ProcessExtension* truth, const drivers::LogStreamStats* log,
                  const ImuReport* imu, const FlightLoop::Memory& memory,
                  const core::StackWatermark& output_stack, std::string* error) {
  cli::OutputFile out;
  if (!out.Open(path, error)) return false;
  std::FILE* f = out.Stream();
  std::fprintf(f, "{\n  \"result\": \"%s\",\n  \"result_reasons\": %s,\n", verdict.result,
               JsonString(verdict.reasons).c_str());
  WriteRunEcho(f, run, c);
  std::fprintf(f, "  \"source\": \"%s\",\n", SourceName(c.source));
  std::fprintf(f, "  \"frames\": %lld,\n", static_cast<long long>(counters.frames));
  std::fprintf(f, "  \"rate_hz\": %.3f,\n  \"window\": %d,\n  \"mode\": \"%s\",\n", c.rate_hz,
               c.window, c.mode.c_str());
  if (imu != nullptr) WriteImu(f, c, *imu);
  if (truth != nullptr) truth->WriteSummaryHead(f);
  WriteIntegrity(f, integrity, truth);
  std::fprintf(f, "  \"stages\": {\n");
  for (int i = 0; i < kNumStages; ++i) {
    std::fprintf(f, "    \"%s\": {\"p50_ms\": %.3f, \"p99_ms\": %.3f, \"max_ms\": %.3f}%s\n",
                 StageName(i), health.stages[i].p50_ms, health.stages[i].p99_ms,
                 health.stages[i].max_ms, i + 1 < kNumStages ? "," : "");
  }
  std::fprintf(f, "  },\n");
  std::fprintf(
      f,
      "  \"overruns\": %lld,\n  \"hazard_overruns\": %lld,\n"
      "  \"lockstep_waits\": {\"cycles\": %lld, \"total_ms\": %.3f, \"max_ms\": %.3f},\n"
      "  \"allocations_after_start\": %lld,\n"
      "  \"outputs_dropped\": %lld,\n  \"frames_dropped\": %lld,\n"
      "  \"frames_rejected\": %lld,\n"
      "  \"camera\": {\"missing_packets\": %lld, \"pairing_failures\": %lld, \"timeouts\": %lld},\n"
      "  \"stage_errors\": %lld,\n  \"records_lost\": %lld,\n  \"fault_bits\": %d,\n"
      "  \"num_landmarks\": %d,\n"
      "  \"mlockall\": %s,\n  \"sched_fifo\": %s,\n",
      static_cast<long long>(counters.overruns), static_cast<long long>(counters.hazard_overruns),
      static_cast<long long>(counters.lockstep_waits), core::NsToMs(counters.lockstep_wait_ns),
      core::NsToMs(counters.lockstep_wait_max_ns),
      static_cast<long long>(health.allocations_after_start),
      static_cast<long long>(health.outputs_dropped), static_cast<long long>(health.frames_dropped),
      static_cast<long long>(health.frames_rejected),
      static_cast<long long>(health.camera_missing_packets),
      static_cast<long long>(health.camera_pairing_failures),
      static_cast<long long>(health.camera_timeouts), static_cast<long long>(counters.stage_errors),
      static_cast<long long>(output.record_errors + output.encode_errors), health.fault_bits,
      health.num_landmarks, locked ? "true" : "false", fifo ? "true" : "false");
  WriteMemory(f, memory, output_stack);
  if (log != nullptr) {
    std::fprintf(f,
                 "  \"log\": {\"frames_missing\": %lld, \"duplicates_refused\": %lld, "
                 "\"out_of_order_refused\": %lld},\n",
                 static_cast<long long>(log->frames_missing),
                 static_cast<long long>(log->duplicates),
                 static_cast<long long>(log->out_of_order));
  }
  WriteHazard(f, hazard, truth);
  std::fprintf(f, "}\n");
  return out.Commit(error);
}

struct CommandLine {
  std::string config_path;
  std::string log_path;
  std::string record_override;
  bool progress = false;
  bool check = false;  // --check: validate, run nothing
  std::vector<std::string> sets;
  std::vector<std::string> arguments;  // as given, echoed into the summary
};

// The flight processes' options (swf::cli's parser: the convention of docs/cli.md without CLI11
// in the flight binary). A replay takes its frames from --log and may name its recording.
// cli::kContinue or the exit code.
int ParseCommandLine(int argc, char** argv, const Program& program, CommandLine* cl) {
  cli::CommandLine parser(
      program.tool,
      program.replay ? "--config FILE --log IN.lcmlog [--record OUT.lcmlog] [--set 'key: value']..."
                       " [--progress] [--check]"
                     : "--config FILE [--set 'key: value']... [--progress] [--check]",
      program.replay ? "The flight pipeline on the stereo frames of a recorded LCM log."
                     : "The flight process: configuration -> source -> rate groups -> outputs "
                       "(fsw/app/README.md).");
  parser.Value("--config", "FILE", "the configuration file", &cl->config_path, true);
  parser.Repeated("--set", "'key: value'", "override one key of the file", &cl->sets);
  if (program.replay) {
    parser.Value("--log", "IN.lcmlog", "the recorded log to replay", &cl->log_path, true);
    parser.Value("--record", "OUT.lcmlog", "record the replay's outputs here",
                 &cl->record_override);
  }
  parser.Flag("--progress", "a progress line on stderr", &cl->progress);
  parser.Flag("--check",
              "validate the configuration (the file, every --set, the output paths) and exit 0 "
              "without running (2: refused)",
              &cl->check);
  const int code = parser.Parse(argc, argv);
  cl->arguments = parser.Arguments();
  return code;
}

// Exit codes of the phases below: kContinue, or what the process exits with.
constexpr int kContinue = cli::kContinue;
constexpr int kRefused = cli::kExitUsage;
constexpr int kRunError = cli::kExitFailed;

// Everything one run of the flight process holds, built phase by phase before real time starts
// and read by the report after it.
struct FlightProcess {
  const char* tool = "swf-fsw";
  bool replay = false;
  ProcessExtension* extension = nullptr;
  bool extension_source = false;  // the extension opened the source: it has the run's truth
  bool progress = false;
  RunEcho run;
  FswConfig config;
  std::string error;
  // The source and what it told about the run.
  PipelineOptions po;
  std::int8_t nav_mode = 0;
  std::int64_t total_frames = 0;
  std::string imu_channel;
#if SWF_APP_HAVE_ARAVIS
  // Aravis's GigE Vision fake cameras served by this process (camera.fake); they outlive the
  // source that talks to them.
  struct FakeCameras {
    std::vector<ArvGvFakeCamera*> cameras;
    ~FakeCameras() {
      for (ArvGvFakeCamera* c : cameras) g_object_unref(c);
    }
  } fake_cameras;
#endif
  std::unique_ptr<drivers::StereoSource> source;
  drivers::LogStereoSource* log_source = nullptr;
  drivers::LcmStereoSource* lcm_source = nullptr;
#if SWF_APP_HAVE_ARAVIS
  drivers::AravisStereoSource* aravis_source = nullptr;
  std::string aravis_left_id;  // the source keeps pointers to these
  std::string aravis_right_id;
  std::string aravis_features;
#endif
#if SWF_APP_HAVE_V4L2
  drivers::V4l2StereoSource* v4l2_source = nullptr;
#endif
  FlightParts parts;  // the preallocated flight process
  FlightLoop loop;
  drivers::ImuProvider* imu = nullptr;
  LcmImuInput lcm_imu;
  // Output observers.
  Progress progress_display;
  LastHealth last_health;
  HazardCounter hazard_counter;
  // Real time.
  bool locked = false;
  bool fifo = false;
  core::Status run_status = core::Status::kOk;

  FlightProcess() = default;
  FlightProcess(const FlightProcess&) = delete;
  FlightProcess& operator=(const FlightProcess&) = delete;

  int Refuse() const {
    std::fprintf(stderr, "%s: configuration refused: %s\n", tool, error.c_str());
    return kRefused;
  }
  int RunError() const {
    std::fprintf(stderr, "%s: %s\n", tool, error.c_str());
    return kRunError;
  }
};

// The file and every --set, validated once as a whole (their order does not matter); a replay
// takes its source from --log. Output paths are checked now, not discovered unwritable after the
// whole descent.
int Configure(const CommandLine& cl, FlightProcess* fp) {
  FswConfig& config = fp->config;
  const ConfigExtension* keys = fp->extension != nullptr ? fp->extension->Config() : nullptr;
  if (!LoadConfig(cl.config_path, cl.sets, &config, &fp->error, keys)) return fp->Refuse();
  if (fp->replay) {
    config.source = SourceKind::kLog;
    config.log_path = cl.log_path;
    // The replayed frames are in the input log already, so a replay's recording holds only the
    // outputs unless asked (--set 'record.frames: true'): then it holds the frames too and can be
    // replayed again (swf-convert's round trip test).
    const auto frames = config.origins.keys.find("record.frames");
    if (frames == config.origins.keys.end() || frames->second != "--set") {
      config.record_frames = false;
    }
    const auto record = config.origins.keys.find("record.path");
    if (!cl.record_override.empty()) {
      config.record_path = cl.record_override;
    } else if (record == config.origins.keys.end() || record->second != "--set") {
      config.record_path = "";
    }
    if (!ValidateConfig(config, cl.config_path, &fp->error)) return fp->Refuse();
  }
  if (!CheckOutputPaths(config, &fp->error)) return fp->Refuse();
  fp->imu_channel =
      config.imu.channel.empty() ? config.channel_prefix + kImuSuffix : config.imu.channel;
  return kContinue;
}

// The first pose: the configured hand-over (initial: position, camera pointing straight down,
// image x along world x) or, initial: truth, the extension's simulated descent. The extension's
// own source sets its start when it opens (a descent to an orbital target needs its terrain).
int SetInitialState(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  PipelineOptions& po = fp->po;
  if (config.initial != "truth") {
    Eigen::Matrix3d nadir;
    nadir << 1.0, 0.0, 0.0,  //
        0.0, -1.0, 0.0,      //
        0.0, 0.0, -1.0;
    po.initial_world_T_camera.R = nadir;
    po.initial_world_T_camera.t = Eigen::Vector3d(
        config.initial_position_m[0], config.initial_position_m[1], config.initial_position_m[2]);
    po.imu = ImuOptionsFor(config);
  }
  if (fp->extension != nullptr && config.source != SourceKind::kSim &&
      !fp->extension->Start(config, &po, &fp->error)) {
    return fp->Refuse();
  }
  return kContinue;
}

// Raw frames (aravis, v4l2, an unrectified log): the calibrations give the image size and the
// pipeline rectifies. Loaded here, once.
int UseCameraCalibrations(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  PipelineOptions& po = fp->po;
  fp->error.clear();
  if (config.camera.left_calibration.empty() || config.camera.right_calibration.empty() ||
      !image_io::LoadCalibration(config.camera.left_calibration, &po.left_calibration,
                                 &fp->error) ||
      !image_io::LoadCalibration(config.camera.right_calibration, &po.right_calibration,
                                 &fp->error)) {
    std::fprintf(stderr, "%s: configuration refused: camera calibration: %s\n", fp->tool,
                 fp->error.empty() ? "both calibration files are required" : fp->error.c_str());
    return kRefused;
  }
  po.rectify = true;
  po.width_px = po.left_calibration.width;
  po.height_px = po.left_calibration.height;
  return kContinue;
}

// The extension's own source (source sim: swf-sil's simulated descent).
int OpenExtensionSource(FlightProcess* fp) {
  if (!fp->extension->OpenSource(fp->config, fp->progress, &fp->po, &fp->source, &fp->total_frames,
                                 &fp->error)) {
    return fp->RunError();
  }
  fp->extension_source = true;
  return kContinue;
}

// Configures a live source and makes it the process's, kept as *typed too for its own
// statistics; it runs to max_frames. kRefused, naming the source, when it refuses its options.
template <typename Source, typename Options>
int UseLiveSource(FlightProcess* fp, const char* name, const Options& options,
                  std::unique_ptr<Source> source, Source** typed) {
  if (const core::Status s = source->Configure(options); s != core::Status::kOk) {
    std::fprintf(stderr, "%s: the %s source refused its options (%s): %s\n", fp->tool, name,
                 core::ToString(s), source->LastError());
    return kRefused;
  }
  fp->total_frames = fp->config.max_frames;
  *typed = source.get();
  fp->source = std::move(source);
  return kContinue;
}

int OpenLogSource(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  PipelineOptions& po = fp->po;
  auto log = std::make_unique<drivers::LogStereoSource>();
  if (config.imu.enabled) log->SetImuChannel(fp->imu_channel);
  if (!log->Load(config.log_path, config.channel_prefix + kStereoSuffix, &fp->error))
    return fp->RunError();
  if (log->NumFrames() == 0 && !log->LoadError().empty()) {
    std::fprintf(stderr, "%s: %s (no frame before it)\n", fp->tool, log->LoadError().c_str());
    return kRunError;
  }
  if (log->NumFrames() == 0) {
    std::fprintf(stderr,
                 "%s: %s: no %s%s records (a replay records its frames only with --set "
                 "'record.frames: true'; swf-convert makes logs of datasets)\n",
                 fp->tool, config.log_path.c_str(), config.channel_prefix.c_str(), kStereoSuffix);
    return kRunError;
  }
  po.width_px = log->Width();
  po.height_px = log->Height();
  if (log->Rectified()) {
    // A rectified log's frames carry no camera model: only its recorder's rig fits them.
    if (fp->extension == nullptr) {
      std::fprintf(stderr,
                   "%s: %s: the frames are rectified and carry no camera model (a simulated "
                   "descent's log): replay it with swf-replay\n",
                   fp->tool, config.log_path.c_str());
      return kRefused;
    }
    po.camera = fp->extension->RectifiedRig(config, log->Width(), log->Height());
  } else {
    if (const int code = UseCameraCalibrations(fp); code != kContinue) return code;
    if (po.width_px != log->Width() || po.height_px != log->Height()) {
      std::fprintf(stderr,
                   "%s: configuration refused: camera.left_calibration: %s is for %dx%d px, "
                   "the log's frames are %dx%d px\n",
                   fp->tool, config.camera.left_calibration.c_str(), po.width_px, po.height_px,
                   log->Width(), log->Height());
      return kRefused;
    }
  }
  fp->total_frames = static_cast<std::int64_t>(log->NumFrames());
  fp->log_source = log.get();
  fp->source = std::move(log);
  return kContinue;
}

int OpenAravisSource(FlightProcess* fp) {
#if SWF_APP_HAVE_ARAVIS
  const FswConfig& config = fp->config;
  if (const int code = UseCameraCalibrations(fp); code != kContinue) return code;
  fp->aravis_left_id = config.camera.left.empty() ? "127.0.0.1" : config.camera.left;
  fp->aravis_right_id = config.camera.right.empty() ? "127.0.0.2" : config.camera.right;
  if (config.camera.fake) {
    // Aravis's GigE Vision fake cameras served by this process (tests, no hardware): at the
    // address camera.left / camera.right name, or, when they name a serial number, at 127.0.0.1
    // / 127.0.0.2 with that serial (found by discovery, as a bench's cameras are).
    for (const auto& [id, default_address] : {std::pair{fp->aravis_left_id, "127.0.0.1"},
                                              std::pair{fp->aravis_right_id, "127.0.0.2"}}) {
      const bool by_address = drivers::IsIpv4Address(id.c_str());
      const std::string address = by_address ? id : default_address;
      ArvGvFakeCamera* fake =
          arv_gv_fake_camera_new(address.c_str(), by_address ? nullptr : id.c_str());
      if (fake == nullptr || !arv_gv_fake_camera_is_running(fake)) {
        std::fprintf(stderr, "%s: cannot serve a fake GigE camera on %s\n", fp->tool,
                     address.c_str());
        if (fake != nullptr) g_object_unref(fake);
        return kRunError;
      }
      fp->fake_cameras.cameras.push_back(fake);
    }
  }
  auto aravis = std::make_unique<drivers::AravisStereoSource>();
  drivers::AravisStereoOptions ao;
  ao.left_id = fp->aravis_left_id.c_str();
  ao.right_id = fp->aravis_right_id.c_str();
  ao.width = fp->po.left_calibration.width;
  ao.height = fp->po.left_calibration.height;
  const CameraConfig& camera = config.camera;
  ao.x = camera.roi_offset_px[0];
  ao.y = camera.roi_offset_px[1];
  ao.exposure_us = camera.exposure_us;
  ao.gain = camera.gain;
  ao.packet_size = camera.packet_size;
  const std::string trigger =
      camera.trigger.empty() ? (camera.fake ? "software" : "free") : camera.trigger;
  ao.trigger = trigger == "software"   ? drivers::TriggerMode::kSoftware
               : trigger == "hardware" ? drivers::TriggerMode::kHardware
                                       : drivers::TriggerMode::kFreeRun;
  ao.hardware_trigger_source = camera.trigger_source.c_str();
  ao.frame_rate_hz = ao.trigger == drivers::TriggerMode::kFreeRun ? config.rate_hz : 0.0;
  for (const auto& [name, value] : camera.features) {
    fp->aravis_features += (fp->aravis_features.empty() ? "" : " ") + name + "=" + value;
  }
  ao.features = fp->aravis_features.c_str();
  return UseLiveSource(fp, "aravis", ao, std::move(aravis), &fp->aravis_source);
#else
  std::fprintf(stderr,
               "%s: configuration refused: source: aravis: this build has no Aravis "
               "(SWF_WITH_ARAVIS=OFF)\n",
               fp->tool);
  return kRefused;
#endif
}

int OpenV4l2Source(FlightProcess* fp) {
#if SWF_APP_HAVE_V4L2
  if (const int code = UseCameraCalibrations(fp); code != kContinue) return code;
  // The device paths stay in `config`, which outlives the source.
  std::unique_ptr<drivers::V4l2StereoSource> v4l2 =
      MakeV4l2Source(fp->config, fp->po.left_calibration.width, fp->po.left_calibration.height,
                     drivers::LinuxV4l2Kernel(), &fp->error);
  if (v4l2 == nullptr) return fp->Refuse();
  fp->total_frames = fp->config.max_frames;
  fp->v4l2_source = v4l2.get();
  fp->source = std::move(v4l2);
  return kContinue;
#else
  std::fprintf(stderr,
               "%s: configuration refused: source: v4l2: this build has no V4L2 "
               "(SWF_WITH_V4L2=OFF)\n",
               fp->tool);
  return kRefused;
#endif
}

// Raw pairs published live as stereo_frame_t: the calibrations give their size (a frame of
// another size, or already rectified, is rejected and counted by the source) and the pipeline
// rectifies them.
int OpenLcmSource(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  if (const int code = UseCameraCalibrations(fp); code != kContinue) return code;
  auto lcm = std::make_unique<drivers::LcmStereoSource>();
  drivers::LcmStereoOptions lo;
  lo.url = config.lcm_source.url.empty() ? config.lcm_url : config.lcm_source.url;
  lo.channel = config.lcm_source.channel;
  lo.max_width = fp->po.width_px;
  lo.max_height = fp->po.height_px;
  lo.exact_size = true;
  lo.rectified = false;
  lo.buffers = config.lcm_source.buffers;
  return UseLiveSource(fp, "lcm", lo, std::move(lcm), &fp->lcm_source);
}

int OpenSource(FlightProcess* fp) {
  switch (fp->config.source) {
    case SourceKind::kSim: return OpenExtensionSource(fp);
    case SourceKind::kLog: return OpenLogSource(fp);
    case SourceKind::kLcm: return OpenLcmSource(fp);
    case SourceKind::kAravis: return OpenAravisSource(fp);
    case SourceKind::kV4l2: return OpenV4l2Source(fp);
  }
  return kRefused;
}

// The flight parts with all of their memory (AssembleFlightParts), then the output thread's
// observers.
int Preallocate(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  PipelineOptions& po = fp->po;
  ApplyEstimatorConfig(config, &po, &fp->nav_mode);
  hazard::HazardMapperOptions ho;
  ho.max_disparities = config.hazard_max_disparities;
  ho.downsample = config.hazard_downsample;
  OutputOptions oo;
  oo.lcm_url = config.publish ? config.lcm_url : "";
  oo.channel_prefix = config.channel_prefix;
  oo.record_path = config.record_path;
  oo.record_frames = config.record_frames;
  if (const core::Status s = AssembleFlightParts(po, ho, oo, &fp->parts, &fp->error);
      s != core::Status::kOk) {
    return s == core::Status::kInvalidArgument ? fp->Refuse() : fp->RunError();
  }
  const Pipeline& pipeline = *fp->parts.pipeline;
  if (!CheckEnvelopeDisparity(config, pipeline.Camera().fx, pipeline.Camera().baseline_m,
                              po.width_px, &fp->error)) {
    return fp->Refuse();
  }
  if (fp->extension_source) fp->extension->Observe(&fp->parts);
  fp->progress_display.Reset(
      fp->tool,
      config.max_frames > 0 ? std::min(config.max_frames, fp->total_frames) : fp->total_frames,
      fp->progress, isatty(2) != 0);
  fp->parts.output.AddObserver(&fp->progress_display);
  fp->parts.output.AddObserver(&fp->last_health);
  fp->parts.output.AddObserver(&fp->hazard_counter);
  return kContinue;
}

// The IMU: the simulator's unit, the log's recording, or (cameras) imu_t over LCM.
int ConnectImu(FlightProcess* fp) {
  if (!fp->config.imu.enabled) return kContinue;
  if (fp->extension_source) {
    fp->imu = fp->extension->Imu();
  } else if (fp->log_source != nullptr) {
    if (fp->log_source->NumImuSamples() == 0) {
      std::fprintf(stderr, "%s: %s: imu.enabled but no %s records in the log\n", fp->tool,
                   fp->config.log_path.c_str(), fp->imu_channel.c_str());
      return kRunError;
    }
    fp->imu = fp->log_source;
  } else {
    if (!fp->lcm_imu.Start(fp->config.lcm_url, fp->imu_channel, &fp->error)) return fp->RunError();
    fp->imu = &fp->lcm_imu;
  }
  return kContinue;
}

#if SWF_APP_HAVE_ARAVIS
// The configuration key behind a setting the Aravis source says a camera refused (its LastError()
// names the GenICam feature or the setting), "" when none is.
std::string CameraKeyOfRefusal(const std::string& detail) {
  const std::string feature = "GenICam feature ";
  if (const std::size_t at = detail.find(feature); at != std::string::npos) {
    const std::size_t begin = at + feature.size();
    return "camera.feature." + detail.substr(begin, detail.find('=', begin) - begin);
  }
  static const std::pair<const char*, const char*> kSettings[] = {
      {": ExposureTime:", "camera.exposure_us"},
      {": Gain:", "camera.gain"},
      {": GevSCPSPacketSize:", "camera.packet_size"},
      {": region of interest:", "camera.roi_offset_px"},
      {": software trigger:", "camera.trigger"},
      {": hardware trigger:", "camera.trigger_source"},
      {": AcquisitionFrameRate:", "rate_hz"}};
  for (const auto& [setting, key] : kSettings) {
    if (detail.find(setting) != std::string::npos) return key;
  }
  return "";
}
#endif

// The rate groups around the pipeline, then the source started.
int ConfigureLoop(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  LoopOptions lo;
  lo.rate_hz = config.rate_hz;
  lo.pacing = fp->replay && config.pacing == Pacing::kRealtime ? Pacing::kLockstep : config.pacing;
  lo.hazard_every = config.hazard_every;
  lo.health_every = config.health_every;
  // Frames go to the output thread when they are recorded, and in a replay that publishes, so a
  // viewer on the bus sees the images (published only: they are in the replayed log already).
  lo.record_frames =
      (config.record_frames && !config.record_path.empty()) || (fp->replay && config.publish);
  lo.max_frames = config.max_frames;
  lo.nav_mode = fp->nav_mode;
  lo.hazard_priority = config.priority > 1 ? config.priority - 1 : 0;
  lo.inject_stage = config.inject_stage.empty() ? -1 : StageIndex(config.inject_stage);
  lo.inject_first_frame = config.inject_frame;
  lo.inject_frames = config.inject_frames;
  lo.inject_ms = config.inject_ms;
  if (fp->imu == &fp->lcm_imu) {
    lo.imu_wait_ns = static_cast<core::TimeNs>(config.imu.max_latency_ms * 1e6);
    lo.imu_period_ns = static_cast<core::TimeNs>(1e9 / config.imu.rate_hz);
  }
  drivers::MotionProvider* motion = fp->extension_source
                                        ? fp->extension->Motion()
                                        : static_cast<drivers::MotionProvider*>(fp->log_source);
  if (fp->loop.Configure(lo, fp->parts.pipeline.get(), fp->source.get(), fp->parts.channels.get(),
                         motion, fp->parts.hazard.get(), fp->imu) != core::Status::kOk) {
    std::fprintf(stderr,
                 "%s: configuration refused: rate groups (rate_hz, hazard_every, "
                 "health_every)\n",
                 fp->tool);
    return kRefused;
  }
  if (fp->source->Start() == core::Status::kOk) return kContinue;
  const char* detail = "";
  std::string key;
  if (fp->lcm_source != nullptr) detail = fp->lcm_source->LastError();
#if SWF_APP_HAVE_ARAVIS
  if (fp->aravis_source != nullptr) {
    detail = fp->aravis_source->LastError();
    key = CameraKeyOfRefusal(detail);
  }
#endif
#if SWF_APP_HAVE_V4L2
  if (fp->v4l2_source != nullptr) detail = fp->v4l2_source->LastError();
#endif
  std::fprintf(
      stderr, "%s: the %s source did not start%s%s%s%s%s\n", fp->tool, fp->source->Name(),
      detail[0] != '\0' ? ": " : "", detail, key.empty() ? "" : " (configuration key ",
      key.empty() ? "" : key.c_str(),
      key.empty() ? "" : (" at " + ConfigWhere(config, key, config.origins.file) + ")").c_str());
  return kRunError;
}

// The frame group on its own SCHED_FIFO thread (pinned with `cpu`) until the source ends or a
// signal stops it; then the source stops and the outputs drain.
void RunRealTime(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  char message[200];
  if (config.mlockall) {
    fp->locked = LockMemory(message, sizeof message);
    std::fprintf(stderr, "%s: %s\n", fp->tool, message);
  }
  fp->parts.output.Start();
  g_loop = &fp->loop;
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::thread rt([fp, &config] {
    char m[200];
    fp->fifo = MakeThreadRealtime(config.priority, m, sizeof m);
    std::fprintf(stderr, "%s: frame group: %s\n", fp->tool, m);
    if (config.cpu >= 0) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(config.cpu, &set);
      if (pthread_setaffinity_np(pthread_self(), sizeof set, &set) != 0) {
        std::fprintf(stderr, "%s: pinning to CPU %d refused: continuing unpinned\n", fp->tool,
                     config.cpu);
      }
    }
#if SWF_APP_HAVE_ARAVIS
    // GLib gives a thread it did not create its GThread record on first use (one allocation
    // inside the first Aravis call of the frame group): take it here, before counting starts.
    if (fp->aravis_source != nullptr) (void)g_thread_self();
#endif
    fp->run_status = fp->loop.Run();
  });
  rt.join();
  g_loop = nullptr;
  fp->source->Stop();
  fp->parts.output.StopAndDrain();
  fp->progress_display.Finish();
}

// The IMU's part of the report; stops the LCM subscription.
ImuReport ReportImu(FlightProcess* fp) {
  ImuReport report;
  const Pipeline& pipeline = *fp->parts.pipeline;
  report.counts = pipeline.ImuStreamCounts();
  if (fp->imu == &fp->lcm_imu) {
    fp->lcm_imu.Stop();
    report.has_lcm = true;
    report.lcm = fp->lcm_imu.Counters();
    const LoopCounters& loop = fp->loop.Counters();
    std::fprintf(stderr,
                 "%s: imu over LCM: %lld received, %lld undecodable, %lld lost to a full "
                 "queue, %lld stamped too far ahead; %lld frames waited for late samples, %lld "
                 "of them in vain (imu.max_latency_ms)\n",
                 fp->tool, static_cast<long long>(report.lcm.received),
                 static_cast<long long>(report.lcm.undecodable),
                 static_cast<long long>(report.lcm.queue_full),
                 static_cast<long long>(report.lcm.future_dropped),
                 static_cast<long long>(loop.imu_waits),
                 static_cast<long long>(loop.imu_wait_timeouts));
  }
  report.time_offset_s = pipeline.ImuTimeOffsetS();
  report.time_offset_estimated = fp->config.imu.estimate_time_offset;
  report.time_offset_sigma_s = pipeline.ImuTimeOffset().SigmaS();
  report.time_offset_readings = pipeline.ImuTimeOffset().Readings();
  if (const estimator::NavState<double>* x = pipeline.NewestNavState()) {
    report.has_biases = true;
    report.estimated = x->biases;
  }
  const estimator::ImuStreamCounts& s = report.counts.stream;
  std::fprintf(stderr, "%s: imu: %lld samples integrated, %lld dropped, %lld intervals bridged\n",
               fp->tool, static_cast<long long>(s.accepted),
               static_cast<long long>(s.out_of_order + s.duplicated + s.invalid + s.saturated),
               static_cast<long long>(report.counts.intervals_bridged));
  return report;
}

void PrintMemoryLine(const FlightProcess& fp) {
  const FlightLoop::Memory& m = fp.loop.MemoryUse();
  if (!m.at_start.valid || !m.at_end.valid) return;
  constexpr double kMiB = 1024.0 * 1024.0;
  std::fprintf(stderr,
               "%s: memory: %.1f MiB resident at start, %.1f MiB at end (peak %.1f MiB), %lld "
               "page faults after start; stack high-water: frame group %.1f KiB, hazard %.1f "
               "KiB, output %.1f KiB\n",
               fp.tool, static_cast<double>(m.at_start.resident_bytes) / kMiB,
               static_cast<double>(m.at_end.resident_bytes) / kMiB,
               static_cast<double>(m.at_end.peak_resident_bytes) / kMiB,
               static_cast<long long>(m.at_end.minor_faults - m.at_start.minor_faults +
                                      m.at_end.major_faults - m.at_start.major_faults),
               static_cast<double>(m.frame_group.HighWaterBytes()) / 1024.0,
               static_cast<double>(m.hazard.HighWaterBytes()) / 1024.0,
               static_cast<double>(fp.parts.output.Stack().HighWaterBytes()) / 1024.0);
}

void PrintRunLine(const FlightProcess& fp) {
  const LoopCounters& counters = fp.loop.Counters();
  const HealthRecord& h = fp.last_health.last;
  std::fprintf(stderr,
               "%s: %lld frames, %lld overruns, %lld outputs dropped, %lld allocations after "
               "start, cycle p50 %.1f ms p99 %.1f ms max %.1f ms%s",
               fp.tool, static_cast<long long>(counters.frames),
               static_cast<long long>(counters.overruns), static_cast<long long>(h.outputs_dropped),
               static_cast<long long>(h.allocations_after_start), h.stages[kStageCycle].p50_ms,
               h.stages[kStageCycle].p99_ms, h.stages[kStageCycle].max_ms,
               fp.extension_source ? fp.extension->RunLine().c_str() : "");
  std::fprintf(stderr,
               ", %lld hazard maps (%lld skipped, %lld failed, %lld over their period; %lld "
               "outlier cells rejected, %lld replaced), hazard p50 %.1f ms\n",
               static_cast<long long>(fp.hazard_counter.maps),
               static_cast<long long>(counters.hazard_skipped),
               static_cast<long long>(fp.loop.HazardErrors()),
               static_cast<long long>(counters.hazard_overruns),
               static_cast<long long>(fp.hazard_counter.outliers_rejected),
               static_cast<long long>(fp.hazard_counter.cells_replaced),
               h.stages[kStageHazard].p50_ms);
}

void PrintIntegrityLine(const FlightProcess& fp, const Verdict& verdict) {
  const IntegrityCounters& integrity = fp.parts.pipeline->Integrity();
  std::fprintf(stderr,
               "%s: integrity: %lld VALID, %lld DEGRADED, %lld INVALID frames, %lld restarts, "
               "%lld measurements gated, %lld rejected, %lld landmarks rejected\n",
               fp.tool, static_cast<long long>(integrity.frames_valid),
               static_cast<long long>(integrity.frames_degraded),
               static_cast<long long>(integrity.frames_invalid),
               static_cast<long long>(integrity.restarts),
               static_cast<long long>(integrity.measurements_gated),
               static_cast<long long>(integrity.measurements_rejected),
               static_cast<long long>(integrity.landmarks_rejected));
  std::fprintf(stderr, "%s: result: %s%s%s\n", fp.tool, verdict.result,
               verdict.reasons.empty() ? "" : ": ", verdict.reasons.c_str());
}

// What the source said went wrong: a damaged log, a failed camera. True when the log was damaged.
bool ReportSourceTrouble(const FlightProcess& fp) {
  const drivers::LogStereoSource* log_source = fp.log_source;
  const bool damaged_log = log_source != nullptr && !log_source->LoadError().empty();
  if (damaged_log) {
    std::fprintf(stderr,
                 "%s: stopped at a damaged log: %s (the %zu frames before it were "
                 "replayed)\n",
                 fp.tool, log_source->LoadError().c_str(), log_source->NumFrames());
  }
#if SWF_APP_HAVE_V4L2
  if (fp.v4l2_source != nullptr && fp.run_status != core::Status::kOk) {
    std::fprintf(stderr, "%s: the v4l2 source failed: %s\n", fp.tool, fp.v4l2_source->LastError());
  }
#endif
  if (fp.lcm_source != nullptr) {
    // Every message on the channel accounted for: served, rejected (itemised) or dropped.
    const drivers::LcmStereoStats d = fp.lcm_source->Detail();
    const drivers::SourceStats s = fp.lcm_source->Stats();
    std::fprintf(stderr,
                 "%s: lcm %s: %llu messages, %llu pairs served; %llu rejected (%llu undecodable, "
                 "%llu wrong size, %llu wrong rectification, %llu bad fields, %llu out of "
                 "order); %llu dropped (%llu announced by the publisher, %llu sequence gaps, "
                 "%llu no free buffer)\n",
                 fp.tool, fp.config.lcm_source.channel.c_str(),
                 static_cast<unsigned long long>(d.received),
                 static_cast<unsigned long long>(s.pairs_served),
                 static_cast<unsigned long long>(s.frames_rejected),
                 static_cast<unsigned long long>(d.undecodable),
                 static_cast<unsigned long long>(d.wrong_size),
                 static_cast<unsigned long long>(d.wrong_rectification),
                 static_cast<unsigned long long>(d.bad_fields),
                 static_cast<unsigned long long>(d.out_of_order),
                 static_cast<unsigned long long>(s.frames_dropped),
                 static_cast<unsigned long long>(d.announced_drops),
                 static_cast<unsigned long long>(d.sequence_gaps),
                 static_cast<unsigned long long>(d.pool_full));
    if (fp.run_status != core::Status::kOk) {
      std::fprintf(stderr, "%s: the lcm source failed: %s\n", fp.tool, fp.loop.SourceFault());
    }
  }
  const drivers::LogStreamStats* log_stream =
      log_source != nullptr ? &log_source->StreamStats() : nullptr;
  if (log_stream != nullptr && (log_stream->frames_missing > 0 || log_stream->Refused() > 0)) {
    std::fprintf(stderr,
                 "%s: log: %lld frames missing (sequence gaps), %lld duplicated and %lld "
                 "out-of-order frames refused\n",
                 fp.tool, static_cast<long long>(log_stream->frames_missing),
                 static_cast<long long>(log_stream->duplicates),
                 static_cast<long long>(log_stream->out_of_order));
  }
  return damaged_log;
}

// After the run: the verdict from the numbers (and, with the extension's source, its truth), the
// lines on stderr and the summary file. Returns the exit code.
int Report(FlightProcess* fp) {
  const FswConfig& config = fp->config;
  const LoopCounters& counters = fp->loop.Counters();
  const bool damaged_log = ReportSourceTrouble(*fp);
  const drivers::LogStreamStats* log_stream =
      fp->log_source != nullptr ? &fp->log_source->StreamStats() : nullptr;
  const HealthRecord& h = fp->last_health.last;
  const IntegrityCounters& integrity = fp->parts.pipeline->Integrity();
  Verdict verdict =
      JudgeRun(counters, h, integrity, fp->parts.pipeline->LastIntegrity().status, log_stream);
  if (fp->run_status != core::Status::kOk)
    Fail(&verdict, std::string("the frame group stopped: ") + core::ToString(fp->run_status));
  if (damaged_log) Fail(&verdict, "damaged log");
  const OutputCounters& out = fp->parts.output.Counters();
  if (out.record_errors > 0 || out.encode_errors > 0) {
    std::fprintf(stderr, "%s: %lld records could not be written, %lld not encoded\n", fp->tool,
                 static_cast<long long>(out.record_errors),
                 static_cast<long long>(out.encode_errors));
    Fail(&verdict, "records lost");
  }
  const bool inertial = fp->parts.pipeline->Inertial();
  ImuReport imu_report;
  if (inertial) imu_report = ReportImu(fp);
  const ProcessExtension* truth = fp->extension_source ? fp->extension : nullptr;
  if (fp->extension_source) {
    fp->extension->Evaluate(config, fp->parts, fp->po, counters.imu_samples, &verdict,
                            inertial ? &imu_report : nullptr);
  }
  PrintRunLine(*fp);
  PrintMemoryLine(*fp);
  PrintIntegrityLine(*fp, verdict);
  if (!config.summary_path.empty() &&
      !WriteSummary(config.summary_path, fp->run, config, counters, out, h, fp->hazard_counter,
                    fp->locked, fp->fifo, verdict, integrity, truth, log_stream,
                    inertial ? &imu_report : nullptr, fp->loop.MemoryUse(),
                    fp->parts.output.Stack(), &fp->error)) {
    std::fprintf(stderr, "%s: cannot write the summary: %s; exit 1\n", fp->tool, fp->error.c_str());
    return kRunError;
  }
  return verdict.exit_code;
}

}  // namespace

void Fail(Verdict* v, const std::string& reason) {
  v->result = "failed";
  v->exit_code = cli::kExitFailed;
  v->reasons += (v->reasons.empty() ? "" : ", ") + reason;
}

void Degrade(Verdict* v, const std::string& reason) {
  if (v->exit_code == 0) {
    v->result = "degraded";
    v->exit_code = cli::kExitDegraded;
  }
  v->reasons += (v->reasons.empty() ? "" : ", ") + reason;
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", c);
      out += escaped;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

ImuOptions ImuOptionsFor(const FswConfig& c) {
  const ImuConfig& k = c.imu;
  ImuOptions o;
  o.enabled = k.enabled;
  o.noise.gyro_noise_density = k.gyro_noise_density;
  o.noise.gyro_random_walk = k.gyro_random_walk;
  o.noise.accel_noise_density = k.accel_noise_density;
  o.noise.accel_random_walk = k.accel_random_walk;
  o.stream.gyro_range_radps = k.gyro_range_radps;
  o.stream.accel_range_mps2 = k.accel_range_mps2;
  o.gravity_world_mps2 = estimator::Vec3<double>(0.0, 0.0, -k.gravity_mps2);
  o.first_gyro_bias_sigma_radps = k.gyro_bias_sigma_radps;
  o.first_accel_bias_sigma_mps2 = k.accel_bias_sigma_mps2;
  o.first_velocity_sigma_mps = k.velocity_sigma_mps;
  o.static_start = k.static_start;
  o.time_offset_s = k.time_offset_ms * 1e-3;
  o.estimate_time_offset = k.estimate_time_offset;
  o.max_time_offset_s = k.max_time_offset_ms * 1e-3;
  o.stream.nominal_period_us = std::max<std::int64_t>(1, std::llround(1e6 / k.rate_hz));
  estimator::Pose<double> camera_T_imu;
  camera_T_imu.t =
      estimator::Vec3<double>(k.camera_t_imu_m[0], k.camera_t_imu_m[1], k.camera_t_imu_m[2]);
  camera_T_imu.R = estimator::ExpSO3<double>(
      estimator::Vec3<double>(k.camera_r_imu_rad[0], k.camera_r_imu_rad[1], k.camera_r_imu_rad[2]));
  o.imu_T_camera = camera_T_imu.Inverse();
  o.initial_velocity_world_mps = estimator::Vec3<double>(
      k.initial_velocity_mps[0], k.initial_velocity_mps[1], k.initial_velocity_mps[2]);
  return o;
}

void ApplyEstimatorConfig(const FswConfig& config, PipelineOptions* po, std::int8_t* nav_mode) {
  po->frontend = FrontendFor(config, po->width_px, po->height_px);
  po->swf = SwfFor(config, nav_mode);
  po->measurement_sigma_px = config.measurement_sigma_px;
  po->measurement_sigma_per_magnification_px = config.measurement_sigma_per_magnification_px;
  po->measurement_sigma_per_magnification_rad = config.measurement_sigma_per_magnification_rad;
  po->measurement_disparity_sigma_px = config.measurement_disparity_sigma_px;
  po->measurement_disparity_sigma_per_parallax_px =
      config.measurement_disparity_sigma_per_parallax_px;
  po->track_error_shared = config.measurement_track_error_shared;
  po->min_quality = static_cast<float>(config.min_quality);
  po->refine_in_loop = config.frontend_refine_in_loop;
  po->process_sigma_m = config.process_sigma_m;
  po->process_sigma_rad = config.process_sigma_rad;
  po->calibration_baseline_sigma_m = config.calibration_baseline_sigma_m;
  po->calibration_disparity_sigma_px = config.calibration_disparity_sigma_px;
}

core::Status AssembleFlightParts(const PipelineOptions& po,
                                 hazard::HazardMapperOptions hazard_options,
                                 OutputOptions output_options, FlightParts* parts,
                                 std::string* error) {
  char text[300];
  parts->pipeline = std::make_unique<Pipeline>();
  if (const core::Status s = parts->pipeline->Configure(po); s != core::Status::kOk) {
    std::snprintf(text, sizeof text,
                  "the pipeline rejected it (%s): check window, max_tracks, max_disparity_px and "
                  "the rig",
                  core::ToString(s));
    *error = text;
    return core::Status::kInvalidArgument;
  }
  parts->hazard = std::make_unique<MapperHazardStage>();
  hazard_options.camera = parts->pipeline->Camera();
  hazard_options.image_width = po.width_px;
  hazard_options.image_height = po.height_px;
  if (const core::Status s = parts->hazard->Configure(hazard_options); s != core::Status::kOk) {
    std::snprintf(text, sizeof text,
                  "hazard.max_disparities / hazard.downsample: the hazard mapper rejected them "
                  "for %dx%d images (%s)",
                  po.width_px, po.height_px, core::ToString(s));
    *error = text;
    return core::Status::kInvalidArgument;
  }
  parts->channels = std::make_unique<OutputChannels>();
  if (parts->channels->Allocate(po.width_px, po.height_px, parts->hazard->GridCells()) !=
      core::Status::kOk) {
    *error = "out of memory for the output pools";
    return core::Status::kFull;
  }
  output_options.max_width = po.width_px;
  output_options.max_height = po.height_px;
  output_options.max_hazard_cells = parts->hazard->GridCells();
  if (!parts->output.Open(output_options, parts->channels.get(), error))
    return core::Status::kIoError;
  return core::Status::kOk;
}

int RunFlightProcess(int argc, char** argv, const Program& program) {
  CommandLine command_line;
  if (const int code = ParseCommandLine(argc, argv, program, &command_line);
      code != cli::kContinue) {
    return code;
  }
  auto fp = std::make_unique<FlightProcess>();
  fp->tool = program.tool;
  fp->replay = program.replay;
  fp->extension = program.extension;
  fp->progress = command_line.progress;
  fp->run.tool = program.tool;
  fp->run.arguments = command_line.arguments;
  if (const int code = Configure(command_line, fp.get()); code != kContinue) return code;
  if (command_line.check) {
    // Everything a run refuses before it builds anything has been said: the file and every --set
    // as a whole (the simulator's envelope included) and the output paths.
    std::fprintf(stderr, "%s: configuration accepted (--check: nothing run)\n", fp->tool);
    return 0;
  }
  if (!MakeOutputDirectories(fp->config, &fp->error)) return fp->RunError();
  // Each phase either continues or gives the exit code: nothing runs before all are done.
  using Phase = int (*)(FlightProcess*);
  for (const Phase phase :
       {&SetInitialState, &OpenSource, &Preallocate, &ConnectImu, &ConfigureLoop}) {
    if (const int code = phase(fp.get()); code != kContinue) return code;
  }
  RunRealTime(fp.get());
  return Report(fp.get());
}

}  // namespace swf::app
