// ImuInput: the samples between frames into the two preintegrations, with every kind of bad
// sample counted and a hole in the stream bridged and flagged, never fatal.
#include "swf/app/imu_input.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "swf/testing/allocation_counter.hpp"

namespace swf::app {
namespace {

using estimator::ImuSample;
using estimator::ImuSampleVerdict;
using estimator::Vec3;

constexpr std::int64_t kPeriodUs = 5000;  // 200 Hz

ImuOptions Options() {
  ImuOptions o;
  o.enabled = true;
  o.noise.gyro_noise_density = 1e-4;
  o.noise.accel_noise_density = 1e-3;
  o.noise.gyro_random_walk = 1e-5;
  o.noise.accel_random_walk = 1e-4;
  o.stream.nominal_period_us = kPeriodUs;
  o.stream.gyro_range_radps = 10.0;
  return o;
}

// A vehicle turning at 0.1 rad/s about z and at rest otherwise (specific force: gravity up).
ImuSample<double> Sample(std::int64_t k) {
  ImuSample<double> s;
  s.t_us = k * kPeriodUs;
  s.seq = k;
  s.gyro_radps = Vec3<double>(0.0, 0.0, 0.1);
  s.accel_mps2 = Vec3<double>(0.0, 0.0, 9.81);
  return s;
}

TEST(ImuInputTest, IntegratesTheSamplesUpToEachFrameIntoBothIntervals) {
  ImuInput in;
  ASSERT_EQ(in.Configure(Options()), core::Status::kOk);
  for (std::int64_t k = 0; k <= 20; ++k) EXPECT_EQ(in.Add(Sample(k)), ImuSampleVerdict::kAccepted);
  ASSERT_EQ(in.Start(0, estimator::ImuBiases<double>{}), core::Status::kOk);
  ASSERT_EQ(in.IntegrateTo(50000), core::Status::kOk);  // 50 ms
  EXPECT_NEAR(in.SinceEstimate().DurationS(), 0.05, 1e-12);
  EXPECT_FALSE(in.LastInterval().gap);
  ASSERT_EQ(in.RestartSinceEstimate(estimator::ImuBiases<double>{}), core::Status::kOk);
  ASSERT_EQ(in.IntegrateTo(100000), core::Status::kOk);
  // The frame interval restarted, the trusted one runs on: 0.1 rad/s for 50 and 100 ms.
  EXPECT_NEAR(in.SinceEstimate().DurationS(), 0.05, 1e-12);
  EXPECT_NEAR(in.SinceTrusted().DurationS(), 0.1, 1e-12);
  const auto since_trusted = in.SinceTrusted().Corrected(estimator::ImuBiases<double>{});
  EXPECT_NEAR(estimator::LogSO3<double>(since_trusted.rotation).z(), 0.01, 1e-9);
  EXPECT_EQ(in.IntegrateTo(100000), core::Status::kOk);  // not later: nothing
  EXPECT_NEAR(in.SinceTrusted().DurationS(), 0.1, 1e-12);
}

TEST(ImuInputTest, BadSamplesAreCountedAndAHoleIsBridgedAndFlagged) {
  ImuInput in;
  ASSERT_EQ(in.Configure(Options()), core::Status::kOk);
  ASSERT_EQ(in.Start(0, estimator::ImuBiases<double>{}), core::Status::kOk);
  EXPECT_EQ(in.Add(Sample(0)), ImuSampleVerdict::kAccepted);
  EXPECT_EQ(in.Add(Sample(1)), ImuSampleVerdict::kAccepted);
  EXPECT_EQ(in.Add(Sample(1)), ImuSampleVerdict::kDroppedDuplicate);
  EXPECT_EQ(in.Add(Sample(0)), ImuSampleVerdict::kDroppedOutOfOrder);
  ImuSample<double> nan = Sample(2);
  nan.accel_mps2.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(in.Add(nan), ImuSampleVerdict::kDroppedInvalid);
  ImuSample<double> clipped = Sample(3);
  clipped.gyro_radps.z() = 10.0;  // at the range
  EXPECT_EQ(in.Add(clipped), ImuSampleVerdict::kDroppedSaturated);
  // 10 samples lost (times 4 .. 13), then the stream resumes.
  EXPECT_EQ(in.Add(Sample(14)), ImuSampleVerdict::kAcceptedAfterGap);
  EXPECT_EQ(in.Add(Sample(15)), ImuSampleVerdict::kAccepted);
  ASSERT_EQ(in.IntegrateTo(15 * kPeriodUs), core::Status::kOk);
  EXPECT_TRUE(in.LastInterval().gap);
  EXPECT_NEAR(in.SinceEstimate().DurationS(), 0.075, 1e-12);  // the hole is held, not skipped
  const ImuCounts c = in.Counts();
  EXPECT_EQ(c.stream.accepted, 4);
  EXPECT_EQ(c.stream.duplicated, 1);
  EXPECT_EQ(c.stream.out_of_order, 1);
  EXPECT_EQ(c.stream.invalid, 1);
  EXPECT_EQ(c.stream.saturated, 1);
  EXPECT_EQ(c.stream.gaps, 1);
  EXPECT_EQ(c.intervals_bridged, 1);
}

TEST(ImuInputTest, AFullRingDropsTheOldestCountedAndNothingAllocates) {
  ImuInput in;
  ASSERT_EQ(in.Configure(Options()), core::Status::kOk);
  ASSERT_EQ(in.Start(0, estimator::ImuBiases<double>{}), core::Status::kOk);
  swf::testing::AllocationScope scope;
  for (std::int64_t k = 0; k < kMaxImuSamples + 10; ++k) (void)in.Add(Sample(k));
  ASSERT_EQ(in.IntegrateTo((kMaxImuSamples + 9) * kPeriodUs), core::Status::kOk);
  EXPECT_EQ(scope.Count(), 0u);
  EXPECT_EQ(in.Counts().overflowed, 10);
  EXPECT_TRUE(in.LastInterval().gap);  // the first sample kept is after the interval's start
}

TEST(ImuInputTest, NoSampleEverIsEmptyAndBadOptionsAreRefused) {
  ImuInput in;
  ASSERT_EQ(in.Configure(Options()), core::Status::kOk);
  EXPECT_EQ(in.IntegrateTo(1000), core::Status::kNotConfigured);  // before Start
  ASSERT_EQ(in.Start(0, estimator::ImuBiases<double>{}), core::Status::kOk);
  EXPECT_EQ(in.IntegrateTo(1000), core::Status::kEmpty);
  EXPECT_TRUE(in.LastInterval().gap);
  ImuOptions bad = Options();
  bad.noise.gyro_noise_density = -1.0;
  EXPECT_EQ(in.Configure(bad), core::Status::kInvalidArgument);
  bad = Options();
  bad.first_velocity_sigma_mps = std::numeric_limits<double>::infinity();
  EXPECT_EQ(in.Configure(bad), core::Status::kInvalidArgument);
  bad = Options();
  bad.stream.nominal_period_us = 0;
  EXPECT_EQ(in.Configure(bad), core::Status::kInvalidArgument);
}

}  // namespace
}  // namespace swf::app
