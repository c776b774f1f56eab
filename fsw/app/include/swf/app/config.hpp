// The flight process's configuration file: one `key: value` per line, `#` starts a comment, dotted
// keys group settings (`sim.width_px: 512`). Every key is known and typed; the whole file is
// validated before anything starts, and the first problem is reported with the line and the field's
// name ("config.cfg:12: window: 40 is outside [1, 10]"). Unknown keys are errors, so a typo never
// silently falls back to a default; so are a key given twice, a file without settings or without
// `source`, NUL and other control bytes. Errors quote at most a bounded, printable excerpt of what
// was read. fsw/app/README.md lists every key.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "swf/app/config_fields.hpp"
#include "swf/app/flight_loop.hpp"
#include "swf/app/pipeline.hpp"

namespace swf::app {

enum class SourceKind : std::uint8_t { kSim, kV4l2, kAravis, kLog, kLcm };

struct SimConfig {
  std::string scenario = "descent";  // descent | hover | sideways | lab | lab_static
  std::string terrain = "craters";   // plains | craters | rocks
  std::int32_t width_px = 512;
  std::int32_t height_px = 384;
  double hfov_deg = 25.0;
  double baseline_m = 1.0;
  std::int32_t frames = 0;  // 0 = the whole scenario
  std::int32_t terrain_size = 2048;
  std::uint64_t seed = 1;
  std::string shared_dir;  // ../shared (or $SWF_SHARED_DIR) when empty
  std::int32_t render_threads = 2;
  // Descent target (scenario descent): "nominal" flies straight down over the origin; "orbital"
  // flies straight down over the point sim::SelectOrbitalTarget picks within target_search_m of
  // the origin from the terrain degraded to orbital resolution (the mission's pre-selection of
  // the landing target from orbital data, before descent).
  std::string target = "nominal";
  double target_search_m = 40.0;
  // The lander's IMU / navigation filter as the process-model input: true relative motion plus
  // white noise of these 1-sigma per frame (translation per axis, rotation per axis).
  bool imu = true;
  double imu_sigma_m = 0.02;
  double imu_sigma_rad = 0.0005;
  // The simulated strapdown IMU (sim/imu_model.hpp) riding on the trajectory: "mems" (Analog
  // Devices ADIS16448), "tactical" (Honeywell HG1700) or "none". Its samples feed the
  // stereo-inertial estimator (imu.enabled), which then takes the unit's parameters.
  std::string imu_unit = "none";
  // The simulated unit's clock against the cameras' (ms): it stamps an instant t as t + this
  // (a desynchronization for imu.estimate_time_offset to find).
  double imu_clock_offset_ms = 0.0;
  // The state guidance hands over with the first frame (initial: truth): "none" gives the true
  // pose and velocity; "drawn" adds an error drawn (seeded by sim.seed) from the sigmas the
  // estimator states for them (the first pose's 1 mm / 0.1 mrad, imu.velocity_sigma_mps), as a
  // real handover has: a Monte Carlo judges the filter's consistency only if its start is drawn
  // from the prior the filter states.
  std::string handover_error = "none";

