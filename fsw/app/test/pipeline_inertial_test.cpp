// The flight pipeline's stereo-inertial estimator over a simulated descent with the simulator's
// MEMS IMU (sim::ImuModel, ADIS16448 parameters, riding on the rendered trajectory): accuracy
// against the truth and against the stereo-only pipeline, the IMU biases, and a camera outage of
// 2 s carried by the IMU (flagged, within its covariance) with re-acquisition afterwards.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "small_rig.hpp"
#include "swf/app/config.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/sil/sil.hpp"
#include "swf/sim/imu_model.hpp"

namespace swf::app {
namespace {

using estimator::NavIntegrity;
using estimator::Vec3;

constexpr int kFrames = 80;

struct FrameResult {
  std::int8_t status = 0;
  std::uint32_t flags = 0;
  double error_m = 0.0;
  double sigma_m = 0.0;  // 1-sigma of the position error along its own direction
};

class InertialDescent {
 public:
  InertialDescent() {
    std::string error;
    EXPECT_TRUE(testing::BuildSimWorld(
        "source: sim\nsim.frames: 80\nsim.width_px: 256\nsim.height_px: 192\n"
        "sim.terrain_size: 1024\nrate_hz: 10\n",
        &config_, world_.get(), &error))
        << error;
    sim::ImuModelOptions unit = sim::MemsImu();
    unit.camera_T_imu.t = Vec3<double>(0.1, -0.05, 0.02);
    unit.seed = 7;
    EXPECT_EQ(imu_.Configure(unit, world_->Trajectory()), core::Status::kOk);
    camera_t_imu_ = unit.camera_T_imu;
  }

  PipelineOptions Options(bool inertial) const {
    PipelineOptions po = testing::SmallRigOptions(*world_);
    po.integrity.max_speed_mps = 50.0;
    po.initial_world_T_camera = world_->Trajectory().WorldTCamera(0);
    po.imu.enabled = inertial;
    po.imu.noise = imu_.NoiseModel();
    po.imu.stream.nominal_period_us = 2500;  // 400 Hz
    po.imu.imu_T_camera = camera_t_imu_.Inverse();
    po.imu.gravity_world_mps2 = imu_.GravityWorld();
    po.imu.initial_velocity_world_mps = imu_.TrueState(FrameTimeS(0)).velocity_world_mps;
    return po;
  }

  // Runs the descent; frames in [blind_begin, blind_end) have no stereo pair (the pipeline
  // coasts) or, with `black`, black images. The IMU samples up to each exposure are added
  // before the frame.
  std::vector<FrameResult> Run(bool inertial, int blind_begin = -1, int blind_end = -1,
                               bool black = false) {
    const std::vector<std::uint8_t> dark(
        static_cast<std::size_t>(world_->Width()) * static_cast<std::size_t>(world_->Height()), 0);
    pipeline_ = std::make_unique<Pipeline>();
    EXPECT_EQ(pipeline_->Configure(Options(inertial)), core::Status::kOk);
    std::vector<FrameResult> out(kFrames);
    std::size_t next_sample = 0;
    const auto& samples = imu_.Samples();
    for (int k = 0; k < kFrames; ++k) {
      const std::int64_t utime = world_->Trajectory().FrameTimeNs(k) / 1000;
      while (inertial && next_sample < samples.size() && samples[next_sample].t_us <= utime)
        pipeline_->AddImu(samples[next_sample++]);
      const bool blind = k >= blind_begin && k < blind_end;
      if (blind && !black) {
        EXPECT_EQ(pipeline_->Coast(nullptr), core::Status::kOk) << k;
      } else {
        PipelineFrame frame;
        const std::uint8_t* left = blind ? dark.data() : world_->Left(k);
        const std::uint8_t* right = blind ? dark.data() : world_->Right(k);
        frame.left = frontend::GrayView{left, world_->Width(), world_->Height(), world_->Width()};
        frame.right = frontend::GrayView{right, world_->Width(), world_->Height(), world_->Width()};
        frame.utime = utime;
        frame.seq = k;
        EXPECT_EQ(pipeline_->Rectify(frame), core::Status::kOk) << k;
        EXPECT_EQ(pipeline_->Track(), core::Status::kOk) << k;
        EXPECT_EQ(pipeline_->Estimate(nullptr), core::Status::kOk) << k;
      }
      NavOutput nav;
      pipeline_->MakeNav(&nav);
      const Vec3<double> e =
          Vec3<double>(nav.position_world_m[0], nav.position_world_m[1], nav.position_world_m[2]) -
          world_->Trajectory().WorldTCamera(k).t;
      estimator::Mat3<double> p;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) p(r, c) = nav.covariance[6 * r + c];
      out[k].status = nav.status;
      out[k].flags = static_cast<std::uint32_t>(nav.integrity_flags);
      out[k].error_m = e.norm();
      out[k].sigma_m = e.norm() > 0.0 ? std::sqrt(e.dot(p * e) / e.squaredNorm()) : 0.0;
    }
    return out;
  }

