// EuRoC imu0 reader: the shared recording (ADIS16448, 200 Hz, the 40 frames of V1_01) reads with
// its calibration, passes the stream checker, bad rows are refused naming file:line, and the real
// gyroscope preintegrated between consecutive camera frames turns the body as the ground truth
// does once its bias is taken from the static start.
#include "euroc_imu.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "euroc.hpp"
#include "swf/estimator/imu_stream.hpp"
#include "swf/evaluation/statistics.hpp"
#include "swf/testing/shared_dir.hpp"

namespace swf::eval {
namespace {

using swf::testing::SharedDir;

using estimator::ImuSample;

std::string EurocDir() { return SharedDir() + "/data/euroc-v101"; }

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(EurocImu, ReadsTheSharedCalibration) {
  EurocImuCalibration c;
  std::string error;
  ASSERT_TRUE(ReadEurocImuCalibration(EurocDir() + "/mav0/imu0/sensor.yaml", &c, &error)) << error;
  EXPECT_DOUBLE_EQ(c.noise.gyro_noise_density, 1.6968e-04);
  EXPECT_DOUBLE_EQ(c.noise.gyro_random_walk, 1.9393e-05);
  EXPECT_DOUBLE_EQ(c.noise.accel_noise_density, 2.0e-3);
  EXPECT_DOUBLE_EQ(c.noise.accel_random_walk, 3.0e-3);
  EXPECT_DOUBLE_EQ(c.rate_hz, 200.0);
  EXPECT_TRUE(c.body_T_imu.R.isIdentity());
  EXPECT_TRUE(c.body_T_imu.t.isZero());
}

TEST(EurocImu, SharedSamplesAreACleanStream) {
  std::vector<ImuSample<double>> samples;
  std::string error;
  ASSERT_TRUE(ReadEurocImuSamples(EurocDir() + "/mav0/imu0/data.csv", &samples, &error)) << error;
  ASSERT_EQ(samples.size(), 391u);
  EXPECT_EQ(samples.front().t_us, 1403715273262143);
  EXPECT_NEAR(samples.front().accel_mps2.x(), 9.0874956666666655, 1e-12);
  estimator::ImuStreamChecker<double> checker;
  ASSERT_EQ(checker.Configure({5000, 3, 0.0, 0.0}), core::Status::kOk);
  for (const auto& s : samples) EXPECT_TRUE(estimator::IsAccepted(checker.Check(s)));
  EXPECT_EQ(checker.Counts().accepted, 391);
  EXPECT_EQ(checker.Counts().gaps, 0);
}

TEST(EurocImu, BadInputNamesFileAndLine) {
  const std::string header = "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n";
  const std::string good = "1000000,0.1,0.2,0.3,9.8,0.0,0.1\n";
  std::vector<ImuSample<double>> samples;
  std::string error;
  for (const std::string& bad : {std::string("2000000,0.1,0.2,0.3,9.8,0.0\n"),
                                 std::string("2000000,0.1,x,0.3,9.8,0.0,0.1\n"),
                                 std::string("2000000,0.1,0.2,0.3,9.8,0.0,nan\n"),
                                 std::string("2e6,0.1,0.2,0.3,9.8,0.0,0.1\n"),
                                 std::string("2000000,0.1,0.2,0.3,9.8,0.0,0.1,7\n")}) {
    const std::string path = WriteTemp("imu_bad.csv", header + good + bad);
    EXPECT_FALSE(ReadEurocImuSamples(path, &samples, &error)) << bad;
    EXPECT_NE(error.find(path + ":3:"), std::string::npos) << error;
  }
  EXPECT_FALSE(ReadEurocImuSamples(WriteTemp("imu_empty.csv", header), &samples, &error));
  EXPECT_FALSE(ReadEurocImuSamples("/nonexistent/data.csv", &samples, &error));

  std::ifstream in(EurocDir() + "/mav0/imu0/sensor.yaml");
  const std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EurocImuCalibration c;
  const auto replace = [&](const std::string& from, const std::string& to) {
    std::string text = yaml;
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };
  std::string path = WriteTemp("imu_bad.yaml", replace("1.6968e-04", "-1.6968e-04"));
  EXPECT_FALSE(ReadEurocImuCalibration(path, &c, &error));
  EXPECT_NE(error.find(path + ":17:"), std::string::npos) << error;
  path = WriteTemp("imu_bad.yaml", replace("accelerometer_random_walk", "accel_rw"));
  EXPECT_FALSE(ReadEurocImuCalibration(path, &c, &error));
  EXPECT_NE(error.find("accelerometer_random_walk"), std::string::npos) << error;
  path = WriteTemp("imu_bad.yaml", replace("0.0, 0.0, 0.0, 1.0]", "0.0, 0.0, 1.0]"));
  EXPECT_FALSE(ReadEurocImuCalibration(path, &c, &error));
  EXPECT_NE(error.find(path + ":10:"), std::string::npos) << error;
}

// Camera frame stamps (cam0/data.csv), microseconds.
std::vector<std::int64_t> FrameStamps() {
  std::ifstream in(EurocDir() + "/mav0/cam0/data.csv");
  std::vector<std::int64_t> stamps;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    stamps.push_back(NsToUs(std::stoll(line.substr(0, line.find(',')))));
  }
  return stamps;
}

// Per-frame rotation-increment error against the ground truth (the body frame is the IMU's).
std::vector<double> IncrementErrors(const std::vector<ImuSample<double>>& samples,
                                    const std::vector<std::int64_t>& frames,
                                    const std::vector<TumPose>& gt,
                                    const estimator::ImuBiases<double>& bias, std::size_t first) {
  std::vector<double> errors;
  for (std::size_t k = first; k + 1 < frames.size(); ++k) {
    estimator::ImuPreintegration<double> pim;
    EXPECT_EQ(pim.Reset(estimator::ImuNoise<double>{}, bias), core::Status::kOk);
    estimator::IntervalSummary summary;
    EXPECT_EQ(estimator::PreintegrateInterval(
                  samples.data(), static_cast<int>(samples.size()), frames[k], frames[k + 1],
                  estimator::SampleHold::kMidpoint, 0.0075, &pim, &summary),
              core::Status::kOk);
    EXPECT_EQ(summary.bridged_steps, 0);
    const Eigen::Matrix3d truth = gt[k].pose.R.transpose() * gt[k + 1].pose.R;
    errors.push_back(
        estimator::LogSO3<double>(Eigen::Matrix3d(truth.transpose() * pim.Increments().rotation))
            .norm());
  }
  return errors;
}

using evaluation::Rms;

// GIVEN the real ADIS16448 and the ground truth over the 40 shared frames (a static start)
// WHEN the gyroscope is preintegrated between consecutive frames, with zero bias and with the
//      bias taken as the mean rate over the first 20 frames (the static-start initialization;
//      the ground truth is not used for it)
// THEN over the last 19 frames the bias-corrected increments match the truth to the sensor's
//      noise level, and the uncorrected ones are off by the bias (~4 mrad per frame)
TEST(EurocImu, GyroIncrementsMatchGroundTruthAfterStaticStartBias) {
  std::vector<ImuSample<double>> samples;
  std::string error;
  ASSERT_TRUE(ReadEurocImuSamples(EurocDir() + "/mav0/imu0/data.csv", &samples, &error)) << error;
  std::vector<TumPose> gt;
  ASSERT_TRUE(ReadTum(EurocDir() + "/groundtruth_tum.txt", &gt, &error)) << error;
  const std::vector<std::int64_t> frames = FrameStamps();
  ASSERT_EQ(frames.size(), 40u);
  ASSERT_EQ(gt.size(), frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k)
    ASSERT_NEAR(gt[k].stamp_s * 1e6, static_cast<double>(frames[k]), 10.0) << k;

  estimator::ImuBiases<double> static_bias;
  int n = 0;
  for (const auto& s : samples) {
    if (s.t_us >= frames[19]) break;
    static_bias.gyro_radps += s.gyro_radps;
    ++n;
  }
  static_bias.gyro_radps /= n;
  const std::vector<double> raw = IncrementErrors(samples, frames, gt, {}, 20);
  const std::vector<double> corrected = IncrementErrors(samples, frames, gt, static_bias, 20);
  double truth_rms = 0.0;
  for (std::size_t k = 20; k + 1 < frames.size(); ++k) {
    const double angle =
        estimator::LogSO3<double>(Eigen::Matrix3d(gt[k].pose.R.transpose() * gt[k + 1].pose.R))
            .norm();
    truth_rms += angle * angle;
  }
  truth_rms = std::sqrt(truth_rms / 19.0);
  // One frame of the datasheet white noise: N sqrt(dt) per axis, three axes.
  const double noise_per_frame = 1.6968e-4 * std::sqrt(0.05) * std::sqrt(3.0);
  std::printf(
      "euroc imu0: gyro bias from the static start (%d samples) %.5f %.5f %.5f rad/s; "
      "rotation increment error per frame over frames 20-39: RMS %.3e rad (max %.3e) with it, "
      "%.3e rad without; ground-truth increments RMS %.3e rad; white noise alone %.2e rad\n",
      n, static_bias.gyro_radps.x(), static_bias.gyro_radps.y(), static_bias.gyro_radps.z(),
      Rms(corrected), *std::max_element(corrected.begin(), corrected.end()), Rms(raw), truth_rms,
      noise_per_frame);
  EXPECT_GT(Rms(raw), 2e-3);
  EXPECT_LT(Rms(corrected), 0.25 * Rms(raw));
  EXPECT_LT(Rms(corrected), 2e-4);
}

}  // namespace
}  // namespace swf::eval
