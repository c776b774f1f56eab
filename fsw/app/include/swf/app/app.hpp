// The flight process as a function: configuration -> source -> pipeline -> rate groups -> outputs
// -> verdict and summary. swf-fsw (the flight binary) runs it as it is; the ground programs built
// on it (tools/sil: swf-sil and swf-replay) add the simulated descent and its truth through a
// ProcessExtension. The mains only name the program.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "swf/app/hazard_stage.hpp"
#include "swf/app/imu_input.hpp"
#include "swf/app/lcm_io.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/core/status.hpp"
#include "swf/drivers/process_input.hpp"
#include "swf/drivers/stereo_source.hpp"

namespace swf::app {

struct FswConfig;        // config.hpp
struct ConfigExtension;  // config.hpp

// The flight process's preallocated parts around a source: the frame group's pipeline, the
// hazard stage, the output pools and the output thread (opened, not started). The observers,
// the rate groups and the source are the caller's. swf-fsw, swf-replay and the tests all build
// them with AssembleFlightParts.
struct FlightParts {
  std::unique_ptr<Pipeline> pipeline;
  std::unique_ptr<MapperHazardStage> hazard;
  std::unique_ptr<OutputChannels> channels;
  OutputThread output;
};

// Sizes everything from `po` (the hazard mapper's camera and image size, the pools and the
// output buffers) and allocates it all now. kInvalidArgument: the pipeline or the hazard mapper
// refused its options; kFull: out of memory; kIoError: the output (LCM, the log) did not open.
// `error` says which, for a "configuration refused:" or run-time error line.
core::Status AssembleFlightParts(const PipelineOptions& po,
                                 hazard::HazardMapperOptions hazard_options,
                                 OutputOptions output_options, FlightParts* parts,
                                 std::string* error);

// The configuration's front-end, filter and noise settings into `po` (whose width_px and
// height_px the source has already set); `nav_mode` gets nav_state_t's MODE_* for the filter
// mode. The one place the flight process, its tests and benchmarks take them from.
void ApplyEstimatorConfig(const FswConfig& config, PipelineOptions* po, std::int8_t* nav_mode);

// The stereo-inertial estimator's IMU options from the configuration (imu.*; the velocity at
// start: imu.initial_velocity_mps).
ImuOptions ImuOptionsFor(const FswConfig& config);

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
inline constexpr double kMaxLostFraction = 0.01;
inline constexpr double kMaxDegradedFraction = 0.10;
void Fail(Verdict* v, const std::string& reason);
void Degrade(Verdict* v, const std::string& reason);

// A JSON number, or null when not finite (JSON has no inf/nan).
std::string JsonNumber(double v);
// A JSON string: `s` in quotes, with quotes, backslashes and control characters escaped.
std::string JsonString(const std::string& s);

// The IMU of a stereo-inertial run: its stream's counts, the biases the filter ended with, what
// an LCM subscription lost, and (a ProcessExtension with truth) the unit's true biases.
struct ImuReport {
  ImuCounts counts;
  bool has_biases = false;
  estimator::ImuBiases<double> estimated;
  bool has_truth = false;
  estimator::ImuBiases<double> truth;
  double imu_only_pose_rms_m = 0.0;  // the unit alone from the same start (with truth)
  // The camera-IMU time offset at the end (the configured one, or the online estimate with its
  // 1-sigma and the intervals read).
  double time_offset_s = 0.0;
  bool time_offset_estimated = false;
  double time_offset_sigma_s = 0.0;
  long time_offset_readings = 0;
  bool has_lcm = false;  // the IMU came over LCM: what the subscription lost
  LcmImuCounters lcm;
};

// What a ground program built on the flight process adds to it: tools/sil's simulated descent
// (its configuration keys, its source, motion input and IMU, the truth-derived start) and the
// evaluation of the run against its truth. The flight binary has none. Called in this order.
class ProcessExtension {
 public:
  virtual ~ProcessExtension() = default;
  // Its configuration keys and checks (FswConfig::extension).
  virtual const ConfigExtension* Config() const = 0;
  // `source` is its source: builds and opens it. Sets po's camera and image size and, with
  // initial: truth, the initial pose and IMU options; `total_frames` for the progress display.
  virtual bool OpenSource(const FswConfig& config, bool progress, PipelineOptions* po,
                          std::unique_ptr<drivers::StereoSource>* source,
                          std::int64_t* total_frames, std::string* error) = 0;
  // Another source (a log of a simulated descent): the start from the configured simulation,
  // after the flight process's own (initial: truth: the descent's first pose; the IMU options of
  // its unit).
  virtual bool Start(const FswConfig& config, PipelineOptions* po, std::string* error) = 0;
  // The rig of a rectified log's frames (they carry no camera model): its recorder's, at the
  // log's image size.
  virtual estimator::StereoCamera<double> RectifiedRig(const FswConfig& config, int width_px,
                                                       int height_px) = 0;
  // Its motion input and IMU samples, when it opened the source (nullptr otherwise).
  virtual drivers::MotionProvider* Motion() = 0;
  virtual drivers::ImuProvider* Imu() = 0;
  // Observers of the published outputs it needs during the run (added to parts->output; the
  // parts are assembled).
  virtual void Observe(FlightParts* parts) = 0;
  // After the run (the pipeline idle, the outputs drained): the run against its truth. Adds its
  // findings to the verdict, the true biases to the IMU report (when `imu`), and prints nothing.
  virtual void Evaluate(const FswConfig& config, const FlightParts& parts,
                        const PipelineOptions& po, std::int64_t imu_samples_taken, Verdict* verdict,
                        ImuReport* imu) = 0;
  // Its part of the run line on stderr (", pose RMS error 0.031 m"); "" without truth.
  virtual std::string RunLine() const = 0;
  // Its members of the summary: after the run's settings, inside "integrity" (each member after
  // a ", "), and the published hazard maps against truth ("hazard", "hazard_by_map",
  // "safe_site"; false: it has none and the flight process writes them null).
  virtual void WriteSummaryHead(std::FILE* f) const = 0;
  virtual void WriteIntegrityTruth(std::FILE* f) const = 0;
  virtual bool WriteHazardTruth(std::FILE* f) const = 0;
};

// The program running the flight process: its name in messages, whether it replays a log
// (--log given; paced lockstep unless the config says otherwise, input frames not re-recorded)
// and its extension (nullptr: the flight binary).
struct Program {
  const char* tool = "swf-fsw";
  bool replay = false;
  ProcessExtension* extension = nullptr;
};

// Exit codes (swf::cli, docs/cli.md): 0 ok, 3 degraded, 1 failed or a run-time error (source,
// damaged log record), 2 bad command line or configuration; --help and --version exit 0.
int RunFlightProcess(int argc, char** argv, const Program& program);

}  // namespace swf::app
