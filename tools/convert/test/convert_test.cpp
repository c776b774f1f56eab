// swf-convert's converters on the real data (EuRoC V1_01, the KITTI excerpt) and on broken
// inputs: each refusal names the file and record, and leaves no file behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "swf/calibration/calibration_import.hpp"
#include "swf/convert/convert.hpp"
#include "swf/drivers/log_stereo_source.hpp"
#include "swf/testing/shared_dir.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::convert {
namespace {

namespace fs = std::filesystem;

std::string Shared(const std::string& rel) { return swf::testing::SharedDir() + "/data/" + rel; }

std::string Temp(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/convert_test/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<swf_msgs::stereo_frame_t> Frames(const std::string& log) {
  std::vector<swf_msgs::stereo_frame_t> frames;
  std::string error;
  const auto decode = [&](const drivers::LogEvent& e) {
    if (e.channel != "SWF_STEREO") return true;
    frames.emplace_back();
    EXPECT_GT(frames.back().decode(e.data.data(), 0, static_cast<int>(e.data.size())), 0);
    return true;
  };
  EXPECT_TRUE(drivers::ForEachLogEvent(log, decode, &error)) << error;
  return frames;
}

// The first `frames` EuRoC V1_01 pairs with their IMU samples, converted into the log at `path`.
void ConvertEuroc(const std::string& path, int frames, InputSummary* summary) {
  LogInputOptions o;
  o.log_path = path;
  o.max_frames = frames;
  std::string error;
  ASSERT_TRUE(EurocToLog(Shared("euroc-v101"), o, summary, &error)) << error;
}

TEST(Convert, KittiExcerptBecomesARawLogWithItsRectifiedCalibration) {
  const std::string dir = Temp("kitti");
  LogInputOptions o;
  o.log_path = dir + "/kitti.lcmlog";
  o.calib_dir = dir + "/calib";
  o.max_frames = 5;
  InputSummary s;
  std::string error;
  ASSERT_TRUE(KittiToLog(Shared("kitti-odometry-excerpt"), o, &s, &error)) << error;
  EXPECT_EQ(s.frames, 5);
  EXPECT_EQ(s.truth_poses, 5);
  EXPECT_EQ(s.width, 1226);
  const auto frames = Frames(o.log_path);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_FALSE(frames[0].rectified);
  EXPECT_EQ(frames[4].seq, 4);
  calibration::StereoCalibration c;
  ASSERT_TRUE(calibration::ImportStereoCalibration(
      {o.calib_dir + "/left.yaml", o.calib_dir + "/right.yaml"}, {}, &c, &error))
      << error;
  calibration::RectifiedPair pair;
  ASSERT_TRUE(calibration::RectifyCalibration(c, &pair, &error)) << error;
  EXPECT_NEAR(pair.camera.fx, 707.0912, 1e-6);
  EXPECT_NEAR(pair.camera.baseline_m, 0.537, 0.001);
}

// EuRoC -> log -> PNG pairs (swf-grab's names) -> log: the same pixels, the IMU before its frame.
TEST(Convert, PngPairsOfALogConvertBackToTheSameFrames) {
  const std::string dir = Temp("pngs");
  const std::string euroc = dir + "/euroc.lcmlog";
  InputSummary s;
  ASSERT_NO_FATAL_FAILURE(ConvertEuroc(euroc, 3, &s));
  EXPECT_EQ(s.frames, 3);
  EXPECT_GT(s.imu_samples, 0);
  std::string error;
  std::int64_t pairs = 0;
  ASSERT_TRUE(LogToPngs(euroc, "SWF_STEREO", dir + "/pngs", &pairs, &error)) << error;
  EXPECT_EQ(pairs, 3);
  LogInputOptions g;
  g.log_path = dir + "/grab.lcmlog";
  ASSERT_TRUE(GrabToLog(dir + "/pngs", g, &s, &error)) << error;
  const auto a = Frames(euroc);
  const auto b = Frames(g.log_path);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].left, b[i].left);
    EXPECT_EQ(a[i].right, b[i].right);
    EXPECT_EQ(b[i].seq, static_cast<std::int64_t>(i));
  }
  // The log reader the replay uses serves every frame with the samples up to it.
  drivers::LogStereoSource source;
  source.SetImuChannel("SWF_IMU");
  ASSERT_TRUE(source.Load(euroc, "SWF_STEREO", &error)) << error;
  EXPECT_TRUE(source.LoadError().empty()) << source.LoadError();
  EXPECT_EQ(source.NumFrames(), 3u);
}

TEST(Convert, GrabFolderWithAMissingRightImageIsRefusedNamingIt) {
  const std::string dir = Temp("grab_missing");
  std::ofstream(dir + "/left_000007.png") << "x";
  LogInputOptions g;
  g.log_path = dir + "/out/grab.lcmlog";
  InputSummary s;
  std::string error;
  EXPECT_FALSE(GrabToLog(dir, g, &s, &error));
  EXPECT_NE(error.find("right_000007.png: missing"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(g.log_path));
  EXPECT_TRUE(fs::is_empty(dir + "/out"));  // no temporary file left either
  EXPECT_FALSE(GrabToLog(Temp("grab_empty"), g, &s, &error));
  EXPECT_NE(error.find("no left_NNNNNN.png"), std::string::npos) << error;
}

TEST(Convert, CutLogAndLogWithoutOutputsAreRefusedNamingTheRecord) {
  const std::string dir = Temp("cut");
  const std::string euroc = dir + "/euroc.lcmlog";
  InputSummary s;
  ASSERT_NO_FATAL_FAILURE(ConvertEuroc(euroc, 2, &s));
  std::string error;
  std::int64_t n = 0;
  EXPECT_FALSE(LogToTrajectory(euroc, "SWF_NAV", dir + "/t.txt", "", false, &n, &error));
  EXPECT_NE(error.find("no SWF_NAV records"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dir + "/t.txt"));
  fs::resize_file(euroc, fs::file_size(euroc) - 1000);
  EXPECT_FALSE(LogToPngs(euroc, "SWF_STEREO", dir + "/pngs", &n, &error));
  EXPECT_NE(error.find("record"), std::string::npos) << error;
  EXPECT_NE(error.find(euroc), std::string::npos) << error;
}

TEST(Convert, MissingDatasetIsRefusedNamingIt) {
  LogInputOptions o;
  o.log_path = Temp("missing") + "/x.lcmlog";
  InputSummary s;
  std::string error;
  EXPECT_FALSE(EurocToLog("/nonexistent/euroc", o, &s, &error));
  EXPECT_NE(error.find("/nonexistent/euroc"), std::string::npos) << error;
  EXPECT_FALSE(KittiToLog("/nonexistent/kitti", o, &s, &error));
  EXPECT_NE(error.find("/nonexistent/kitti"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(o.log_path));
}

}  // namespace
}  // namespace swf::convert
