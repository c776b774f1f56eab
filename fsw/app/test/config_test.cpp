// The configuration is refused before start with a message naming the field: bad files (empty, a
// directory, duplicate keys, NUL bytes, no `source`) and output paths that cannot be written.
#include "swf/app/config.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace swf::app {
namespace {

bool Refused(const std::string& text, const std::string& expect_in_error) {
  FswConfig c;
  std::string error;
  const bool ok = ParseConfig(text, "t.cfg", &c, &error);
  EXPECT_FALSE(ok) << text.substr(0, 200);
  EXPECT_NE(error.find(expect_in_error), std::string::npos) << "error was: " << error;
  return !ok;
}

bool Accepted(const std::string& text, FswConfig* c = nullptr) {
  FswConfig local;
  std::string error;
  const bool ok = ParseConfig(text, "t.cfg", c != nullptr ? c : &local, &error);
  EXPECT_TRUE(ok) << error;
  return ok;
}

// The fsw/app directory of the source tree (config/, test/).
std::string AppDir() {
  std::string here = __FILE__;  // .../fsw/app/test/config_test.cpp
  return here.substr(0, here.rfind("/test/"));
}

// A scratch directory removed at the end of the test.
class ScratchDir {
 public:
  ScratchDir() {
    char name[] = "/tmp/swf_config_test_XXXXXX";
    const char* made = ::mkdtemp(name);
    EXPECT_NE(made, nullptr);
    path_ = made != nullptr ? made : "/tmp";
  }
  ~ScratchDir() { (void)std::system(("rm -rf '" + path_ + "'").c_str()); }
  const std::string& Path() const { return path_; }
  std::string Write(const std::string& name, const std::string& text) const {
    const std::string file = path_ + "/" + name;
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

 private:
  std::string path_;
};

bool Exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

TEST(ConfigTest, ParsesEveryKindOfField) {
  FswConfig c;
  std::string error;
  ASSERT_TRUE(
      ParseConfig("# comment\nsource: sim\nwindow: 4   # K\nrate_hz: 12.5\n"
                  "pacing: lockstep\nrt.mlockall: false\ninitial.position_m: 1 2 3\n"
                  "sim.width_px: 320\nrecord.path: /tmp/x.lcmlog\n",
                  "t.cfg", &c, &error))
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
  Refused("source: usb\n", "source: 'usb' is not one of sim v4l2 aravis log");
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
}

// ---- A: files that must not fly --------------------------------------------------------------

TEST(ConfigTest, RefusesAnEmptyOrCommentsOnlyFile) {
  Refused("", "t.cfg: no settings (the file is empty or only comments)");
  Refused("# nothing\n\n   # but comments\n\t\n", "t.cfg: no settings");
  ScratchDir dir;
  FswConfig c;
  std::string error;
  EXPECT_FALSE(LoadConfig(dir.Write("empty.cfg", ""), &c, &error));
  EXPECT_NE(error.find("empty.cfg: no settings"), std::string::npos) << error;
}

TEST(ConfigTest, RefusesADirectoryADeviceAndAHugeFile) {
  ScratchDir dir;
  FswConfig c;
  std::string error;
  EXPECT_FALSE(LoadConfig(dir.Path(), &c, &error));
  EXPECT_NE(error.find(dir.Path() + ": is a directory"), std::string::npos) << error;
  EXPECT_FALSE(LoadConfig("/dev/null", &c, &error));
  EXPECT_NE(error.find("/dev/null: is not a regular file"), std::string::npos) << error;
  const std::string big = dir.Write("big.cfg", "source: sim\n" + std::string(kMaxConfigBytes, '#'));
  EXPECT_FALSE(LoadConfig(big, &c, &error));
  EXPECT_NE(error.find("larger than the 1048576"), std::string::npos) << error;
  EXPECT_FALSE(LoadConfig("/nonexistent/x.cfg", &c, &error));
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
    EXPECT_FALSE(ParseConfig(text, "t.cfg", &c, &error));
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
  ASSERT_TRUE(ParseConfig("source: sim\nwindow: 5\n", "t.cfg", &c, &error)) << error;
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
  ASSERT_TRUE(LoadConfig(file, {"mode: ekf", "window: 1", "summary.path: b.json"}, &c, &error))
      << error;
  EXPECT_EQ(c.mode, "ekf");
  EXPECT_EQ(c.window, 1);
  EXPECT_EQ(c.summary_path, "b.json");
  EXPECT_EQ(c.origins.keys.at("window"), "--set");
  EXPECT_EQ(c.origins.keys.at("source"), file + ":1");
  // One override at a time validates each step: the first of the same pair is refused.
  ASSERT_TRUE(LoadConfig(file, &c, &error)) << error;
  EXPECT_FALSE(OverrideConfig("mode: ekf", &c, &error));
  EXPECT_NE(error.find("f.cfg:3: window: must be 1 in mode ekf"), std::string::npos) << error;
  // Refusals from an override name --set; the same key twice on the command line is refused.
  EXPECT_FALSE(LoadConfig(file, {"window: 1", "window: 2"}, &c, &error));
  EXPECT_NE(error.find("--set: window: given twice on the command line"), std::string::npos)
      << error;
  EXPECT_FALSE(LoadConfig(file, {"mode: ekf", "window: 2"}, &c, &error));
  EXPECT_NE(error.find("--set: window: must be 1 in mode ekf"), std::string::npos) << error;
  EXPECT_FALSE(LoadConfig(file, {"rate_hz: -3"}, &c, &error));
  EXPECT_NE(error.find("--set: rate_hz: -3 is outside"), std::string::npos) << error;
  // The file is still checked like a file.
  const std::string dup = dir.Write("dup.cfg", "source: aravis\nsource: sim\n");
  EXPECT_FALSE(LoadConfig(dup, {"source: sim"}, &c, &error));
  EXPECT_NE(error.find("dup.cfg:2: source: set again"), std::string::npos) << error;
}

TEST(ConfigTest, CommittedConfigurationsLoad) {
  for (const char* name : {"demo.cfg", "test.cfg", "fake_gv.cfg"}) {
    FswConfig c;
    std::string error;
    EXPECT_TRUE(LoadConfig(AppDir() + "/config/" + name, &c, &error)) << name << ": " << error;
  }
}

// ---- output paths ------------------------------------------------------------------------------

TEST(ConfigTest, OutputPathsAreCheckedBeforeTheRun) {
  ScratchDir dir;
  const std::string d = dir.Path();
  const std::string a_file = dir.Write("file", "x");
  FswConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig("source: sim\nsummary.path: " + d + "/s.json\nrecord.path: " + d +
                              "/r.lcmlog\nsummary.plot_dir: " + d + "\n",
                          "t.cfg", &c, &error))
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
  FswConfig bad = c;
  bad.summary_path = d + "/missing/s.json";
  refused(bad, "t.cfg:2: summary.path: '" + d + "/missing/s.json' its directory '" + d +
                   "/missing' does not exist");
  bad = c;
  bad.summary_path = d;
  refused(bad, "t.cfg:2: summary.path: '" + d + "' is a directory");
  bad = c;
  bad.record_path = a_file + "/r.lcmlog";
  refused(bad,
          "t.cfg:3: record.path: '" + a_file + "/r.lcmlog' '" + a_file + "' is not a directory");
  bad = c;
  bad.record_path = bad.summary_path;
  refused(bad, "record.path: '" + a_file + "' is also summary.path");
  bad = c;
  bad.plot_dir = d + "/plots";
  refused(bad, "t.cfg:4: summary.plot_dir: '" + d + "/plots' does not exist");
  bad = c;
  bad.plot_dir = a_file;
  refused(bad, "summary.plot_dir: '" + a_file + "' is not a directory");
  // A path given by --set is named as such.
  FswConfig over = c;
  ASSERT_TRUE(OverrideConfig("summary.path: /nonexistent/s.json", &over, &error)) << error;
  refused(over,
          "--set: summary.path: '/nonexistent/s.json' its directory "
          "'/nonexistent'");
  // Permissions (meaningless for root, who may write anywhere on a writable file system).
  if (::geteuid() != 0) {
    const std::string ro = d + "/ro";
    ASSERT_EQ(::mkdir(ro.c_str(), 0555), 0);
    bad = c;
    bad.summary_path = ro + "/s.json";
    refused(bad, "summary.path: '" + ro + "/s.json' its directory '" + ro + "' cannot be written");
  }
}

}  // namespace
}  // namespace swf::app