  // Dispersions of the simulated flight (a Monte Carlo campaign sets them with --set). Every
  // default is the nominal flight, bit for bit.
  // Descent geometry (sim.scenario descent; sim/trajectory.hpp): from start to end altitude at
  // the descent rate, (start - end) / rate * rate_hz + 1 frames (both ends); a constant
  // horizontal velocity (world x east, y north); a constant attitude offset of the camera from
  // nadir, roll / pitch / yaw about the camera's x / y / z (optical) axes, and a constant body
  // rate in the camera frame that makes the offset grow linearly with time.
  double start_altitude_m = 100.0;
  double end_altitude_m = 10.0;
  double descent_rate_mps = 10.0;
  double horizontal_velocity_mps[2] = {0.0, 0.0};
  double attitude_deg[3] = {0.0, 0.0, 0.0};
  double attitude_rate_dps[3] = {0.0, 0.0, 0.0};
  // Illumination (sim::AppearanceOptions's defaults).
  double sun_elevation_deg = 30.0;
  double sun_azimuth_deg = 135.0;  // from +x (east) towards +y (north)
  // Camera photometry (sim::RenderOptions's defaults): read noise, gain, mean exposure.
  double read_noise_e = 15.0;
  double e_per_dn = 40.0;
  double exposure_dn = 110.0;
  // Calibration errors the estimator does not know (sim::RenderOptions): the true baseline is
  // baseline_m + baseline_error_m, the true right camera turned by this rotation vector in its
  // own frame; the pipeline keeps the calibrated rig (baseline_m, rectified).
  double baseline_error_m = 0.0;
  double relative_rotation_error_rad[3] = {0.0, 0.0, 0.0};
  // Camera timing faults of the simulated source (sim::PrerenderedStereoSource): each frame after
  // the first independently not delivered (a gap, pair.dropped_before), and Gaussian jitter of the
  // exposure stamps (1 sigma, truncated at 4 sigma); the images stay those of the true time.
  double frame_drop_probability = 0.0;
  double timestamp_jitter_ms = 0.0;
};

// The stereo-inertial estimator (PipelineOptions::imu) and its IMU. With the simulator's unit
// (sim.imu_unit, also when replaying a log of a sim run) rate, noise, ranges, bias sigmas and
// gravity are the unit's and the unit is mounted at camera_*_imu; otherwise (cameras: the IMU
// arrives as imu_t over LCM) all of these are as given.
struct ImuConfig {
  bool enabled = false;
  std::string channel;  // LCM channel of the IMU ("" = channel_prefix + "IMU")
  double rate_hz = 200.0;
  // imu_t over LCM: how long the frame group waits for the samples up to an exposure.
  double max_latency_ms = 20.0;
  // Continuous-time noise (Allan deviation of the datasheet; defaults: the ADIS16448 as EuRoC
  // calibrated it).
  double gyro_noise_density = 1.6968e-4;  // rad/s/sqrt(Hz)
  double gyro_random_walk = 1.9393e-5;    // rad/s^2/sqrt(Hz)
  double accel_noise_density = 2.0e-3;    // m/s^2/sqrt(Hz)
  double accel_random_walk = 3.0e-3;      // m/s^3/sqrt(Hz)
  double gyro_range_radps = 0.0;          // 0: trust the saturation flags only
  double accel_range_mps2 = 0.0;
  // The IMU in the left camera frame: position (m) and rotation vector (rad).
  double camera_t_imu_m[3] = {0.0, 0.0, 0.0};
  double camera_r_imu_rad[3] = {0.0, 0.0, 0.0};
  double gravity_mps2 = 1.625;  // along world -z (the Moon's surface gravity)
  // 1-sigma of the biases at start (they start at zero): the datasheet's turn-on bias.
  double gyro_bias_sigma_radps = 0.01;
  double accel_bias_sigma_mps2 = 0.1;
  // The IMU's velocity at the first frame, world frame (the state guidance hands over;
  // initial: truth in the simulator takes the true one).
  double initial_velocity_mps[3] = {0.0, 0.0, 0.0};
  // 1-sigma of that velocity per axis. It matters more than it looks: with a narrow field of
  // view and distant terrain a tilt rate (a gyroscope bias b) and a sideways velocity Z b (Z the
  // range) move the image alike, so until the range has shrunk the velocity's prior is what
  // separates the gyroscope bias from a drift (docs/imu.md, "Measured").
  double velocity_sigma_mps = 0.1;
  // The vehicle stands still before the first frame (on the pad, a parked rover): the samples up
  // to it give the gyroscope bias and level the attitude, the velocity starts at zero
  // (ImuOptions::static_start). An IMU cannot tell rest from constant velocity: set it only when
  // the vehicle is known to be at rest.
  bool static_start = false;
  // Camera-IMU time offset (ms): the IMU stamps an instant t as t + offset. The known one, and
  // whether to estimate it online from there (docs/imu.md, "Camera-IMU time offset"), held
  // within +-max_time_offset_ms.
  double time_offset_ms = 0.0;
  bool estimate_time_offset = false;
  double max_time_offset_ms = 50.0;
};

struct CameraConfig {
  std::string left;  // device path (v4l2) or camera id / address (aravis)
  std::string right;
  std::string left_calibration;  // YAML (EuRoC or ROS/OpenCV); raw images are rectified
  std::string right_calibration;
  bool fake = false;  // aravis: Aravis's in-process fake GigE cameras (tests, no hardware)
  // v4l2: requested pixel format (grey | y16 | yuyv), driver buffers per device, and the largest
  // kernel time-stamp difference of a left/right pair.
  std::string format = "grey";
  std::int32_t buffers = 4;
  double pair_tolerance_ms = 2.0;
  // aravis (GigE Vision): applied to both cameras when the source starts, in this order; a
  // setting the camera refuses stops the start with an error naming its key. Negative / 0 keep
  // the camera's own value. The region of interest's size is the calibrations'; roi_offset_px
  // places it on the sensor.
  double exposure_us = -1.0;
  double gain = -1.0;
  std::int32_t roi_offset_px[2] = {0, 0};
  std::int32_t packet_size = 0;  // GigE packet size, bytes (0: the largest the path allows)
  std::string trigger;           // free | software | hardware ("": software when fake, else free)
  std::string trigger_source = "Line1";  // the hardware trigger's input line
  // Any other GenICam feature: `camera.feature.<Name>: <value>` (one key each), applied last.
  std::map<std::string, std::string> features;
};

// source: lcm: raw stereo_frame_t pairs published live on an LCM channel (a camera process on
// another computer), received by drivers::LcmStereoSource; camera.*_calibration give their size
// and the pipeline rectifies them, as for an unrectified log.
struct LcmSourceConfig {
  std::string url;           // "" = lcm.url (the bus the outputs go to)
  std::string channel;       // required with source lcm
  std::int32_t buffers = 4;  // pairs the source's pool holds
};

// Where the settings came from, so that every error names the line to change: the file, and for
// each key given, "<file>:<line>" or "--set" (a command-line override). Keys left at their default
// are absent (their errors name the file alone).
struct ConfigOrigins {
  std::string file;
  std::map<std::string, std::string> keys;
  std::map<std::string, std::string>
      values;  // each given key's value as written (the summary's echo)
};

// What a program built on the flight process adds to its configuration: tools/sil's simulator
// (source sim, the sim.* and inject.black_* keys, the checks between them, and the closest range
// its trajectory flies). swf-fsw has none: its configuration refuses source sim and every sim.*
// key, and its SimConfig stays at the defaults.
struct ConfigExtension {
  const char* source = "";                                      // the source it serves ("sim")
  const std::map<std::string, ConfigSetter>* fields = nullptr;  // its keys
  // Checks across keys, after the flight process's own (ValidateConfig).
  bool (*validate)(const FswConfig& c, const std::string& origin, std::string* error) = nullptr;
  // CheckEnvelopeDisparity for its source: the disparity at the closest range it flies.
  bool (*envelope_fits)(const FswConfig& c, double fx_px, const std::string& origin,
                        std::string* error) = nullptr;
};

struct FswConfig {
  const ConfigExtension* extension = nullptr;  // the program's keys beyond the flight's (or none)
  SourceKind source = SourceKind::kSim;        // required in every file
  std::string log_path;                        // source: log
  LcmSourceConfig lcm_source;                  // source: lcm
  SimConfig sim;
  CameraConfig camera;
  ImuConfig imu;

