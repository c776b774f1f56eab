// The configuration is refused before start with a message naming the field: bad files (empty, a
// directory, duplicate keys, NUL bytes, no `source`), settings the flown envelope cannot work with,
// capacities that cannot hold, and output paths that cannot be written.
#include "swf/app/config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "swf/app/app.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/sil/sil.hpp"
#include "swf/sim/rig.hpp"
#include "swf/testing/files.hpp"

namespace swf::app {
namespace {

bool Refused(const std::string& text, const std::string& expect_in_error) {
  FswConfig c;
  std::string error;
  const bool ok = ParseConfig(text, "t.cfg", &c, &error, sil::SimConfigExtension());
  EXPECT_FALSE(ok) << text.substr(0, 200);
  EXPECT_NE(error.find(expect_in_error), std::string::npos) << "error was: " << error;
  return !ok;
}

bool Accepted(const std::string& text, FswConfig* c = nullptr) {
  FswConfig local;
  std::string error;
  const bool ok =
      ParseConfig(text, "t.cfg", c != nullptr ? c : &local, &error, sil::SimConfigExtension());
  EXPECT_TRUE(ok) << error;
  return ok;
}

// The fsw/app directory of the source tree (config/, test/).
// fsw/app in the source tree. __FILE__ is relative to the build directory when ccache rewrites
// paths (CCACHE_BASEDIR); ctest runs the tests from the source root, where "fsw/app" is.
std::string AppDir() {
  const std::string here = __FILE__;  // .../fsw/app/test/config_test.cpp
  if (here.empty() || here[0] != '/') return "fsw/app";
  return here.substr(0, here.rfind("/test/"));
}

using swf::testing::Exists;
using swf::testing::ScratchDir;

// The demo's descent (demo.cfg) at the paper's 1024 x 768: f = 512 / tan(12.5 deg) = 2309.5 px, 1 m
// baseline, lowest altitude 10 m -> 230.9 px.
const std::string kDemo1024 =
    "source: sim\n"             // 1
    "sim.scenario: descent\n"   // 2
    "sim.width_px: 1024\n"      // 3
    "sim.height_px: 768\n"      // 4
    "sim.hfov_deg: 25\n"        // 5
    "sim.baseline_m: 1.0\n"     // 6
    "rate_hz: 10\n"             // 7
    "max_disparity_px: 160\n";  // 8

TEST(ConfigTest, ParsesEveryKindOfField) {
  FswConfig c;
  std::string error;
  ASSERT_TRUE(
      ParseConfig("# comment\nsource: sim\nwindow: 4   # K\nrate_hz: 12.5\n"
                  "pacing: lockstep\nrt.mlockall: false\ninitial.position_m: 1 2 3\n"
                  "sim.width_px: 320\nrecord.path: /tmp/x.lcmlog\n",
                  "t.cfg", &c, &error, sil::SimConfigExtension()))
      << error;
  EXPECT_EQ(c.window, 4);
  EXPECT_DOUBLE_EQ(c.rate_hz, 12.5);
  EXPECT_EQ(c.pacing, Pacing::kLockstep);
  EXPECT_FALSE(c.mlockall);
  EXPECT_DOUBLE_EQ(c.initial_position_m[2], 3.0);
  EXPECT_EQ(c.sim.width_px, 320);
  EXPECT_EQ(c.record_path, "/tmp/x.lcmlog");
  EXPECT_EQ(c.origins.keys.at("window"), "t.cfg:3");
}

TEST(ConfigTest, NamesTheFieldAndLineOfEveryProblem) {
  Refused("source: sim\nwindow: 40\n", "t.cfg:2: window: 40 is outside [1, ");
  Refused("source: sim\nrate_hz: fast\n", "t.cfg:2: rate_hz: 'fast' is not a finite number");
  Refused("source: sim\nrate_hz: 0\n", "rate_hz: 0 is outside");
  Refused("source: sim\nwidnow: 5\n", "t.cfg:2: widnow: unknown field");
  Refused("source: usb\n", "source: 'usb' is not one of sim v4l2 aravis log lcm");
  Refused("source: sim\nmode: batch\n", "mode: 'batch' is not one of");
  Refused("source: sim\nwindow\n", "t.cfg:2: expected 'key: value'");
  Refused("source: sim\n: 5\n", "t.cfg:2: expected 'key: value', got ': 5' (no key)");
  Refused("source: sim\nrt.mlockall: maybe\n", "rt.mlockall: 'maybe' is not true/false");
  Refused("source: sim\ninitial.position_m: 1 2\n", "initial.position_m:");
  Refused("source: sim\nsim.width_px: 5000\n", "sim.width_px: 5000 is outside");
  Refused("source: sim\nmeasurement_sigma_px: nan\n", "measurement_sigma_px:");
  Refused("source: sim\nsim.target: best\n", "sim.target: 'best' is not one of nominal orbital");
  Refused("source: sim\nsim.target_search_m: 70\n",
          "t.cfg:2: sim.target_search_m: 70 is outside [0, 60]");
  const std::string over = std::to_string(frontend::kMaxTracks + 1);
  Refused("source: sim\nmax_tracks: " + over + "\n",
          "t.cfg:2: max_tracks: " + over + " is outside [8, " +
              std::to_string(frontend::kMaxTracks) + "] (frontend::kMaxTracks");
  Refused("source: aravis\nenvelope.min_range_m: -1\n", "t.cfg:2: envelope.min_range_m: -1");
}

TEST(ConfigTest, RefusesInconsistentCombinationsAtTheLineOfTheField) {
  Refused("source: log\n", "t.cfg: log.path: required when source is log");
  Refused("source: v4l2\ninitial: position\n", "t.cfg: camera.left: required");
  Refused("source: aravis\ncamera.fake: true\ninitial: position\n",
          "t.cfg: camera.left_calibration: required");
  Refused("source: sim\nmode: ekf\nwindow: 3\n", "t.cfg:3: window: must be 1 in mode ekf");
  Refused(
      "source: v4l2\ncamera.left: /dev/video0\ncamera.right: /dev/video1\n"
      "camera.left_calibration: a.yaml\ncamera.right_calibration: b.yaml\n",
      "t.cfg: initial: 'truth' needs the simulator");
  Refused("source: sim\ninject.ms: 5\n", "t.cfg: inject.stage: required");
  Refused("source: sim\nsim.width_px: 256\nsim.width_px: 255\n",
          "t.cfg:3: sim.width_px: set again");
  Refused("source: sim\nsim.width_px: 255\n", "t.cfg:2: sim.width_px: must be even");
  Refused("source: sim\nsim.scenario: hover\nsim.target: orbital\n",
          "t.cfg:3: sim.target: 'orbital' selects a descent");
  Refused("source: sim\nenvelope.min_range_m: 5\n",
          "t.cfg:2: envelope.min_range_m: only for camera and log sources");
  Refused(
      "source: sim\nmeasurement_sigma_per_magnification_rad: 1e-4\n"
      "frontend.reference_from_estimate: false\n",
      "t.cfg:2: measurement_sigma_per_magnification_rad: needs "
      "frontend.reference_from_estimate: true");
  Refused("source: sim\nmeasurement_track_error: shared\n",
          "t.cfg:2: measurement_track_error: shared: needs "
          "measurement_sigma_per_magnification_px or _rad > 0");
  Refused(
      "source: sim\nmeasurement_sigma_per_magnification_px: 0.1\n"
      "frontend.reference_from_estimate: false\n",
      "t.cfg:2: measurement_sigma_per_magnification_px: needs "
      "frontend.reference_from_estimate: true");
}

// source: lcm: raw pairs published on a channel by a camera process; the calibrations give their
// size and the pipeline rectifies them.
TEST(ConfigTest, LcmSourceKeysAndTheirRefusals) {
  const std::string base =
      "source: lcm\ninitial: position\ncamera.left_calibration: l.yaml\n"
      "camera.right_calibration: r.yaml\n";  // lines 1-4
  FswConfig c;
  ASSERT_TRUE(Accepted(base + "lcm_source.channel: CAM_STEREO\nlcm_source.buffers: 8\n", &c));
  EXPECT_EQ(c.source, SourceKind::kLcm);
  EXPECT_STREQ(SourceName(c.source), "lcm");
  EXPECT_EQ(c.lcm_source.channel, "CAM_STEREO");
  EXPECT_EQ(c.lcm_source.buffers, 8);
  EXPECT_EQ(c.lcm_source.url, "");  // the outputs' bus, lcm.url
  ASSERT_TRUE(
      Accepted(base + "lcm_source.channel: C\nlcm_source.url: udpm://239.1.2.3:7667\n", &c));
  EXPECT_EQ(c.lcm_source.url, "udpm://239.1.2.3:7667");

  Refused(base, "t.cfg: lcm_source.channel: required when source is lcm");
  Refused(base + "lcm_source.channel: C\nlcm_source.buffers: 1\n",
          "t.cfg:6: lcm_source.buffers: 1 is outside [2, 16]");
  Refused(base + "lcm_source.channel: C\nlcm_source.buffers: 17\n",
          "t.cfg:6: lcm_source.buffers: 17 is outside [2, 16]");
  // Its own outputs are not frames.
  Refused(base + "lcm_source.channel: SWF_NAV\n",
          "t.cfg:5: lcm_source.channel: 'SWF_NAV' is this process's own output channel");
  Refused(base + "lcm.channel_prefix: X_\nlcm_source.channel: X_HEALTH\n",
          "t.cfg:6: lcm_source.channel: 'X_HEALTH' is this process's own output channel");
  Refused(base + "lcm_source.channel: C\ncamera.left: /dev/video0\n",
          "t.cfg:6: camera.left: not for source lcm");
  Refused(base + "lcm_source.channel: C\ncamera.fake: true\n",
          "t.cfg:6: camera.fake: not for source lcm");
  Refused("source: lcm\ninitial: position\nlcm_source.channel: C\n",
          "t.cfg: camera.left_calibration: required");
  Refused(
      "source: lcm\nlcm_source.channel: C\ncamera.left_calibration: l.yaml\n"
      "camera.right_calibration: r.yaml\n",
      "t.cfg: initial: 'truth' needs the simulator");
  Refused("source: log\nlog.path: x.lcmlog\nlcm_source.channel: C\n",
          "t.cfg:3: lcm_source.channel: only for source lcm");
  Refused("source: sim\nlcm_source.buffers: 4\n",
          "t.cfg:2: lcm_source.buffers: only for source lcm");
}

// The stereo-inertial keys: the simulator's unit, the IMU's parameters for camera sources, and
// the combinations that cannot fly.
TEST(ConfigTest, ImuKeysParseAndBadOnesAreRefusedNamingTheField) {
  FswConfig c;
  ASSERT_TRUE(Accepted(
      "source: sim\nsim.imu_unit: tactical\nimu.enabled: true\nimu.camera_t_imu_m: 0.1, -0.2, 0.3\n"
      "imu.camera_r_imu_rad: 0 0 1.5\nimu.initial_velocity_mps: 0 0 -10\nimu.rate_hz: 400\n"
      "imu.gyro_noise_density: 2e-5\nimu.channel: LANDER_IMU\nimu.velocity_sigma_mps: 0.02\n",
      &c));
  EXPECT_TRUE(c.imu.enabled);
  EXPECT_EQ(c.sim.imu_unit, "tactical");
  EXPECT_EQ(c.imu.camera_t_imu_m[1], -0.2);
  EXPECT_EQ(c.imu.camera_r_imu_rad[2], 1.5);
  EXPECT_EQ(c.imu.initial_velocity_mps[2], -10.0);
  EXPECT_EQ(c.imu.rate_hz, 400.0);
  EXPECT_EQ(c.imu.gyro_noise_density, 2e-5);
  EXPECT_EQ(c.imu.channel, "LANDER_IMU");
  EXPECT_EQ(c.imu.velocity_sigma_mps, 0.02);
  Refused("source: sim\nimu.enabled: true\n",
          "t.cfg:2: imu.enabled: the simulator carries no IMU: set sim.imu_unit");
  Refused("source: sim\nsim.imu_unit: consumer\n",
          "t.cfg:2: sim.imu_unit: 'consumer' is not one of");
  Refused("source: sim\nimu.camera_t_imu_m: 1 2\n",
          "t.cfg:2: imu.camera_t_imu_m: '1 2' is not 3 finite numbers (x y z)");
  Refused("source: sim\nimu.gyro_noise_density: -1\n",
          "t.cfg:2: imu.gyro_noise_density: -1 is outside");
  Refused("source: sim\nimu.initial_velocity_mps: 0 nan 0\n", "t.cfg:2: imu.initial_velocity_mps:");
  Refused("source: log\nlog.path: x.lcmlog\nimu.enabled: true\nimu.rate_hz: 1\n",
          "imu.rate_hz: must be at least 10 Hz");
  Refused("source: log\nlog.path: x.lcmlog\nimu.enabled: true\nimu.velocity_sigma_mps: 0\n",
          "imu.velocity_sigma_mps: must be positive");
}

// The dispersions of the simulated flight (a Monte Carlo campaign's --set keys): every key parses,
// its defaults are the simulator's own (the nominal flight, bit for bit), and a bad value or an
// inconsistent combination is refused at the line that set it.
TEST(ConfigTest, DispersionKeysParseAndBadOnesAreRefusedNamingTheField) {
  FswConfig c;
  ASSERT_TRUE(Accepted(
      "source: sim\nsim.start_altitude_m: 80\nsim.end_altitude_m: 20\nsim.descent_rate_mps: 6\n"
      "sim.horizontal_velocity_mps: 1.5, -2\nsim.attitude_deg: 3 -2 45\n"
      "sim.attitude_rate_dps: 0.5, -0.25, 1\nsim.sun_elevation_deg: 12\nsim.sun_azimuth_deg: -30\n"
      "sim.read_noise_e: 30\nsim.e_per_dn: 20\nsim.exposure_dn: 80\nsim.baseline_error_m: -0.01\n"
      "sim.relative_rotation_error_rad: 0.001 -0.002 0.0005\nsim.frame_drop_probability: 0.05\n"
      "sim.timestamp_jitter_ms: 2\n",
      &c));
  EXPECT_EQ(c.sim.start_altitude_m, 80.0);
  EXPECT_EQ(c.sim.end_altitude_m, 20.0);
  EXPECT_EQ(c.sim.descent_rate_mps, 6.0);
  EXPECT_EQ(c.sim.horizontal_velocity_mps[1], -2.0);
  EXPECT_EQ(c.sim.attitude_deg[2], 45.0);
  EXPECT_EQ(c.sim.attitude_rate_dps[1], -0.25);
  EXPECT_EQ(c.sim.sun_elevation_deg, 12.0);
  EXPECT_EQ(c.sim.sun_azimuth_deg, -30.0);
  EXPECT_EQ(c.sim.read_noise_e, 30.0);
  EXPECT_EQ(c.sim.e_per_dn, 20.0);
  EXPECT_EQ(c.sim.exposure_dn, 80.0);
  EXPECT_EQ(c.sim.baseline_error_m, -0.01);
  EXPECT_EQ(c.sim.relative_rotation_error_rad[1], -0.002);
  EXPECT_EQ(c.sim.frame_drop_probability, 0.05);
  EXPECT_EQ(c.sim.timestamp_jitter_ms, 2.0);
  EXPECT_EQ(c.origins.keys.at("sim.timestamp_jitter_ms"), "t.cfg:16");

  // The defaults are the simulator's own.
  const SimConfig nominal;
  const sim::AppearanceOptions look;
  const sim::RenderOptions camera;
  const sim::TrajectoryOptions descent = sim::DescentTrajectory(10.0);
  EXPECT_EQ(nominal.sun_elevation_deg, look.sun_elevation_deg);
  EXPECT_EQ(nominal.sun_azimuth_deg, look.sun_azimuth_deg);
  EXPECT_EQ(nominal.read_noise_e, camera.read_noise_e);
  EXPECT_EQ(nominal.e_per_dn, camera.electrons_per_dn);
  EXPECT_EQ(nominal.exposure_dn, camera.exposure_dn);
  EXPECT_EQ(nominal.start_altitude_m, descent.start_world_m.z());
  EXPECT_EQ(-nominal.descent_rate_mps, descent.velocity_world_mps.z());

  // Each value's own range.
  Refused("source: sim\nsim.start_altitude_m: 0\n",
          "t.cfg:2: sim.start_altitude_m: 0 is outside (0, 1000]");
  Refused("source: sim\nsim.end_altitude_m: -5\n", "t.cfg:2: sim.end_altitude_m: -5 is outside");
  Refused("source: sim\nsim.descent_rate_mps: fast\n",
          "t.cfg:2: sim.descent_rate_mps: 'fast' is not a finite number");
  Refused("source: sim\nsim.horizontal_velocity_mps: 1\n",
          "t.cfg:2: sim.horizontal_velocity_mps: '1' is not 2 finite numbers (vx, vy)");
  Refused("source: sim\nsim.attitude_deg: 1 2 3 4\n",
          "t.cfg:2: sim.attitude_deg: '1 2 3 4' is not 3 finite numbers (roll, pitch, yaw)");
  Refused("source: sim\nsim.attitude_rate_dps: 0 0 200\n",
          "t.cfg:2: sim.attitude_rate_dps: 0 0 200: 200 is outside [-100, 100]");
  Refused("source: sim\nsim.sun_elevation_deg: 0\n",
          "t.cfg:2: sim.sun_elevation_deg: 0 is outside (0, 90]");
  Refused("source: sim\nsim.sun_azimuth_deg: inf\n", "t.cfg:2: sim.sun_azimuth_deg: 'inf' is not");
  Refused("source: sim\nsim.read_noise_e: -1\n", "t.cfg:2: sim.read_noise_e: -1 is outside [0, ");
  Refused("source: sim\nsim.e_per_dn: 0\n", "t.cfg:2: sim.e_per_dn: 0 is outside (0, ");
  Refused("source: sim\nsim.exposure_dn: 0\n", "t.cfg:2: sim.exposure_dn: 0 is outside (0, 1000]");
  Refused("source: sim\nsim.baseline_error_m: 1e9\n",
          "t.cfg:2: sim.baseline_error_m: 1e9 is outside");
  Refused("source: sim\nsim.relative_rotation_error_rad: 0 0.2 0\n",
          "t.cfg:2: sim.relative_rotation_error_rad: 0 0.2 0: 0.2 is outside [-0.1, 0.1]");
  Refused("source: sim\nsim.frame_drop_probability: 1\n",
          "t.cfg:2: sim.frame_drop_probability: 1 is outside [0, 1)");
  Refused("source: sim\nsim.timestamp_jitter_ms: nan\n", "t.cfg:2: sim.timestamp_jitter_ms: 'nan'");

  // Combinations, at the line of the key to change.
  Refused("source: sim\nsim.end_altitude_m: 100\n",
          "t.cfg:2: sim.end_altitude_m: 100.00 m end altitude is not below the 100.00 m start");
  Refused("source: sim\nsim.start_altitude_m: 5\n",
          "t.cfg:2: sim.start_altitude_m: 10.00 m end altitude is not below the 5.00 m start");
  Refused("source: sim\nsim.scenario: hover\nsim.attitude_deg: 0 5 0\n",
          "t.cfg:3: sim.attitude_deg: shapes the descent: needs sim.scenario descent");
  Refused("source: sim\nsim.descent_rate_mps: 0.001\n",
          "t.cfg:2: sim.descent_rate_mps: 90.0 m at 0.001 m/s and rate_hz 10.0 is 900000 frames");
  Refused("source: sim\nsim.baseline_error_m: -1\n",
          "t.cfg:2: sim.baseline_error_m: leaves no baseline (sim.baseline_m 1.000 m)");
  Accepted("source: sim\nsim.timestamp_jitter_ms: 10\n");  // a tenth of 100 ms
  Refused("source: sim\nsim.timestamp_jitter_ms: 10.5\n",
          "t.cfg:2: sim.timestamp_jitter_ms: 10.500 ms is above a tenth of the frame period");
  Refused("source: sim\nsim.attitude_deg: 70 0 0\n",
          "t.cfg:2: sim.attitude_deg: tilts the camera 70.0 deg off nadir during the descent");
  // 10 deg/s of pitch for the 9 s descent: 90 deg by the end.
  Refused("source: sim\nsim.attitude_rate_dps: 0 10 0\n",
          "t.cfg:2: sim.attitude_rate_dps: tilts the camera 90.0 deg off nadir");
}

// The flown envelope of a dispersed descent: the end altitude, the true baseline, the image
// corner a tilted camera sees closest and the right image's shift by a rotation error all enter
// the disparity the front end must find.
TEST(ConfigTest, TheEnvelopeIsTheDispersedDescents) {
  // The demo at 512 px: f 1154.7 px, 1 m, 10 m: 115.5 px.
  const std::string demo512 =
      "source: sim\nsim.width_px: 512\nsim.height_px: 384\nrate_hz: 10\nmax_disparity_px: ";
  // Ending at 20 m halves it (57.7 px); ending at 5 m doubles it.
  Accepted(demo512 + "60\nsim.end_altitude_m: 20\n");
  Refused(
      demo512 + "58\nsim.end_altitude_m: 20\n",
      "t.cfg:5: max_disparity_px: 58 is below the disparity at the closest range flown, 57.7 px "
      "at 20.0 m (the lowest altitude of the sim.descent trajectory");
  Refused(demo512 + "160\nsim.end_altitude_m: 5\n", "230.9 px at 5.0 m");
  // The true baseline is the rig's plus its error.
  Refused(demo512 + "160\nsim.baseline_error_m: 0.5\n",
          "173.2 px at 10.0 m (the lowest altitude of the sim.descent trajectory; f 1154.7 px x "
          "baseline 1.500 m from sim.width_px 512, sim.hfov_deg 25, sim.baseline_m 1 + "
          "sim.baseline_error_m 0.5)");
  // Rolled 9.4 deg (about the half field of view along the image's height), the image's edge
  // looks straight down from 10 m while the optical axis does not: 117.1 px, not 115.5.
  Accepted(demo512 + "117\n");
  Refused(
      demo512 + "117\nsim.attitude_deg: 9.4, 0, 0\n",
      "117.1 px at 9.9 m (the closest datum depth in view over the tilted sim.descent trajectory");
  // 20 mrad about the right camera's y moves the right image by f x 0.02 = 23.1 px.
  Accepted(demo512 + "160\nsim.relative_rotation_error_rad: 0 0.02 0\n");
  Refused(demo512 + "130\nsim.relative_rotation_error_rad: 0 0.02 0\n",
          "138.6 px at 10.0 m (the lowest altitude of the sim.descent trajectory; f 1154.7 px x "
          "baseline 1.000 m from sim.width_px 512, sim.hfov_deg 25, sim.baseline_m 1 + 23.1 px of "
          "sim.relative_rotation_error_rad)");
}

// ---- A: files that must not fly --------------------------------------------------------------

TEST(ConfigTest, RefusesAnEmptyOrCommentsOnlyFile) {
  Refused("", "t.cfg: no settings (the file is empty or only comments)");
  Refused("# nothing\n\n   # but comments\n\t\n", "t.cfg: no settings");
  ScratchDir dir;
  FswConfig c;
  std::string error;
  EXPECT_FALSE(LoadConfig(dir.Write("empty.cfg", ""), &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("empty.cfg: no settings"), std::string::npos) << error;
}

TEST(ConfigTest, RefusesADirectoryADeviceAndAHugeFile) {
  ScratchDir dir;
  FswConfig c;
  std::string error;
  EXPECT_FALSE(LoadConfig(dir.Path(), &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find(dir.Path() + ": is a directory"), std::string::npos) << error;
  EXPECT_FALSE(LoadConfig("/dev/null", &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("/dev/null: is not a regular file"), std::string::npos) << error;
  const std::string big = dir.Write("big.cfg", "source: sim\n" + std::string(kMaxConfigBytes, '#'));
  EXPECT_FALSE(LoadConfig(big, &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("larger than the 1048576"), std::string::npos) << error;
  EXPECT_FALSE(LoadConfig("/nonexistent/x.cfg", &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("/nonexistent/x.cfg: cannot open"), std::string::npos) << error;
}

TEST(ConfigTest, RequiresSource) {
  Refused("window: 5\nmode: swf\n", "t.cfg: source: required (sim, v4l2, aravis or log)");
  Accepted("source: sim\n");
}

TEST(ConfigTest, RefusesAKeySetTwiceInTheFile) {
  // The last one used to win silently: this flew the simulator.
  Refused("source: aravis\nwindow: 5\nsource: sim\n",
          "t.cfg:3: source: set again (first on t.cfg:1); a key is set once");
  Refused("source: sim\nwindow: 5\n  window : 5  # same value\n", "t.cfg:3: window: set again");
}

TEST(ConfigTest, RefusesNulAndControlBytes) {
  // std::string with an embedded NUL: `window: 5\0junk` used to read as window 5.
  const std::string nul("source: sim\nwindow: 5\0junk\n", 27);
  Refused(nul, "t.cfg:2: a NUL byte (0x00) at column 10: a configuration is text");
  Refused("source: sim\nsummary.path: /tmp/\x1b[2Jx\n", "t.cfg:2: a control byte (0x1b)");
  Refused(std::string("# \0\n", 4) + "source: sim\n", "t.cfg:1: a NUL byte");
  // Tabs and CRLF line ends are blanks, not refused.
  Accepted("source:\tsim\r\nwindow: 4\r\n");
}

TEST(ConfigTest, QuotesOnlyABoundedExcerptOfABadLine) {
  const std::string huge(10'000'000, 'x');
  for (const std::string& text :
       {"source: sim\nmode: " + huge + "\n", "source: sim\n" + huge + ": 1\n",
        "source: sim\n" + huge + "\n", "source: sim\nwindow: " + huge + "\n"}) {
    FswConfig c;
    std::string error;
    EXPECT_FALSE(ParseConfig(text, "t.cfg", &c, &error, sil::SimConfigExtension()));
    EXPECT_LT(error.size(), 200u) << error.substr(0, 300);
    EXPECT_NE(error.find("t.cfg:2: "), std::string::npos) << error.substr(0, 300);
    EXPECT_NE(error.find("... (10000"), std::string::npos) << error.substr(0, 300);
  }
  // Bytes outside printable ASCII are shown escaped.
  Refused("source: sim\nmode: \xff\xfe\n", "mode: '\\xff\\xfe' is not one of");
}

TEST(ConfigTest, OverridesAreCheckedLikeTheFile) {
  FswConfig c;
  std::string error;
  ASSERT_TRUE(
      ParseConfig("source: sim\nwindow: 5\n", "t.cfg", &c, &error, sil::SimConfigExtension()))
      << error;
  // Overriding a key the file sets is what --set is for: not a duplicate.
  EXPECT_TRUE(OverrideConfig("window: 3", &c, &error)) << error;
  EXPECT_EQ(c.window, 3);
  EXPECT_EQ(c.origins.keys.at("window"), "--set");
  EXPECT_FALSE(OverrideConfig("max_iterations: 0", &c, &error));
  EXPECT_NE(error.find("--set: max_iterations: 0 is outside"), std::string::npos) << error;
  EXPECT_EQ(c.max_iterations, 10);  // unchanged on refusal
  EXPECT_FALSE(OverrideConfig("window: 4", &c, &error));
  EXPECT_NE(error.find("--set: window: given twice on the command line"), std::string::npos)
      << error;
  EXPECT_FALSE(OverrideConfig("", &c, &error));
  EXPECT_NE(error.find("--set: expected 'key: value'"), std::string::npos) << error;
  EXPECT_FALSE(OverrideConfig(std::string("mode: swf\0x", 11), &c, &error));
  EXPECT_NE(error.find("--set: a NUL byte"), std::string::npos) << error;
  // A cross-field problem names the field's own origin: here the file's line.
  EXPECT_FALSE(OverrideConfig("mode: ekf", &c, &error));
  EXPECT_NE(error.find("--set: window: must be 1 in mode ekf"), std::string::npos) << error;
}

TEST(ConfigTest, LoadWithOverridesValidatesTheWholeOnceInAnyOrder) {
  ScratchDir dir;
  const std::string file =
      dir.Write("f.cfg", "source: sim\nmode: swf\nwindow: 5\nsummary.path: a.json\n");
  FswConfig c;
  std::string error;
  // The file's own keys may be overridden; together the overrides are consistent.
  ASSERT_TRUE(LoadConfig(file, {"mode: ekf", "window: 1", "summary.path: b.json"}, &c, &error,
                         sil::SimConfigExtension()))
      << error;
  EXPECT_EQ(c.mode, "ekf");
  EXPECT_EQ(c.window, 1);
  EXPECT_EQ(c.summary_path, "b.json");
  EXPECT_EQ(c.origins.keys.at("window"), "--set");
  EXPECT_EQ(c.origins.keys.at("source"), file + ":1");
  // One override at a time validates each step: the first of the same pair is refused.
  ASSERT_TRUE(LoadConfig(file, &c, &error, sil::SimConfigExtension())) << error;
  EXPECT_FALSE(OverrideConfig("mode: ekf", &c, &error));
  EXPECT_NE(error.find("f.cfg:3: window: must be 1 in mode ekf"), std::string::npos) << error;
  // Refusals from an override name --set; the same key twice on the command line is refused.
  EXPECT_FALSE(LoadConfig(file, {"window: 1", "window: 2"}, &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("--set: window: given twice on the command line"), std::string::npos)
      << error;
  EXPECT_FALSE(LoadConfig(file, {"mode: ekf", "window: 2"}, &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("--set: window: must be 1 in mode ekf"), std::string::npos) << error;
  EXPECT_FALSE(LoadConfig(file, {"rate_hz: -3"}, &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("--set: rate_hz: -3 is outside"), std::string::npos) << error;
  // The file is still checked like a file.
  const std::string dup = dir.Write("dup.cfg", "source: aravis\nsource: sim\n");
  EXPECT_FALSE(LoadConfig(dup, {"source: sim"}, &c, &error, sil::SimConfigExtension()));
  EXPECT_NE(error.find("dup.cfg:2: source: set again"), std::string::npos) << error;
}

TEST(ConfigTest, CommittedConfigurationsLoadAndFitTheirEnvelope) {
  for (const char* name : {"demo.cfg", "test.cfg"}) {
    FswConfig c;
    std::string error;
    EXPECT_TRUE(LoadConfig(AppDir() + "/config/" + name, &c, &error, sil::SimConfigExtension()))
        << name << ": " << error;
    const estimator::StereoCamera<double> camera = sim::MakeStereoCamera(sil::SimRig(c));
    EXPECT_TRUE(CheckEnvelopeDisparity(c, camera.fx, camera.baseline_m, c.sim.width_px, &error))
        << name << ": " << error;
  }
  FswConfig c;
  std::string error;
  EXPECT_TRUE(LoadConfig(AppDir() + "/config/fake_gv.cfg", &c, &error, sil::SimConfigExtension()))
      << error;
  // fake_gv_{left,right}.yaml: ideal pinholes, f 300 px, 0.2 m apart, 320 px wide.
  EXPECT_TRUE(CheckEnvelopeDisparity(c, 300.0, 0.2, 320, &error)) << error;
}

// The bench's camera settings (bench_gige.cfg): every key parsed, and each refusal names its key.
TEST(ConfigTest, GigECameraSettingsParseAndBadOnesAreRefusedNamingTheKey) {
  FswConfig c;
  std::string error;
  ASSERT_TRUE(LoadConfig(AppDir() + "/config/bench_gige.cfg", &c, &error)) << error;
  EXPECT_EQ(c.camera.left, "LEFT01");
  EXPECT_DOUBLE_EQ(c.camera.exposure_us, 4000.0);
  EXPECT_DOUBLE_EQ(c.camera.gain, 2.0);
  EXPECT_EQ(c.camera.packet_size, 1400);
  EXPECT_EQ(c.camera.trigger, "software");
  EXPECT_EQ(c.camera.roi_offset_px[0], 0);
  EXPECT_EQ(c.camera.features,
            (std::map<std::string, std::string>{{"BinningHorizontal", "1"}, {"GainAuto", "Off"}}));
  const std::string aravis = "source: aravis\ncamera.fake: true\n";
  const std::string calibrated =
      "source: aravis\ncamera.fake: true\ncamera.left_calibration: l.yaml\n"
      "camera.right_calibration: r.yaml\n";
  Refused(aravis + "camera.exposure_us: -5\n", "t.cfg:3: camera.exposure_us: -5 is outside");
  Refused(aravis + "camera.trigger: sometimes\n", "t.cfg:3: camera.trigger: 'sometimes'");
  Refused(aravis + "camera.roi_offset_px: 3\n", "t.cfg:3: camera.roi_offset_px: '3': expected two");
  Refused(aravis + "camera.packet_size: 70000\n", "t.cfg:3: camera.packet_size: 70000 is outside");
  Refused(aravis + "camera.feature.Gain Auto: Off\n", "t.cfg:3: camera.feature.Gain Auto: unknown");
  Refused(aravis + "camera.feature.GainAuto: Off Now\n",
          "t.cfg:3: camera.feature.GainAuto: 'Off Now': expected one word");
  Refused(calibrated + "camera.trigger: hardware\n",
          "t.cfg:5: camera.trigger: hardware: the fake cameras have no trigger line");
  Refused("source: log\nlog.path: x.lcmlog\ncamera.feature.GainAuto: Off\n",
          "t.cfg:3: camera.feature.GainAuto: only for source aravis");
  Refused("source: log\nlog.path: x.lcmlog\ncamera.packet_size: 1400\n",
          "t.cfg:3: camera.packet_size: only for source aravis");
}

// Runs the flight process as `program` with these arguments; returns its exit code.
int RunProgram(const Program& program, std::vector<std::string> args) {
  args.insert(args.begin(), program.tool);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return RunFlightProcess(static_cast<int>(argv.size()), argv.data(), program);
}

// --check: the configuration is validated as a run would (the file, every --set, the output
// paths) and the process exits 0 without running (no summary written), or 2 with the refusal.
TEST(ConfigTest, CheckValidatesAsARunWouldAndRunsNothing) {
  ScratchDir dir;
  const std::string config = AppDir() + "/config/test.cfg";
  const std::string summary = dir.Path() + "/summary.json";
  sil::SimulatedDescent descent;
  auto run = [&](std::vector<std::string> args) {
    return RunProgram({"swf-sil", false, &descent}, std::move(args));
  };
  EXPECT_EQ(run({"--config", config, "--set", "summary.path: " + summary, "--set",
                 "sim.frame_drop_probability: 0.1", "--check"}),
            0);
  EXPECT_FALSE(Exists(summary));  // a run writes it at its end
  EXPECT_EQ(run({"--check", "--config", config, "--set", "sim.attitude_deg: 80 0 0"}), 2);
  // A missing directory is created by a run, not by --check; one under a file is refused.
  EXPECT_EQ(
      run({"--config", config, "--set", "summary.path: " + dir.Path() + "/no/s.json", "--check"}),
      0);
  EXPECT_FALSE(Exists(dir.Path() + "/no"));
  EXPECT_EQ(run({"--config", config, "--set", "summary.path: " + config + "/s.json", "--check"}),
            2);
  EXPECT_EQ(run({"--config", dir.Path() + "/missing.cfg", "--check"}), 2);
  EXPECT_FALSE(Exists(summary));
}

// The flight binary (no extension) knows no simulator: source sim, a sim.* key and initial: truth
// are refused naming the line and the program that flies them.
TEST(ConfigTest, TheFlightBinaryRefusesTheSimulator) {
  FswConfig c;
  std::string error;
  EXPECT_FALSE(ParseConfig("source: sim\n", "f.cfg", &c, &error));
  EXPECT_NE(error.find("f.cfg:1: source: 'sim' is the simulated descent, flown by swf-sil"),
            std::string::npos)
      << error;
  EXPECT_FALSE(ParseConfig("source: log\nlog.path: x.lcmlog\nsim.seed: 3\n", "f.cfg", &c, &error));
  EXPECT_NE(error.find("f.cfg:3: sim.seed: unknown field (a simulator key: swf-sil flies"),
            std::string::npos)
      << error;
  EXPECT_FALSE(ParseConfig("source: log\nlog.path: x.lcmlog\n", "f.cfg", &c, &error));
  EXPECT_NE(error.find("f.cfg: initial: 'truth' is the simulator's"), std::string::npos) << error;
  EXPECT_TRUE(
      ParseConfig("source: log\nlog.path: x.lcmlog\ninitial: position\n", "f.cfg", &c, &error))
      << error;
  // The same file with the simulator's keys is swf-sil's.
  EXPECT_TRUE(
      ParseConfig("source: sim\nsim.seed: 3\n", "f.cfg", &c, &error, sil::SimConfigExtension()))
      << error;
  // And the flight binary says so when run.
  EXPECT_EQ(RunProgram({}, {"--config", AppDir() + "/config/test.cfg", "--check"}), 2);
}

// ---- output paths ------------------------------------------------------------------------------

TEST(ConfigTest, OutputPathsAreCheckedBeforeTheRun) {
  ScratchDir dir;
  const std::string& d = dir.Path();
  const std::string a_file = dir.Write("file", "x");
  FswConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig("source: sim\nsummary.path: " + d + "/s.json\nrecord.path: " + d +
                              "/r.lcmlog\nsummary.plot_dir: " + d + "\n",
                          "t.cfg", &c, &error, sil::SimConfigExtension()))
      << error;
  EXPECT_TRUE(CheckOutputPaths(c, &error)) << error;
  // Nothing is created by the check.
  EXPECT_FALSE(Exists(d + "/s.json"));
  EXPECT_FALSE(Exists(d + "/r.lcmlog"));
  // An existing file may be rewritten.
  c.summary_path = a_file;
  EXPECT_TRUE(CheckOutputPaths(c, &error)) << error;

  auto refused = [&](FswConfig bad, const std::string& expect) {
    std::string why;
    EXPECT_FALSE(CheckOutputPaths(bad, &why)) << expect;
    EXPECT_NE(why.find(expect), std::string::npos) << "error was: " << why;
  };
  // A directory that does not exist yet is accepted when it can be created (the run creates it,
  // docs/cli.md); the check creates nothing.
  FswConfig deep = c;
  deep.summary_path = d + "/missing/deeper/s.json";
  deep.plot_dir = d + "/plots";
  EXPECT_TRUE(CheckOutputPaths(deep, &error)) << error;
  EXPECT_FALSE(Exists(d + "/missing"));
  EXPECT_FALSE(Exists(d + "/plots"));
  ASSERT_TRUE(MakeOutputDirectories(deep, &error)) << error;
  EXPECT_TRUE(Exists(d + "/missing/deeper"));
  EXPECT_TRUE(Exists(d + "/plots"));
  FswConfig bad = c;
  bad.summary_path = d;
  refused(bad, "t.cfg:2: summary.path: '" + d + "' is a directory");
  bad = c;
  bad.record_path = a_file + "/r.lcmlog";
  refused(bad, "t.cfg:3: record.path: '" + a_file + "/r.lcmlog' its directory '" + a_file +
                   "' is not a directory");
  bad = c;
  bad.record_path = a_file + "/sub/r.lcmlog";
  refused(bad, "record.path: '" + a_file + "/sub/r.lcmlog' its directory: '" + a_file +
                   "' is not a directory");
  bad = c;
  bad.record_path = bad.summary_path;
  refused(bad, "record.path: '" + a_file + "' is also summary.path");
  bad = c;
  bad.plot_dir = a_file;
  refused(bad, "summary.plot_dir: '" + a_file + "' is not a directory");
  // A path given by --set is named as such.
  FswConfig over = c;
  ASSERT_TRUE(OverrideConfig("summary.path: " + a_file + "/s.json", &over, &error)) << error;
  refused(over, "--set: summary.path: '" + a_file + "/s.json' its directory '" + a_file + "'");
  // Permissions (meaningless for root, who may write anywhere on a writable file system).
  if (::geteuid() != 0) {
    const std::string ro = d + "/ro";
    ASSERT_EQ(::mkdir(ro.c_str(), 0555), 0);
    bad = c;
    bad.summary_path = ro + "/s.json";
    refused(bad, "summary.path: '" + ro + "/s.json' its directory '" + ro + "' cannot be written");
    bad.summary_path = ro + "/sub/s.json";
    refused(bad, "summary.path: '" + ro + "/sub/s.json' its directory: '" + ro +
                     "' cannot be written (to create '" + ro + "/sub' in it)");
  }
}

// ---- B: the flown envelope and the compiled capacities ----------------------------------------

TEST(ConfigTest, RefusesADisparitySearchBelowTheLowestAltitude) {
  // The case: 1024 x 768 with the demo's 160 px search, 230.9 px needed at 10 m.
  Refused(kDemo1024,
          "t.cfg:8: max_disparity_px: 160 is below the disparity at the closest range flown, "
          "230.9 px at 10.0 m (the lowest altitude of the sim.descent trajectory; f 2309.5 px x "
          "baseline 1.000 m from sim.width_px 1024, sim.hfov_deg 25, sim.baseline_m 1) + 1 px for "
          "the sub-pixel fit");
  std::string repaired = kDemo1024;
  repaired.replace(repaired.find("max_disparity_px: 160"), 21, "max_disparity_px: 240");
  Accepted(repaired);
  // At the demo's 512 px: 115.5 px; the demo's 160 holds, 116 does not (sub-pixel fit: +1 px).
  const std::string demo512 =
      "source: sim\nsim.width_px: 512\nsim.height_px: 384\nrate_hz: 10\nmax_disparity_px: ";
  Accepted(demo512 + "160\n");
  Accepted(demo512 + "117\n");
  Refused(demo512 + "116\n",
          "t.cfg:5: max_disparity_px: 116 is below the disparity at the "
          "closest range flown, 115.5 px at 10.0 m");
  // The default search (128) is named as the default.
  Refused("source: sim\nsim.width_px: 1024\nsim.height_px: 768\n",
          "t.cfg: max_disparity_px: 128 (the default) is below");
  // A shorter descent ends higher: 30 frames at 10 Hz stop at 71 m (32.5 px).
  Accepted(kDemo1024 + "sim.frames: 30\n");
  // The baseline and the field of view enter f x b.
  Refused(
      "source: sim\nsim.width_px: 512\nsim.height_px: 384\nsim.baseline_m: 1.5\n"
      "max_disparity_px: 160\n",
      "173.2 px at 10.0 m");
  Accepted(
      "source: sim\nsim.width_px: 1024\nsim.height_px: 768\nsim.hfov_deg: 45\n"
      "max_disparity_px: 160\n");  // f = 1236.1 px: 123.6 px
  // The orbital target moves the descent sideways only: the same check, without the terrain.
  Refused(
      "source: sim\nsim.target: orbital\nsim.width_px: 1024\nsim.height_px: 768\n"
      "max_disparity_px: 200\n",
      "230.9 px at 10.0 m");
  // Hover at 50 m: 46.2 px at 1024 px.
  Accepted(
      "source: sim\nsim.scenario: hover\nsim.width_px: 1024\nsim.height_px: 768\n"
      "max_disparity_px: 48\n");
  Refused(
      "source: sim\nsim.scenario: hover\nsim.width_px: 1024\nsim.height_px: 768\n"
      "max_disparity_px: 47\n",
      "46.2 px at 50.0 m (the lowest altitude of the sim.hover trajectory");
  // The lab scenario flies to 1 m; with the configured 1 m baseline no search can hold it.
  Refused("source: sim\nsim.scenario: lab\nmax_disparity_px: 250\n",
          "max_disparity_px: 250 is below the disparity at the closest range flown, 1154.7 px at "
          "1.0 m");
  // A search above half the image width is cut to it by the front end.
  Refused(
      "source: sim\nsim.width_px: 128\nsim.height_px: 96\nsim.hfov_deg: 10\n"
      "max_disparity_px: 100\n",
      "t.cfg:5: max_disparity_px: the front end searches at most half the image width (64 "
      "px), below the disparity at the closest range flown, 73.2 px at 10.0 m");
  // The file alone flies 1024 px with a 160 px search; an override repairs it, in any order.
  ScratchDir dir;
  const std::string file = dir.Write("demo.cfg", kDemo1024);
  FswConfig loaded;
  std::string why;
  EXPECT_FALSE(LoadConfig(file, &loaded, &why, sil::SimConfigExtension()));
  EXPECT_NE(why.find("demo.cfg:8: max_disparity_px: 160 is below"), std::string::npos) << why;
  EXPECT_TRUE(LoadConfig(file, {"max_disparity_px: 240"}, &loaded, &why, sil::SimConfigExtension()))
      << why;
  const std::string small = dir.Write(
      "small.cfg", "source: sim\nsim.width_px: 512\nsim.height_px: 384\nmax_disparity_px: 160\n");
  EXPECT_TRUE(LoadConfig(small,
                         {"sim.width_px: 1024", "sim.height_px: 768", "max_disparity_px: 240"},
                         &loaded, &why, sil::SimConfigExtension()))
      << why;
  EXPECT_FALSE(LoadConfig(small, {"sim.width_px: 1024", "max_disparity_px: 200"}, &loaded, &why,
                          sil::SimConfigExtension()));
  EXPECT_NE(why.find("--set: max_disparity_px: 200 is below the disparity"), std::string::npos)
      << why;
  // Overrides: named as --set.
  FswConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig(demo512 + "160\n", "t.cfg", &c, &error, sil::SimConfigExtension()))
      << error;
  EXPECT_FALSE(OverrideConfig("max_disparity_px: 100", &c, &error));
  EXPECT_NE(error.find("--set: max_disparity_px: 100 is below the disparity"), std::string::npos)
      << error;
}

TEST(ConfigTest, CameraSourcesNeedTheirClosestRangeToCheckTheSearch) {
  const std::string cameras =
      "source: aravis\ncamera.fake: true\ncamera.left_calibration: l.yaml\n"
      "camera.right_calibration: r.yaml\ninitial: position\nmax_disparity_px: 64\n";
  FswConfig c;
  std::string error;
  // The fake rig: f 300 px, baseline 0.2 m, 320 px wide.
  ASSERT_TRUE(ParseConfig(cameras, "cam.cfg", &c, &error, sil::SimConfigExtension())) << error;
  EXPECT_FALSE(CheckEnvelopeDisparity(c, 300.0, 0.2, 320, &error));
  EXPECT_NE(error.find("cam.cfg: envelope.min_range_m: required for a camera source"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("f x baseline = 60.0 px m"), std::string::npos) << error;

  ASSERT_TRUE(ParseConfig(cameras + "envelope.min_range_m: 10\n", "cam.cfg", &c, &error,
                          sil::SimConfigExtension()))
      << error;
  EXPECT_TRUE(CheckEnvelopeDisparity(c, 300.0, 0.2, 320, &error)) << error;  // 6 px
  ASSERT_TRUE(ParseConfig(cameras + "envelope.min_range_m: 0.5\n", "cam.cfg", &c, &error,
                          sil::SimConfigExtension()))
      << error;
  EXPECT_FALSE(CheckEnvelopeDisparity(c, 300.0, 0.2, 320, &error));  // 120 px
  EXPECT_NE(error.find("cam.cfg:6: max_disparity_px: 64 is below the disparity at the closest "
                       "range flown, 120.0 px at 0.5 m (envelope.min_range_m; f 300.0 px x "
                       "baseline 0.200 m from the rectified rig)"),
            std::string::npos)
      << error;
  ASSERT_TRUE(ParseConfig(cameras + "envelope.min_range_m: 2\n", "cam.cfg", &c, &error,
                          sil::SimConfigExtension()))
      << error;
  EXPECT_TRUE(CheckEnvelopeDisparity(c, 300.0, 0.2, 320, &error)) << error;  // 30 px
  EXPECT_FALSE(CheckEnvelopeDisparity(c, 300.0, 0.2, 50, &error));
  EXPECT_NE(error.find("at most half the image width (25 px), below the disparity at the closest "
                       "range flown, 30.0 px at 2.0 m"),
            std::string::npos)
      << error;

  // A replay without the key re-runs what was checked when it flew; with it, it is checked.
  FswConfig log = c;
  log.source = SourceKind::kLog;
  log.envelope_min_range_m = 0.0;
  EXPECT_TRUE(CheckEnvelopeDisparity(log, 300.0, 0.2, 320, &error)) << error;
  log.envelope_min_range_m = 0.5;  // 120 px
  EXPECT_FALSE(CheckEnvelopeDisparity(log, 300.0, 0.2, 320, &error));

  // The simulator's range is its trajectory's: the actual rig gives the same answer.
  ASSERT_TRUE(
      ParseConfig("source: sim\nsim.width_px: 512\nsim.height_px: 384\n"
                  "max_disparity_px: 160\n",
                  "sim.cfg", &c, &error, sil::SimConfigExtension()))
      << error;
  EXPECT_TRUE(CheckEnvelopeDisparity(c, 1154.7, 1.0, 512, &error)) << error;
  EXPECT_FALSE(CheckEnvelopeDisparity(c, 2309.5, 1.0, 1024, &error));
  EXPECT_NE(error.find("sim.cfg:4: max_disparity_px: 160 is below"), std::string::npos) << error;
}

TEST(ConfigTest, RefusesWindowsAndTracksTheCompiledCapacitiesCannotHold) {
  const std::string k = std::to_string(kMaxWindow);
  const std::string above = std::to_string(kMaxWindow + 1);
  Refused("source: sim\nwindow: " + above + "\n",
          "window: " + above + " is outside [1, " + k + "] (kMaxWindow");
  // window + 1 poses x max_tracks landmarks must fit in kMaxLandmarks (4096: at window 25, 157
  // tracks; the demo's 150 tracks fit every window).
  const int fit = kMaxLandmarks / (kMaxWindow + 1);
  const std::string at_k = "source: sim\nwindow: " + k + "\nmax_tracks: ";
  Accepted(at_k + std::to_string(fit) + "\n");
  Refused(at_k + std::to_string(fit + 1) + "\n",
          "t.cfg:3: max_tracks: " + std::to_string(fit + 1) + " with window " + k + " can keep (" +
              k + " + 1) x " + std::to_string(fit + 1) + " = " +
              std::to_string((kMaxWindow + 1) * (fit + 1)) +
              " landmarks active, above the compiled capacity kMaxLandmarks = " +
              std::to_string(kMaxLandmarks) + " (at most " + std::to_string(fit) +
              " tracks at window " + k + ")");
  // The defaults (window 5, 150 tracks) hold; at window 10 the limit is kMaxLandmarks / 11
  // (shown in mode vo, which keeps no prior to bound the tracks further).
  Accepted("source: sim\n");
  const int fit10 = kMaxLandmarks / 11;
  static_assert(kMaxLandmarks / 11 < static_cast<int>(frontend::kMaxTracks));
  Accepted("source: sim\nmode: vo\nwindow: 10\nmax_tracks: " + std::to_string(fit10) + "\n");
  Refused("source: sim\nmode: vo\nwindow: 10\nmax_tracks: " + std::to_string(fit10 + 1) + "\n",
          "t.cfg:4: max_tracks: " + std::to_string(fit10 + 1) + " with window 10");
  // VO's window of one holds every track count the front end allows.
  static_assert(2 * frontend::kMaxTracks <= static_cast<std::size_t>(kMaxLandmarks));
  Accepted("source: sim\nmode: vo\nwindow: 1\nmax_tracks: " + std::to_string(frontend::kMaxTracks) +
           "\n");
}

// Every track a marginalized pose shares with the window enters the prior (eqs. 8-10): a mode
// that marginalizes refuses more tracks than the prior holds, at any window.
TEST(ConfigTest, RefusesMoreTracksThanThePriorHolds) {
  const std::string p = std::to_string(kMaxPriorLandmarks);
  const std::string above = std::to_string(kMaxPriorLandmarks + 1);
  static_assert(kMaxPriorLandmarks >= 150, "the demo's and flight_gige's 150 tracks");
  static_assert(kMaxPriorLandmarks < static_cast<int>(frontend::kMaxTracks));
  for (const std::string mode : {"swf", "vsdf", "ekf"}) {
    const std::string head = "source: sim\nmode: " + mode + "\nwindow: 1\nmax_tracks: ";
    Accepted(head + p + "\n");
    Refused(head + above + "\n",
            "t.cfg:4: max_tracks: " + above +
                " tracks can all enter the prior when their pose is marginalized, above the "
                "compiled prior capacity kMaxPriorLandmarks = " +
                p + " (mode vo keeps no prior)");
  }
  Accepted("source: sim\nmode: vo\nwindow: 1\nmax_tracks: " + above + "\n");
}

// The held window (hold_depth_precision) grows to the compiled capacity whatever `window` says:
// the landmark bound is checked at kMaxWindow + 1 poses, and a hold that has no room above the
// window, or a mode that does not marginalize a window, is refused.
TEST(ConfigTest, HeldWindowIsCheckedAtTheCompiledCapacity) {
  const std::string k = std::to_string(kMaxWindow);
  const int fit = kMaxLandmarks / (kMaxWindow + 1);
  const std::string held = "source: sim\nhold_depth_precision: 0.005\nmax_tracks: ";
  Accepted(held + std::to_string(fit) + "\n");
  Refused(held + std::to_string(fit + 1) + "\n",
          "t.cfg:3: max_tracks: " + std::to_string(fit + 1) + " with kMaxWindow " + k +
              " (held: hold_depth_precision) can keep (" + k + " + 1) x " +
              std::to_string(fit + 1) + " = " + std::to_string((kMaxWindow + 1) * (fit + 1)) +
              " landmarks active, above the compiled capacity kMaxLandmarks = " +
              std::to_string(kMaxLandmarks) + " (at most " + std::to_string(fit) +
              " tracks at kMaxWindow " + k + " (held: hold_depth_precision))");
  // The same track count at the same window without the hold is the window's business only.
  const int fit10 = kMaxLandmarks / 11;
  static_assert(kMaxLandmarks / 11 > kMaxLandmarks / (kMaxWindow + 1));
  Accepted("source: sim\nmode: vo\nwindow: 10\nmax_tracks: " + std::to_string(fit10) + "\n");
  Refused("source: sim\nwindow: 10\nhold_depth_precision: 0.005\nmax_tracks: " +
              std::to_string(fit10) + "\n",
          "t.cfg:4: max_tracks: " + std::to_string(fit10) + " with kMaxWindow " + k);
  Refused("source: sim\nwindow: " + k + "\nhold_depth_precision: 0.005\nmax_tracks: 8\n",
          "t.cfg:3: hold_depth_precision: cannot hold a pose beyond window " + k +
              ": the compiled capacity kMaxWindow is " + k);
  Refused("source: sim\nmode: ekf\nwindow: 1\nhold_depth_precision: 0.005\nmax_tracks: 8\n",
          "t.cfg:4: hold_depth_precision: only in mode swf or vsdf");
  Refused("source: sim\nmode: vo\nhold_depth_precision: 0.005\nmax_tracks: 8\n",
          "t.cfg:3: hold_depth_precision: only in mode swf or vsdf");
  Accepted("source: sim\nmode: vsdf\nhold_depth_precision: 0.005\nmax_tracks: 8\n");
  // The VSDF's Schur term, whole blocks or the scalar diagonal, is the VSDF's alone.
  FswConfig diagonal;
  EXPECT_TRUE(Accepted("source: sim\nmode: vsdf\nvsdf.schur: diagonal\n", &diagonal));
  EXPECT_TRUE(diagonal.vsdf_scalar_diagonal);
  Accepted("source: sim\nvsdf.schur: block\n");
  Refused("source: sim\nmode: swf\nvsdf.schur: diagonal\n",
          "t.cfg:3: vsdf.schur: diagonal: only in mode vsdf");
  Refused("source: sim\nmode: vsdf\nvsdf.schur: scalar\n", "t.cfg:3: vsdf.schur: ");
  Refused("source: sim\nhold_depth_precision: 0.6\n",
          "t.cfg:2: hold_depth_precision: 0.6 is outside [0, 0.5]");
  Refused("source: sim\nhold_depth_precision: -0.01\n",
          "t.cfg:2: hold_depth_precision: -0.01 is outside [0, 0.5]");
}

}  // namespace
}  // namespace swf::app
