// The flight process's frame group (rectify, track, estimate with the integrity checks and the
// covariances, navigation output) on the demo descent (fsw/app/config/demo.cfg), at 512x384 (the
// reference in the same run) and at the paper's 1024x768, with the demo's tactical IMU (second
// argument 1: its samples up to each exposure are handed over inside the timed group) and with
// the idealized motion input (0: the stereo filter). The frames are rendered before timing; each
// benchmark iteration flies the whole descent and reports the per-frame p50, p99 and max.
// Third argument 1: the held window (hold_depth_precision 0.5 %, growing to kMaxWindow + 1).
// Run with SWF_SHARED_DIR set (the simulator's terrain texture).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "swf/app/app.hpp"
#include "swf/app/config.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/evaluation/statistics.hpp"
#include "swf/sil/sil.hpp"

namespace swf::app {
namespace {

// This thread's CPU time: on a shared machine the wall clock also counts the time the core ran
// someone else; the CPU time is what the group itself costs.
double ThreadCpuMs() {
  timespec t{};
  (void)clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

struct Descent {
  FswConfig config;
  std::unique_ptr<sil::SimWorld> world = std::make_unique<sil::SimWorld>();
  PipelineOptions options;
};

// Builds and renders the demo descent at width x height once per size and motion source.
const Descent* RenderedDescent(int width, int height, bool inertial) {
  static std::unique_ptr<Descent> cache[2][2];
  std::unique_ptr<Descent>& slot = cache[width > 512 ? 1 : 0][inertial ? 1 : 0];
  if (slot) return slot.get();
  auto d = std::make_unique<Descent>();
  std::string error;
  const std::vector<std::string> overrides = {
      std::string("imu.enabled: ") + (inertial ? "true" : "false"), "pacing: lockstep",
      "lcm.publish: false", "sim.width_px: " + std::to_string(width),
      "sim.height_px: " + std::to_string(height),
      // The disparity at the lowest altitude grows with the image (configuration check).
      "max_disparity_px: " + std::to_string(width > 512 ? 240 : 160)};
  if (!LoadConfig(SWF_DEMO_CONFIG, overrides, &d->config, &error, sil::SimConfigExtension()) ||
      !d->world->Build(d->config, &error) || !d->world->RenderAll(2, nullptr, &error)) {
    std::fprintf(stderr, "bench_frame_group: %s\n", error.c_str());
    return nullptr;
  }
  PipelineOptions& po = d->options;
  po.camera = d->world->Camera();
  po.width_px = d->world->Width();
  po.height_px = d->world->Height();
  po.initial_world_T_camera = d->world->Trajectory().WorldTCamera(0);
  if (inertial) po.imu = sil::SimImuOptions(d->config, &d->world->Trajectory());
  std::int8_t nav_mode = 0;
  ApplyEstimatorConfig(d->config, &po, &nav_mode);
  slot = std::move(d);
  return slot.get();
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_FrameGroup(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0));
  const bool inertial = state.range(1) != 0;
  const bool held = state.range(2) != 0;  // the held window (hold_depth_precision: 0.005)
  const Descent* d = RenderedDescent(width, width * 3 / 4, inertial);
  if (d == nullptr || (inertial && d->world->ImuUnit() == nullptr)) {
    state.SkipWithError("the descent could not be built (SWF_SHARED_DIR?)");
    return;
  }
  sil::SimWorld& world = *d->world;
  static const std::vector<estimator::ImuSample<double>> kNoSamples;
  const std::vector<estimator::ImuSample<double>>& samples =
      inertial ? world.ImuUnit()->Samples() : kNoSamples;
  std::vector<double> ms;
  std::vector<double> cpu_ms;
  std::vector<double> estimate_cpu_ms;
  std::vector<double> poses;  // in the window after each frame
  for (auto _ : state) {
    auto pipeline = std::make_unique<Pipeline>();
    PipelineOptions options = d->options;
    if (held) options.swf.hold_depth_precision = 0.005;
    if (pipeline->Configure(options) != core::Status::kOk) {
      state.SkipWithError("pipeline configuration refused");
      return;
    }
    ms.clear();
    cpu_ms.clear();
    estimate_cpu_ms.clear();
    poses.clear();
    std::size_t next_sample = 0;
    for (std::int32_t k = 0; k < world.NumFrames(); ++k) {
      PipelineFrame frame;
      frame.left = frontend::GrayView{world.Left(k), world.Width(), world.Height(), world.Width()};
      frame.right =
          frontend::GrayView{world.Right(k), world.Width(), world.Height(), world.Width()};
      frame.utime = world.Trajectory().FrameTimeNs(k) / 1000;
      frame.seq = k;
      drivers::MotionInput m;
      const bool has_motion = world.Motion(static_cast<std::uint64_t>(k), &m);
      estimator::Pose<double> motion;
      motion.t =
          estimator::Vec3<double>(m.translation_m[0], m.translation_m[1], m.translation_m[2]);
      motion.R = estimator::ExpSO3<double>(
          estimator::Vec3<double>(m.rotation_rad[0], m.rotation_rad[1], m.rotation_rad[2]));
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = ThreadCpuMs();
      while (next_sample < samples.size() && samples[next_sample].t_us <= frame.utime)
        (void)pipeline->AddImu(samples[next_sample++]);
      bool ok =
          pipeline->Rectify(frame) == core::Status::kOk && pipeline->Track() == core::Status::kOk;
      const double c1 = ThreadCpuMs();
      ok = ok && pipeline->Estimate(has_motion ? &motion : nullptr) == core::Status::kOk;
      const double c2 = ThreadCpuMs();
      NavOutput nav;
      pipeline->MakeNav(&nav);
      const auto t1 = std::chrono::steady_clock::now();
      cpu_ms.push_back(ThreadCpuMs() - c0);
      estimate_cpu_ms.push_back(c2 - c1);
      if (!ok) {
        state.SkipWithError("a frame failed");
        return;
      }
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      poses.push_back(pipeline->NumPoses());
    }
  }
  state.counters["frames"] = static_cast<double>(ms.size());
  state.counters["p50_ms"] = evaluation::Quantile(ms, 0.50);
  state.counters["p99_ms"] = evaluation::Quantile(ms, 0.99);
  state.counters["max_ms"] = evaluation::Quantile(ms, 1.0);
  // The same group in this thread's CPU time, and its estimate stage alone (update, gates,
  // covariances, integrity monitor, refinement).
  state.counters["cpu_p50_ms"] = evaluation::Quantile(cpu_ms, 0.50);
  state.counters["cpu_p99_ms"] = evaluation::Quantile(cpu_ms, 0.99);
  state.counters["estimate_cpu_p50_ms"] = evaluation::Quantile(estimate_cpu_ms, 0.50);
  state.counters["estimate_cpu_p99_ms"] = evaluation::Quantile(estimate_cpu_ms, 0.99);
  state.counters["median_poses"] = evaluation::Quantile(poses, 0.5);
  state.counters["max_poses"] = evaluation::Quantile(poses, 1.0);
}
BENCHMARK(BM_FrameGroup)
    ->ArgNames({"width_px", "imu", "held"})
    ->Args({512, 0, 0})
    ->Args({1024, 0, 0})
    ->Args({512, 1, 0})
    ->Args({1024, 1, 0})
    ->Args({512, 1, 1})
    ->Args({1024, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3);

}  // namespace
}  // namespace swf::app

BENCHMARK_MAIN();