  // Estimator.
  std::string mode = "swf";  // swf | ekf | vo | vsdf
  std::int32_t window = 5;
  std::int32_t max_iterations = 10;
  double measurement_sigma_px = 0.5;
  double measurement_sigma_per_magnification_px = 0.0;  // PipelineOptions, MeasurementSigmaPx
  double measurement_sigma_per_magnification_rad = 0.0;
  double measurement_disparity_sigma_px = 0.0;  // PipelineOptions, MeasurementNoiseOf
  double measurement_disparity_sigma_per_parallax_px = 0.0;
  bool measurement_track_error_shared = false;  // PipelineOptions::track_error_shared
  double min_quality = 0.7;
  double process_sigma_m = 0.5;
  double process_sigma_rad = 0.01;
  // The stereo calibration's uncertainty, 1-sigma (PipelineOptions::calibration_*): baseline
  // error and disparity bias (fx times a relative rotation about the camera y axis).
  double calibration_baseline_sigma_m = 0.0;
  double calibration_disparity_sigma_px = 0.0;
  std::int32_t max_tracks = 150;
  std::int32_t max_disparity_px = 128;
  // The held window (SwfOptions::hold_depth_precision): the oldest pose stays while it sees a
  // tracked landmark whose depth its stereo sightings know to worse than this relative 1-sigma,
  // up to the compiled capacity kMaxWindow. 0 = off (the fixed window of `window` poses).
  double hold_depth_precision = 0.0;
  // Mode vsdf: which part of the Schur term its marginalization applies (eq. 12), `vsdf.schur:
  // block` (the blocks within each variable, the default) or `diagonal` (only its scalar
  // diagonal, the paper's wording; SwfOptions::vsdf_scalar_diagonal).
  bool vsdf_scalar_diagonal = false;
  // The front end's paper 4.1 steps, each switchable to measure its effect (docs/frontend.md):
  // refinement in the loop (PipelineOptions::refine_in_loop), templates referenced to the
  // estimated pose so every track is warped, and the search that recovers lost tracks
  // (FrontendOptions::reference_from_estimate, recover_lost_tracks).
  bool frontend_refine_in_loop = true;
  bool frontend_reference_from_estimate = true;
  bool frontend_recover_lost_tracks = true;

  // Rate groups.
  double rate_hz = 10.0;
  Pacing pacing = Pacing::kRealtime;
  std::int32_t hazard_every = 5;
  std::int32_t hazard_max_disparities = 64;  // hazard mapper's SGM range (working resolution)
  std::int32_t hazard_downsample = 2;        // hazard mapper's image reduction: 1, 2 or 4
  std::int32_t health_every = 10;
  std::int64_t max_frames = 0;

  // Real time.
  bool mlockall = true;
  std::int32_t priority = 50;  // SCHED_FIFO of the frame group; hazard group one below
  std::int32_t cpu = -1;       // pin the frame group (-1: no pinning)

