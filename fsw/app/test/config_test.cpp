// The configuration is refused before start with a message naming the field.
#include "swf/app/config.hpp"

#include <gtest/gtest.h>

namespace swf::app {
namespace {

bool Refused(const std::string& text, const std::string& expect_in_error) {
  FswConfig c;
  std::string error;
  const bool ok = ParseConfig(text, "t.cfg", &c, &error);
  EXPECT_FALSE(ok) << text;
  EXPECT_NE(error.find(expect_in_error), std::string::npos) << "error was: " << error;
  return !ok;
}

TEST(ConfigTest, ParsesEveryKindOfField) {
  FswConfig c;
  std::string error;
  ASSERT_TRUE(
      ParseConfig("# comment\nsource: sim\nwindow: 7   # K\nrate_hz: 12.5\n"
                  "pacing: lockstep\nrt.mlockall: false\ninitial.position_m: 1 2 3\n"
                  "sim.width_px: 320\nrecord.path: /tmp/x.lcmlog\n",
                  "t.cfg", &c, &error))
      << error;
  EXPECT_EQ(c.window, 7);
  EXPECT_DOUBLE_EQ(c.rate_hz, 12.5);
  EXPECT_EQ(c.pacing, Pacing::kLockstep);
  EXPECT_FALSE(c.mlockall);
  EXPECT_DOUBLE_EQ(c.initial_position_m[2], 3.0);
  EXPECT_EQ(c.sim.width_px, 320);
  EXPECT_EQ(c.record_path, "/tmp/x.lcmlog");
}

TEST(ConfigTest, NamesTheFieldAndLineOfEveryProblem) {
  Refused("window: 40\n", "t.cfg:1: window: 40 is outside [1, 10]");
  Refused("source: sim\nrate_hz: fast\n", "t.cfg:2: rate_hz: 'fast' is not a finite number");
  Refused("rate_hz: 0\n", "rate_hz: 0 is outside");
  Refused("widnow: 5\n", "t.cfg:1: widnow: unknown field");
  Refused("source: usb\n", "source: 'usb' is not one of sim v4l2 aravis log");
  Refused("mode: batch\n", "mode: 'batch' is not one of");
  Refused("window\n", "t.cfg:1: expected 'key: value'");
  Refused("rt.mlockall: maybe\n", "rt.mlockall: 'maybe' is not true/false");
  Refused("initial.position_m: 1 2\n", "initial.position_m:");
  Refused("sim.width_px: 5000\n", "sim.width_px: 5000 is outside");
  Refused("measurement_sigma_px: nan\n", "measurement_sigma_px:");
  Refused("sim.target: best\n", "sim.target: 'best' is not one of nominal orbital");
  Refused("sim.target_search_m: 70\n", "t.cfg:1: sim.target_search_m: 70 is outside [0, 60]");
}

TEST(ConfigTest, RefusesInconsistentCombinations) {
  Refused("source: log\n", "log.path: required when source is log");
  Refused("source: v4l2\ninitial: position\n", "camera.left: required");
  Refused("source: aravis\ncamera.fake: true\ninitial: position\n",
          "camera.left_calibration: required");
  Refused("mode: ekf\nwindow: 3\n", "window: must be 1 in mode ekf");
  Refused(
      "source: v4l2\ncamera.left: /dev/video0\ncamera.right: /dev/video1\n"
      "camera.left_calibration: a.yaml\ncamera.right_calibration: b.yaml\n",
      "initial: 'truth' needs the simulator");
  Refused("inject.ms: 5\n", "inject.stage: required");
  Refused("sim.width_px: 255\n", "sim.width_px: must be even");
  Refused("sim.scenario: hover\nsim.target: orbital\n", "sim.target: 'orbital' selects a descent");
}

TEST(ConfigTest, OverridesAreCheckedLikeTheFile) {
  FswConfig c;
  std::string error;
  EXPECT_TRUE(OverrideConfig("window: 3", &c, &error)) << error;
  EXPECT_EQ(c.window, 3);
  EXPECT_FALSE(OverrideConfig("window: 0", &c, &error));
  EXPECT_NE(error.find("window"), std::string::npos);
  EXPECT_EQ(c.window, 3);  // unchanged on refusal
  EXPECT_FALSE(LoadConfig("/nonexistent/x.cfg", &c, &error));
  EXPECT_NE(error.find("/nonexistent/x.cfg"), std::string::npos);
}

}  // namespace
}  // namespace swf::app
