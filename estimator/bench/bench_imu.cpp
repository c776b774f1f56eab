// IMU preintegration cost per camera frame: the stream check of each sample, then the
// preintegration of one frame interval (increments, 9x9 covariance, bias Jacobians), then the
// first-order bias correction and prediction the filter evaluates per iteration.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/imu_stream.hpp"

namespace swf::estimator {
namespace {

// Two seconds of a rotating, accelerating IMU at rate_hz (the values only need to be generic).
std::vector<ImuSample<double>> Samples(double rate_hz) {
  std::vector<ImuSample<double>> samples;
  const auto period_us = static_cast<std::int64_t>(std::llround(1e6 / rate_hz));
  for (std::int64_t k = 0; k * period_us <= 2'000'000; ++k) {
    const double t = k * period_us * 1e-6;
    ImuSample<double> s;
    s.t_us = k * period_us;
    s.seq = k;
    s.gyro_radps = {0.3 * std::sin(1.1 * t), 0.2 * std::cos(0.7 * t), 0.1};
    s.accel_mps2 = {0.5 * std::cos(0.9 * t), 0.2, 9.81 + 0.3 * std::sin(1.7 * t)};
    samples.push_back(s);
  }
  return samples;
}

const ImuNoise<double> kAdis16448{1.6968e-4, 2.0e-3, 1.9393e-5, 3.0e-3};

// Arg: IMU rate (Hz); one frame interval of 0.1 s (10 Hz camera, the flight demo's).
void PreintegrateFrame(benchmark::State& state) {
  const double rate_hz = static_cast<double>(state.range(0));
  const std::vector<ImuSample<double>> samples = Samples(rate_hz);
  const int n = static_cast<int>(samples.size());
  ImuPreintegration<double> pim;
  IntervalSummary summary;
  std::int64_t frame = 0;
  for (auto _ : state) {
    const std::int64_t t0 = (frame % 19) * 100000;
    (void)pim.Reset(kAdis16448, ImuBiases<double>{});
    (void)PreintegrateInterval(samples.data(), n, t0, t0 + 100000, SampleHold::kMidpoint, 0.01,
                               &pim, &summary);
    benchmark::DoNotOptimize(pim.Covariance().data());
    ++frame;
  }
  state.counters["samples_per_frame"] = summary.samples_used;
}
BENCHMARK(PreintegrateFrame)->Arg(200)->Arg(400);

void StreamCheckPerSample(benchmark::State& state) {
  const std::vector<ImuSample<double>> samples = Samples(400.0);
  ImuStreamChecker<double> checker;
  (void)checker.Configure({2500, 3, 17.45, 176.0});
  std::size_t i = 0;
  std::int64_t offset_us = 0;
  for (auto _ : state) {
    ImuSample<double> s = samples[i];
    s.t_us += offset_us;
    benchmark::DoNotOptimize(checker.Check(s));
    if (++i == samples.size()) {
      i = 0;
      offset_us += 3'000'000;
    }
  }
}
BENCHMARK(StreamCheckPerSample);

// What a Gauss-Newton iteration of the extended filter re-evaluates per frame: the increments
// corrected to the current bias estimate and the predicted state.
void CorrectAndPredict(benchmark::State& state) {
  const std::vector<ImuSample<double>> samples = Samples(400.0);
  ImuPreintegration<double> pim;
  IntervalSummary summary;
  (void)pim.Reset(kAdis16448, ImuBiases<double>{});
  (void)PreintegrateInterval(samples.data(), static_cast<int>(samples.size()), 0, 100000,
                             SampleHold::kMidpoint, 0.01, &pim, &summary);
  ImuBiases<double> bias;
  bias.gyro_radps = {1e-3, -2e-3, 5e-4};
  bias.accel_mps2 = {0.02, 0.01, -0.03};
  const InertialState<double> start;
  const Vec3<double> gravity(0.0, 0.0, -9.81);
  for (auto _ : state) {
    const InertialState<double> end = pim.Predict(start, bias, gravity);
    benchmark::DoNotOptimize(end.world_T_imu.t.data());
  }
}
BENCHMARK(CorrectAndPredict);

}  // namespace
}  // namespace swf::estimator

BENCHMARK_MAIN();