  // Outputs.
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";  // ttl=0: never leaves the host
  bool publish = true;
  std::string channel_prefix = "SWF_";
  std::string record_path;  // LCM log of every input frame and output ("" = none)
  bool record_frames = true;
  std::string summary_path;  // JSON summary (sim: errors against truth) ("" = none)
  std::string plot_dir;      // the run's plots (tools/plot; "" = none)

  // Camera and log sources: the closest range (metres along the optical axis; for a nadir rig the
  // lowest altitude above the ground) the flight reaches. With the rectified rig's f x baseline it
  // gives the largest disparity the front end must search (CheckEnvelopeDisparity). 0 = not given.
  // The simulator's comes from its trajectory.
  double envelope_min_range_m = 0.0;

  // Initial pose: "truth" (the simulator's first pose; sim and replays of sim logs) or
  // "position": x y z metres, camera pointing straight down (the navigation hand-over).
  std::string initial = "truth";
  double initial_position_m[3] = {0.0, 0.0, 100.0};

  // Fault injection (tests).
  std::string inject_stage;
  std::int64_t inject_frame = -1;
  std::int64_t inject_frames = 1;
  double inject_ms = 0.0;
  // The simulated camera blinded: frames [black_from, black_from + black_frames) are black pairs.
  std::int64_t inject_black_from = -1;
  std::int64_t inject_black_frames = 20;

  ConfigOrigins origins;
};

// Parses and validates. False with `error` = "<origin>:<line>: <field>: <problem>"; a problem
// between fields names the line of the field to change ("<origin>: <field>: ..." when that field
// was left at its default). `config` is untouched on refusal.
// `extension`: the program's keys and checks beyond the flight process's (nullptr: swf-fsw).
bool ParseConfig(const std::string& text, const std::string& origin, FswConfig* config,
                 std::string* error, const ConfigExtension* extension = nullptr);
// Reads `path` (a regular file of at most kMaxConfigBytes; a directory, a device or a larger file
// is refused) and parses it.
bool LoadConfig(const std::string& path, FswConfig* config, std::string* error,
                const ConfigExtension* extension = nullptr);
// The flown configuration: the file, then each `key: value` override in order (a key the file sets
// may be overridden; the same key twice among the overrides is refused), validated once as a whole,
// so that the order of the overrides does not matter and an override may repair a combination the
// file alone fails. Errors in an override read "--set: <field>: <problem>".
bool LoadConfig(const std::string& path, const std::vector<std::string>& overrides,
                FswConfig* config, std::string* error, const ConfigExtension* extension = nullptr);
// Applies one `key: value` override (command line) with the same checks, then re-validates the
// whole configuration (so a pair of overrides that only holds together must come in the order that
// keeps every step valid; LoadConfig with overrides has no such order).
bool OverrideConfig(const std::string& key_value, FswConfig* config, std::string* error);
// Cross-field consistency, including the flown envelope of the simulator (the disparity at the
// lowest altitude against max_disparity_px) and the compiled capacities. `origin` names the
// configuration when `config.origins.file` is empty. Pure: reads no file.
bool ValidateConfig(const FswConfig& config, const std::string& origin, std::string* error);

// The largest configuration file read (a configuration is a few hundred lines).
inline constexpr std::size_t kMaxConfigBytes = 1u << 20;

// Before the run: the front end's disparity search covers the closest range flown, for the rig the
// pipeline actually uses (`camera`: the rectified rig, f in px; `width_px`: its image width). The
// search is min(max_disparity_px, width_px / 2) (app.cpp FrontendFor). The closest range is the
// simulator's lowest altitude (source sim) or envelope.min_range_m (camera sources: required;
// source log: checked when given, otherwise the recorded flight was checked when it flew). False
// with "<where>: <field>: <problem>".
bool CheckEnvelopeDisparity(const FswConfig& config, double fx_px, double baseline_m, int width_px,
                            std::string* error);

// Before the run: every output can be written, so that a run is never lost to a path found bad only
// at its end. summary.path and record.path: an existing regular file this process may write, or a
// new file (not a directory, not the same file as the other); summary.plot_dir: a directory. A
// directory that does not exist yet is accepted when it can be created (its nearest existing
// ancestor is a directory this process may write): the run creates it (MakeOutputDirectories).
// Uses stat(2)/access(2) only: creates, truncates and deletes nothing. False with
// "<where>: <field>: <problem>".
bool CheckOutputPaths(const FswConfig& config, std::string* error);
// Creates the missing directories of summary.path, record.path and summary.plot_dir.
bool MakeOutputDirectories(const FswConfig& config, std::string* error);

const char* SourceName(SourceKind kind);
int StageIndex(const std::string& name);  // -1 when unknown

}  // namespace swf::app