  double FrameTimeS(int k) const { return world_->Trajectory().FrameTimeNs(k) * 1e-9; }
  const sim::ImuModel& Imu() const { return imu_; }
  const Pipeline& LastPipeline() const { return *pipeline_; }

 private:
  FswConfig config_;
  std::unique_ptr<sil::SimWorld> world_ = std::make_unique<sil::SimWorld>();
  sim::ImuModel imu_;
  estimator::Pose<double> camera_t_imu_;
  std::unique_ptr<Pipeline> pipeline_;
};

double Rms(const std::vector<FrameResult>& r, int begin, int end) {
  double sum = 0.0;
  for (int k = begin; k < end; ++k) sum += r[k].error_m * r[k].error_m;
  return std::sqrt(sum / (end - begin));
}

TEST(PipelineInertialTest, StereoInertialDescentIsAccurateAndEstimatesTheBiases) {
  InertialDescent descent;
  const std::vector<FrameResult> stereo = descent.Run(false);
  const std::vector<FrameResult> inertial = descent.Run(true);
  const Pipeline& p = descent.LastPipeline();
  ASSERT_TRUE(p.Inertial());
  const double stereo_rms = Rms(stereo, 0, kFrames);
  const double inertial_rms = Rms(inertial, 0, kFrames);
  int valid = 0;
  int beyond_3_sigma = 0;
  for (const FrameResult& f : inertial) {
    valid += f.status == static_cast<std::int8_t>(NavIntegrity::kValid);
    beyond_3_sigma += f.error_m > 3.0 * f.sigma_m;
  }
  const ImuCounts counts = p.ImuStreamCounts();
  const estimator::NavState<double>* x = p.NewestNavState();
  ASSERT_NE(x, nullptr);
  const estimator::ImuBiases<double>& truth =
      descent.Imu().TrueBiases()[counts.stream.accepted - 1];
  const double gyro_error = (x->biases.gyro_radps - truth.gyro_radps).norm();
  const double gyro_turn_on = truth.gyro_radps.norm();
  std::printf(
      "position RMS: stereo-only %.3f m, stereo-inertial %.3f m; VALID %d/%d, beyond 3 sigma %d; "
      "gyro bias error %.2e rad/s (true bias %.2e); IMU samples %lld accepted\n",
      stereo_rms, inertial_rms, valid, kFrames, beyond_3_sigma, gyro_error, gyro_turn_on,
      static_cast<long long>(counts.stream.accepted));
  EXPECT_EQ(counts.stream.accepted,
            static_cast<std::int64_t>(
                (descent.FrameTimeS(kFrames - 1) - descent.FrameTimeS(0)) * 400.0 + 1.5));
  EXPECT_EQ(counts.intervals_bridged, 0);
  EXPECT_LT(inertial_rms, 0.5);
  EXPECT_LE(inertial_rms, 1.2 * stereo_rms + 0.02);
  EXPECT_GE(valid, kFrames - 5);
  EXPECT_LE(beyond_3_sigma, 4);
  EXPECT_LT(gyro_error, 0.5 * gyro_turn_on);  // the gyro bias is estimated, not left at zero
}

// GIVEN 2 s without usable images (no pair at all, then black pairs) WHEN the stereo-inertial
// pipeline runs THEN the IMU carries the state: every such frame flagged CAMERA_OUTAGE and not
// VALID, the error within 3 sigma of the published covariance and under 1 m, and the filter
// re-acquires (VALID again, error back under 0.5 m by the end).
class PipelineInertialBlind : public ::testing::TestWithParam<bool> {};

TEST_P(PipelineInertialBlind, TwoSecondsBlindAreCarriedByTheImuAndReacquired) {
  const bool black = GetParam();
  InertialDescent descent;
  const int begin = 40;
  const int end = 60;  // 2 s at 10 Hz
  const std::vector<FrameResult> r = descent.Run(true, begin, end, black);
  double worst_normalized = 0.0;
  for (int k = begin; k < end; ++k) {
    EXPECT_NE(r[k].flags & estimator::kFlagCameraOutage, 0u) << k;
    EXPECT_NE(r[k].status, static_cast<std::int8_t>(NavIntegrity::kValid)) << k;
    worst_normalized = std::max(worst_normalized, r[k].error_m / r[k].sigma_m);
  }
  const double end_error_m = r[end - 1].error_m;
  const double end_sigma_m = r[end - 1].sigma_m;
  int valid_after = 0;
  for (int k = end; k < kFrames; ++k)
    valid_after += r[k].status == static_cast<std::int8_t>(NavIntegrity::kValid);
  std::printf(
      "blind 2 s (%s): error %.3f m -> %.3f m (sigma %.3f m), worst error/sigma %.2f; after: "
      "error %.3f m, VALID %d/%d frames\n",
      black ? "black frames" : "no pairs", r[begin - 1].error_m, end_error_m, end_sigma_m,
      worst_normalized, r[kFrames - 1].error_m, valid_after, kFrames - end);
  EXPECT_LT(worst_normalized, 3.0);
  EXPECT_LT(end_error_m, 1.0);
  EXPECT_LT(r[kFrames - 1].error_m, 0.5);
  EXPECT_GE(valid_after, kFrames - end - 8);
  EXPECT_EQ(descent.LastPipeline().Integrity().frames_coasted, end - begin);
  EXPECT_EQ(descent.LastPipeline().Integrity().frames_blind, black ? end - begin : 0);
}

INSTANTIATE_TEST_SUITE_P(NoPairsOrBlackFrames, PipelineInertialBlind, ::testing::Bool());

// GIVEN the simulated hover (at rest, 50 m, the tactical unit) and a guidance attitude 100 mrad
// off in tilt WHEN the pipeline starts at frame 10 with imu.static_start THEN the second of
// samples before it levels the attitude to what the accelerometer's own bias allows (its
// horizontal part over g: on the Moon's 1.625 m/s^2 a 1 mg bias is 6 mrad), and the gyroscope
// bias is read to its noise over that second (3 sigma); without the static start the first
// state keeps the guidance's tilt error.
TEST(PipelineInertialTest, StaticStartLevelsTheAttitudeAndReadsTheGyroBias) {
  FswConfig config;
  std::string error;
  sil::SimWorld world;
  ASSERT_TRUE(
      testing::BuildSimWorld("source: sim\nsim.scenario: hover\nsim.frames: 20\nsim.width_px: 256\n"
                             "sim.height_px: 192\nsim.terrain_size: 1024\nrate_hz: 10\n"
                             "sim.imu_unit: tactical\nimu.enabled: true\nimu.static_start: true\n",
                             &config, &world, &error))
      << error;
  const sim::ImuModel& unit = *world.ImuUnit();
  const int first = 10;
  const estimator::Pose<double> truth = world.Trajectory().WorldTCamera(first);
  for (const bool static_start : {true, false}) {
    PipelineOptions po = testing::SmallRigOptions(world);
    po.imu = sil::SimImuOptions(config, &world.Trajectory());
    po.imu.static_start = static_start;
    po.initial_world_T_camera = truth;
    po.initial_world_T_camera.R = estimator::ExpSO3<double>(Vec3<double>(0.1, 0.0, 0.0)) * truth.R;
    Pipeline pipeline;
    ASSERT_EQ(pipeline.Configure(po), core::Status::kOk);
    const std::int64_t utime = world.Trajectory().FrameTimeNs(first) / 1000;
    std::size_t k = 0;
    for (; k < unit.Samples().size() && unit.Samples()[k].t_us <= utime; ++k)
      pipeline.AddImu(unit.Samples()[k]);
    PipelineFrame frame;
    frame.left =
        frontend::GrayView{world.Left(first), world.Width(), world.Height(), world.Width()};
    frame.right =
        frontend::GrayView{world.Right(first), world.Width(), world.Height(), world.Width()};
    frame.utime = utime;
    frame.seq = first;
    ASSERT_EQ(pipeline.Rectify(frame), core::Status::kOk);
    ASSERT_EQ(pipeline.Track(), core::Status::kOk);
    ASSERT_EQ(pipeline.Estimate(nullptr), core::Status::kOk);
    const estimator::NavState<double>* x = pipeline.NewestNavState();
    ASSERT_NE(x, nullptr);
    const estimator::Mat3<double> world_R_camera = x->world_T_imu.R * po.imu.imu_T_camera.R;
    const double tilt_error =
        (world_R_camera * truth.R.transpose() * Vec3<double>::UnitZ() - Vec3<double>::UnitZ())
            .norm();
    const double gyro_error = (x->biases.gyro_radps - unit.TrueBiases()[k - 1].gyro_radps).norm();
    // What levelling on a biased accelerometer must leave: the bias's horizontal part over g.
    const Vec3<double> bias_world =
        truth.R * po.imu.imu_T_camera.R * unit.TrueBiases()[k - 1].accel_mps2;
    const double expected_tilt = bias_world.head<2>().norm() / 1.625;
    const double gyro_bound = 3.0 * std::sqrt(3.0) * po.imu.noise.gyro_noise_density;  // 1 s
    const ImuCounts counts = pipeline.ImuStreamCounts();
    std::printf(
        "static start %s: tilt error %.2f mrad (accelerometer bias allows %.2f), gyro bias error "
        "%.2e rad/s (3 sigma of the mean %.2e; %lld samples)\n",
        static_start ? "on" : "off", 1e3 * tilt_error, 1e3 * expected_tilt, gyro_error, gyro_bound,
        static_cast<long long>(counts.stream.accepted));
    if (static_start) {
      EXPECT_EQ(counts.static_start, 1);
      EXPECT_NEAR(counts.static_tilt_correction_rad, 0.1, 0.03);
      EXPECT_NEAR(tilt_error, expected_tilt, 0.005);
      EXPECT_LT(gyro_error, gyro_bound);
    } else {
      EXPECT_EQ(counts.static_start, 0);
      EXPECT_GT(tilt_error, 0.09);
    }
  }
}

// The small-rig descent with the simulated unit whose clock is off the cameras' by
// clock_offset_ms, flown by the pipeline with the time offset estimated online (or not): the
// samples are handed over up to each exposure plus the offset the pipeline applies (as the
// flight loop waits for them). The estimate after each frame, and the position RMS.
struct OffsetRun {
  std::vector<double> offset_ms;
  double position_rms_m = 0.0;
  long readings = 0;
};
OffsetRun FlyWithClockOffset(const std::string& unit, double clock_offset_ms, bool estimate,
                             int frames) {
  FswConfig config;
  std::string error;
  sil::SimWorld world;
  EXPECT_TRUE(testing::BuildSimWorld(
      "source: sim\nsim.frames: " + std::to_string(frames) +
          "\nsim.width_px: 256\nsim.height_px: 192\nsim.terrain_size: 1024\nrate_hz: 10\n"
          "sim.imu_unit: " +
          unit +
          "\nimu.enabled: true\nimu.camera_t_imu_m: 0.25, -0.1, -0.4\n"
          "sim.imu_clock_offset_ms: " +
          std::to_string(clock_offset_ms) +
          "\nimu.estimate_time_offset: " + (estimate ? "true" : "false") + "\n",
      &config, &world, &error))
      << error;
  PipelineOptions po = testing::SmallRigOptions(world);
  po.integrity.max_speed_mps = 50.0;
  po.imu = sil::SimImuOptions(config, &world.Trajectory());
  po.initial_world_T_camera = world.Trajectory().WorldTCamera(0);
  Pipeline pipeline;
  EXPECT_EQ(pipeline.Configure(po), core::Status::kOk);
  const auto& samples = world.ImuUnit()->Samples();
  std::size_t next = 0;
  OffsetRun run;
  double sum = 0.0;
  for (int k = 0; k < frames; ++k) {
    const std::int64_t utime = world.Trajectory().FrameTimeNs(k) / 1000;
    const std::int64_t lead =
        std::max<std::int64_t>(0, std::llround(pipeline.ImuTimeOffsetS() * 1e6));
    while (next < samples.size() && samples[next].t_us <= utime + lead)
      pipeline.AddImu(samples[next++]);
    PipelineFrame frame;
    frame.left = frontend::GrayView{world.Left(k), world.Width(), world.Height(), world.Width()};
    frame.right = frontend::GrayView{world.Right(k), world.Width(), world.Height(), world.Width()};
    frame.utime = utime;
    frame.seq = k;
    EXPECT_EQ(pipeline.Rectify(frame), core::Status::kOk) << k;
    EXPECT_EQ(pipeline.Track(), core::Status::kOk) << k;
    EXPECT_EQ(pipeline.Estimate(nullptr), core::Status::kOk) << k;
    NavOutput nav;
    pipeline.MakeNav(&nav);
    const Vec3<double> e =
        Vec3<double>(nav.position_world_m[0], nav.position_world_m[1], nav.position_world_m[2]) -
        world.Trajectory().WorldTCamera(k).t;
    sum += e.squaredNorm();
    run.offset_ms.push_back(1e3 * pipeline.ImuTimeOffsetS());
  }
  run.position_rms_m = std::sqrt(sum / frames);
  run.readings = pipeline.ImuTimeOffset().Readings();
  return run;
}

// GIVEN the descent with the tactical unit's clock 12 ms ahead of the cameras' and with the MEMS
//       unit's 8 ms behind WHEN the pipeline estimates the time offset online from zero THEN the
//       estimate moves toward the truth, without overshooting it, and the position RMS is no
//       worse than without the estimate; without a desynchronization the estimate stays within
//       0.1 ms of zero. What it does not do yet: converge within a few frames. Measured over 60
//       frames: tactical 0.05 / 0.46 / 0.92 ms at frames 5 / 30 / 59 (of 12), MEMS -0.41 / -3.66 /
//       -4.75 ms (of -8): the solved states take most of the offset's effect into themselves, the
//       more so the better the IMU (estimator/imu_time_offset.hpp)
TEST(PipelineInertialTest, TheCameraImuTimeOffsetIsEstimatedOnline) {
  constexpr int kOffsetFrames = 60;
  struct Case {
    const char* unit;
    double offset_ms;
  };
  for (const Case c : {Case{"tactical", 12.0}, Case{"mems", -8.0}, Case{"tactical", 0.0}}) {
    const OffsetRun on = FlyWithClockOffset(c.unit, c.offset_ms, true, kOffsetFrames);
    const OffsetRun off = FlyWithClockOffset(c.unit, c.offset_ms, false, kOffsetFrames);
    double worst_after_30 = 0.0;
    for (int k = 30; k < kOffsetFrames; ++k)
      worst_after_30 = std::max(worst_after_30, std::abs(on.offset_ms[k] - c.offset_ms));
    const double last = on.offset_ms.back();
    std::printf(
        "%s, clock %+.0f ms: estimate at frames 5/10/20/30/59 %.2f %.2f %.2f %.2f %.2f ms "
        "(worst from 30 on %.2f ms off; %ld intervals read); position RMS %.4f m estimated, "
        "%.4f m not\n",
        c.unit, c.offset_ms, on.offset_ms[5], on.offset_ms[10], on.offset_ms[20], on.offset_ms[30],
        on.offset_ms[kOffsetFrames - 1], worst_after_30, on.readings, on.position_rms_m,
        off.position_rms_m);
    EXPECT_GE(on.readings, kOffsetFrames - 5);
    if (c.offset_ms == 0.0) {
      EXPECT_LT(worst_after_30, 0.1) << c.unit;
    } else {
      // Toward the truth by at least 0.5 ms, and not past it.
      EXPECT_GT(last * c.offset_ms, 0.0) << c.unit;
      EXPECT_LT(std::abs(c.offset_ms - last), std::abs(c.offset_ms) - 0.5) << c.unit;
      EXPECT_LE(std::abs(last), std::abs(c.offset_ms)) << c.unit;
    }
    EXPECT_LE(on.position_rms_m, 1.05 * off.position_rms_m + 0.002) << c.unit;
    EXPECT_EQ(off.offset_ms.back(), 0.0);
  }
}

}  // namespace
}  // namespace swf::app
