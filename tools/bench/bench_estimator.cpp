// Estimator benchmarks (tools/run bench -> out/bench/estimator.json):
//   Fig14a/<mode>/<frame>: time of the update at a given frame index with ~20 measurements per
//     frame and tracks of ~10 frames (paper Fig. 14a): sliding windows flat, batch growing.
//   Fig13Update/K=10: full update (robust Gauss-Newton + marginalization) with 150 landmarks
//     tracked through the whole descent, at steady state (every landmark in the prior).
//   Fig13Update_Inertial, Fig14a_InertialSwf10: the same loads with 15-dimensional
//     stereo-inertial states (preintegrated IMU process model) on an analytic IMU scene.
//   Cholesky/<impl>/<n>: the reduced system's dense factorization alone (fill + factor of an SPD
//     n x n matrix): DenseCholesky (flight) and Eigen::LLT<MatrixXd> (reference, heap-allocating,
//     benchmark only), with GFlop/s = (n^3 / 3) / CPU time. n = 510 is Fig13Update's dense_dim.
//   Cholesky_Dense/<n>/<kernel>: 0 = picked at construction, 1 = portable, 2 = AVX.
//   CholeskyKernelRatio/<n>: the picked kernel against the portable one in the same iteration.
//   CholeskyRatio/<n>: both in the same iteration, interleaved; ratio = Eigen CPU / Dense CPU,
//     so machine load cancels out.
//   KittiVo_Swf/<build>, KittiVo_Ceres: the kitti-vo batch problem solved by swf-vo's solver
//     (build 0: filter built once; 1: built every solve) and by Ceres (SPARSE_SCHUR, same cost,
//     same tolerances), same process, same run. Kitti00_*: the same on a generated problem of
//     KITTI sequence-00 size; Kitti00_SwfVsCeres runs both in one iteration (CPU ratio);
//     Kitti00_SwfWindow/<window>: sliding windows over it (minutes; only with
//     SWF_BENCH_KITTI00_WINDOWS=1 in the environment).
// The estimator is single-threaded; run on an idle core and read medians (the JSON keeps all
// repetitions).
#include <benchmark/benchmark.h>
#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>

#include "kitti_vo.hpp"
#include "kitti_vo_ceres.hpp"
#include "kitti_vo_synth.hpp"
#include "swf/estimator/dense_cholesky.hpp"
#include "swf/estimator/inertial_model.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/ground_cli/shared_dir.hpp"
#include "swf/scene/runner.hpp"
#include "swf/testing/random_spd.hpp"

namespace {

using swf::estimator::InertialStereoModel;
using swf::estimator::Mat15;
using swf::estimator::SlidingWindowFilter;
using swf::estimator::StereoModel;
using swf::estimator::SwfMode;
using swf::estimator::SwfOptions;
using swf::estimator::Vec3;
using swf::scene::InertialScene;
using swf::scene::InertialSceneOptions;
using swf::scene::MakeInertialScene;
using swf::scene::MotionInput;
using swf::scene::SceneOptions;
using swf::scene::SyntheticScene;

const SyntheticScene& Fig14Scene() {
  static const SyntheticScene kScene = [] {
    SceneOptions so = swf::scene::Fig14Sideways();
    so.frames = 160;
    so.seed = 3;
    return SyntheticScene(so);
  }();
  return kScene;
}

const SyntheticScene& Fig13Scene() {
  static const SyntheticScene kScene = [] {
    SceneOptions so;  // 150 landmarks, 100 m descent, 1.5 m per frame
    so.frames = 40;
    return SyntheticScene(so);
  }();
  return kScene;
}

// The feeders TimeUpdateAt finds by the scene's type (swf/scene/runner.hpp feeds the frames):
// stereo frames with the true relative motion as the motion input (as from an IMU), inertial
// frames after the first pose with its prior and each frame's preintegrated IMU motion.
template <typename Filter>
void Configure(Filter* swf, const SyntheticScene& scene, SwfMode mode) {
  StereoModel<double> model;
  model.camera = scene.camera();
  if (swf->Configure(model, swf::scene::FilterOptions(mode)) != swf::core::Status::kOk)
    std::abort();
}

template <typename Filter>
void AddFrame(Filter* swf, const SyntheticScene& scene, std::size_t j) {
  static MotionInput exact;  // the truth, stated at the motion-input noise of the experiments
  (void)swf::scene::AddFrame(swf, scene, j, &exact);
}

template <typename Filter>
void Configure(Filter* swf, const InertialScene& scene, SwfMode mode) {
  SwfOptions options;
  options.mode = mode;
  if (swf->Configure(scene.model, options) != swf::core::Status::kOk) std::abort();
}

template <typename Filter>
void AddFrame(Filter* swf, const InertialScene& scene, std::size_t j) {
  static const Mat15<double> kFirstPose = swf::scene::FirstPoseCovariance(1e-3, 1e-5);
  if (swf::scene::AddFrame(swf, scene, j, kFirstPose) != swf::core::Status::kOk) std::abort();
}

// Times the update of `frame`: Configure, then frames 0 .. frame - 1 added and updated untimed,
// then `frame` added and its update timed (Scene: SyntheticScene or InertialScene, whose
// Configure / AddFrame overloads feed it). Batch solves once per frame in Fig. 14a as well, but
// the untimed replay only needs the state, so it skips those solves.
template <typename Filter, typename Scene>
void TimeUpdateAt(benchmark::State& state, Filter* swf, const Scene& scene, std::size_t frame,
                  SwfMode mode) {
  for (auto _ : state) {
    state.PauseTiming();
    Configure(swf, scene, mode);
    for (std::size_t j = 0; j < frame; ++j) {
      AddFrame(swf, scene, j);
      if (mode != SwfMode::kBatch) (void)swf->Update();
    }
    AddFrame(swf, scene, frame);
    state.ResumeTiming();
    benchmark::DoNotOptimize(swf->Update());
  }
}

// Fig. 14a: times the update at frame state.range(0); earlier frames are replayed untimed.
template <typename Filter, typename Scene>
void Fig14a(benchmark::State& state, const Scene& scene, SwfMode mode) {
  const auto frame = static_cast<std::size_t>(state.range(0));
  auto swf = std::make_unique<Filter>();
  TimeUpdateAt(state, swf.get(), scene, frame, mode);
  state.counters["measurements"] = swf->Summary().num_measurements;
  state.counters["state_dim"] = swf->Summary().state_dimension;
  state.counters["iterations"] = swf->Summary().iterations;
}

// Fig. 13: times the steady-state update at frame 30 (every landmark in the prior by then).
template <typename Filter, typename Scene>
void Fig13Update(benchmark::State& state, const Scene& scene) {
  auto swf = std::make_unique<Filter>();
  TimeUpdateAt(state, swf.get(), scene, 30, SwfMode::kSlidingWindow);
  state.counters["dense_dim"] = swf->Summary().dense_dimension;
  state.counters["iterations"] = swf->Summary().iterations;
  state.counters["prior_landmarks"] = swf->NumPriorLandmarks();
}

// The Fig. 14a sweep over the frame index, for the sliding windows (whose update time stays flat).
void Fig14aFrames(benchmark::internal::Benchmark* b) {
  b->Arg(25)
      ->Arg(50)
      ->Arg(100)
      ->Arg(150)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(10)
      ->Repetitions(5);
}

// Fig. 13's timing: 5 timed updates per repetition, 5 repetitions.
void Fig13Timing(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)->Iterations(5)->Repetitions(5);
}

using Swf10 = SlidingWindowFilter<StereoModel<double>, 10, 600, 64, 128>;
using Swf20 = SlidingWindowFilter<StereoModel<double>, 20, 600, 64, 128>;
using Batch = SlidingWindowFilter<StereoModel<double>, 128, 4000, 64, 1>;

// NOLINTNEXTLINE(readability-identifier-naming)
void BM_Fig14a_Swf10(benchmark::State& s) {
  Fig14a<Swf10>(s, Fig14Scene(), SwfMode::kSlidingWindow);
}
// NOLINTNEXTLINE(readability-identifier-naming)
void BM_Fig14a_Swf20(benchmark::State& s) {
  Fig14a<Swf20>(s, Fig14Scene(), SwfMode::kSlidingWindow);
}
// NOLINTNEXTLINE(readability-identifier-naming)
void BM_Fig14a_Batch(benchmark::State& s) { Fig14a<Batch>(s, Fig14Scene(), SwfMode::kBatch); }
BENCHMARK(BM_Fig14a_Swf10)->Apply(Fig14aFrames);
BENCHMARK(BM_Fig14a_Swf20)->Apply(Fig14aFrames);
// The batch grows with the frame index: fewer frames and runs.
BENCHMARK(BM_Fig14a_Batch)
    ->Arg(25)
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3)
    ->Repetitions(3);

using Fig13Swf = SlidingWindowFilter<StereoModel<double>, 10, 160, 160, 160>;

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Fig13Update_K10(benchmark::State& state) { Fig13Update<Fig13Swf>(state, Fig13Scene()); }
BENCHMARK(BM_Fig13Update_K10)->Apply(Fig13Timing);

// Integrity cost at the Fig. 13 load, as the flight pipeline runs a frame: the newest pose's
// covariance of the previous frame is computed (untimed here, BM_Fig13Covariances below), then
// the timed part adds the frame (prediction gate per measurement) and updates (residual gate,
// re-solve after rejections). Arg 0: gates off; 1: on (the flight default). Ratio = 1 / 0.
// NOLINTNEXTLINE(readability-identifier-naming)
void BM_Fig13Gates_K10(benchmark::State& state) {
  const SyntheticScene& scene = Fig13Scene();
  auto swf = std::make_unique<Fig13Swf>();
  constexpr std::size_t kFrame = 30;
  SwfOptions options = swf::scene::FilterOptions(SwfMode::kSlidingWindow);
  options.gate_probability = state.range(0) == 0 ? 0.0 : SwfOptions{}.gate_probability;
  StereoModel<double> model;
  model.camera = scene.camera();
  for (auto _ : state) {
    state.PauseTiming();
    if (swf->Configure(model, options) != swf::core::Status::kOk) std::abort();
    for (std::size_t j = 0; j < kFrame; ++j) {
      AddFrame(swf.get(), scene, j);
      (void)swf->Update();
      (void)swf->ComputeCovariances();
    }
    state.ResumeTiming();
    AddFrame(swf.get(), scene, kFrame);
    benchmark::DoNotOptimize(swf->Update());
  }
  state.counters["gate_checked"] = swf->Summary().gate_checked;
  state.counters["iterations"] = swf->Summary().iterations;
}
BENCHMARK(BM_Fig13Gates_K10)->Arg(0)->Arg(1)->Apply(Fig13Timing);

// The covariances the integrity checks need each frame (newest pose, every landmark and its
// correlation with the newest pose), at the Fig. 13 load. Arg 0: ComputeCovariances(); 1:
// ComputeNewestCovariance() alone (what the navigation output needs). Both after Update(), as
// the pipeline calls them: from the solve's last factor, with no factorization of their own.
// NOLINTNEXTLINE(readability-identifier-naming)
void BM_Fig13Covariances_K10(benchmark::State& state) {
  const SyntheticScene& scene = Fig13Scene();
  auto swf = std::make_unique<Fig13Swf>();
  Configure(swf.get(), scene, SwfMode::kSlidingWindow);
  for (std::size_t j = 0; j <= 30; ++j) {
    AddFrame(swf.get(), scene, j);
    (void)swf->Update();
  }
  const bool newest_only = state.range(0) != 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(newest_only ? swf->ComputeNewestCovariance()
                                         : swf->ComputeCovariances());
  }
  state.counters["dense_dim"] = swf->Summary().dense_dimension;
}
BENCHMARK(BM_Fig13Covariances_K10)
    ->ArgName("newest_only")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5);

// ---- stereo-inertial: 15-dimensional states (pose, velocity, IMU biases) -------------------
// The same loads on the analytic IMU scene (swf/scene/inertial_scene.hpp): Fig. 13's
// descent (150 landmarks in a 2 m disc from 100 m, 1.5 m per frame) and Fig. 14a's sideways
// pass (50 m up, 2.2 m per frame, 0.055 landmarks per square metre). Preintegration is untimed
// (bench_imu times it); the update is what the stereo-only rows above time.

const InertialScene& Fig13InertialScene() {
  static const InertialScene kScene = [] {
    InertialSceneOptions o;
    o.frames = 40;
    o.p0 = Vec3<double>(0.0, 0.0, 100.0);
    o.v0 = Vec3<double>(0.0, 0.0, -15.0);
    o.accel_world.setZero();
    o.disc_landmarks = 150;
    o.disc_radius_m = 2.0;
    return MakeInertialScene(o);
  }();
  return kScene;
}

const InertialScene& Fig14InertialScene() {
  static const InertialScene kScene = [] {
    InertialSceneOptions o;
    o.frames = 160;
    o.p0 = Vec3<double>(0.0, 0.0, 50.0);
    o.v0 = Vec3<double>(22.0, 0.0, 0.0);
    o.accel_world.setZero();
    o.strip_density_per_m2 = 0.055;
    o.seed = 3;
    return MakeInertialScene(o);
  }();
  return kScene;
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Fig13Update_Inertial_K10(benchmark::State& state) {
  using Filter = SlidingWindowFilter<InertialStereoModel<double>, 10, 160, 160, 160>;
  Fig13Update<Filter>(state, Fig13InertialScene());
}
BENCHMARK(BM_Fig13Update_Inertial_K10)->Apply(Fig13Timing);

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Fig14a_InertialSwf10(benchmark::State& state) {
  using Filter = SlidingWindowFilter<InertialStereoModel<double>, 10, 600, 64, 128>;
  Fig14a<Filter>(state, Fig14InertialScene(), SwfMode::kSlidingWindow);
}
BENCHMARK(BM_Fig14a_InertialSwf10)->Apply(Fig14aFrames);

// ---- the dense factorization alone ----------------------------------------------------------

using Dense540 = swf::estimator::DenseCholesky<double, 540>;

double FlopsOfCholesky(int n) { return static_cast<double>(n) * n * n / 3.0; }

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void FactorDense(Dense540* chol, const Eigen::MatrixXd& a) {
  chol->Reset(static_cast<int>(a.rows()));
  chol->AddSymmetric(0, a.data(), static_cast<int>(a.rows()), static_cast<int>(a.rows()));
  if (chol->Factorize() != swf::core::Status::kOk) std::abort();
}

void FactorEigen(Eigen::LLT<Eigen::MatrixXd>* llt, const Eigen::MatrixXd& a) {
  llt->compute(a);
  if (llt->info() != Eigen::Success) std::abort();
}

// Kernel argument: 0 = the one Configure picks (the widest the CPU has), 1 = portable 2-wide,
// 2 = AVX, 3 = AVX-512 (skipped where the CPU has none).
// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Cholesky_Dense(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Eigen::MatrixXd a = swf::testing::RandomSpd(n, 17);
  auto chol = std::make_unique<Dense540>();
  const auto kernel = static_cast<Dense540::Kernel>(state.range(1));
  if (!chol->SetKernel(kernel)) {
    state.SkipWithError("kernel not supported by this CPU");
    return;
  }
  for (auto _ : state) {
    FactorDense(chol.get(), a);
    benchmark::ClobberMemory();
  }
  state.counters["GFlop/s"] =
      benchmark::Counter(FlopsOfCholesky(n) * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Cholesky_Dense)
    ->ArgsProduct({{120, 510}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5);

// The picked kernel against the portable one, interleaved in the same iteration (the ratio
// does not depend on the machine's load); ratio = portable CPU / picked CPU.
// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_CholeskyKernelRatio(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Eigen::MatrixXd a = swf::testing::RandomSpd(n, 17);
  auto picked = std::make_unique<Dense540>();
  auto portable = std::make_unique<Dense540>();
  (void)portable->SetKernel(Dense540::Kernel::kPortable);
  double picked_s = 0.0;
  double portable_s = 0.0;
  for (auto _ : state) {
    const double t0 = ThreadCpuSeconds();
    FactorDense(picked.get(), a);
    const double t1 = ThreadCpuSeconds();
    FactorDense(portable.get(), a);
    const double t2 = ThreadCpuSeconds();
    picked_s += t1 - t0;
    portable_s += t2 - t1;
    benchmark::ClobberMemory();
  }
  const auto iterations = static_cast<double>(state.iterations());
  state.counters["picked_ms"] = 1e3 * picked_s / iterations;
  state.counters["portable_ms"] = 1e3 * portable_s / iterations;
  state.counters["picked_is_avx"] = picked->UsesAvx() ? 1 : 0;
  state.counters["ratio_portable_over_picked"] = portable_s / picked_s;
}
BENCHMARK(BM_CholeskyKernelRatio)
    ->Arg(120)
    ->Arg(510)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5);

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Cholesky_EigenLlt(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Eigen::MatrixXd a = swf::testing::RandomSpd(n, 17);
  Eigen::LLT<Eigen::MatrixXd> llt(n);
  for (auto _ : state) {
    FactorEigen(&llt, a);
    benchmark::ClobberMemory();
  }
  state.counters["GFlop/s"] =
      benchmark::Counter(FlopsOfCholesky(n) * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Cholesky_EigenLlt)->Arg(120)->Arg(510)->Unit(benchmark::kMillisecond)->Repetitions(5);

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_CholeskyRatio(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Eigen::MatrixXd a = swf::testing::RandomSpd(n, 17);
  auto chol = std::make_unique<Dense540>();
  Eigen::LLT<Eigen::MatrixXd> llt(n);
  double dense_s = 0.0;
  double eigen_s = 0.0;
  for (auto _ : state) {
    const double t0 = ThreadCpuSeconds();
    FactorDense(chol.get(), a);
    const double t1 = ThreadCpuSeconds();
    FactorEigen(&llt, a);
    const double t2 = ThreadCpuSeconds();
    dense_s += t1 - t0;
    eigen_s += t2 - t1;
    benchmark::ClobberMemory();
  }
  const auto iterations = static_cast<double>(state.iterations());
  state.counters["dense_ms"] = 1e3 * dense_s / iterations;
  state.counters["eigen_ms"] = 1e3 * eigen_s / iterations;
  state.counters["dense_GFlop/s"] = FlopsOfCholesky(n) * 1e-9 * iterations / dense_s;
  state.counters["eigen_GFlop/s"] = FlopsOfCholesky(n) * 1e-9 * iterations / eigen_s;
  state.counters["ratio_eigen_over_dense"] = eigen_s / dense_s;
}
BENCHMARK(BM_CholeskyRatio)->Arg(120)->Arg(510)->Unit(benchmark::kMillisecond)->Repetitions(5);

std::string KittiDir() { return swf::ground_cli::SharedDir() + "/data/kitti-vo/"; }

[[noreturn]] void Die(const std::string& error) {
  std::fprintf(stderr, "bench_estimator: %s\n", error.c_str());
  std::exit(1);
}

// The kitti-vo sample: 26 poses, 2,634 landmarks, 8,189 factors.
const swf::tools::KittiVoProblem& Kitti() {
  static const swf::tools::KittiVoProblem kProblem = [] {
    const std::string dir = KittiDir();
    swf::tools::KittiVoProblem p;
    std::string error;
    if (!swf::tools::LoadKittiVo(dir + "VO_calibration.txt", dir + "VO_camera_poses_large.txt",
                                 dir + "VO_stereo_factors_large.txt", &p, &error))
      Die(error);
    return p;
  }();
  return kProblem;
}

// A generated problem of KITTI sequence-00 size (77 poses, 15,638 landmarks, 52,544 factors,
// ~680 per pose; kitti_vo_synth.hpp), with the data set's calibration.
const swf::tools::KittiVoProblem& Kitti00() {
  static const swf::tools::KittiVoProblem kProblem = [] {
    swf::estimator::StereoCamera<double> camera;
    swf::tools::KittiVoProblem p;
    std::string error;
    if (!swf::tools::LoadKittiVoCalibration(KittiDir() + "VO_calibration.txt", &camera, &error) ||
        !swf::tools::GenerateKittiLike(camera, swf::tools::KittiLikeOptions{}, &p, nullptr, &error))
      Die(error);
    return p;
  }();
  return kProblem;
}

// Arg 0: the solver (its fixed-capacity filter instance) is built once, as the flight process
// builds its filter at start-up, and each iteration feeds the problem and solves, like Ceres's
// build + solve. Arg 1: the solver is built inside every iteration (a one-shot swf-vo run).
void SwfSolves(benchmark::State& state, const swf::tools::KittiVoProblem& problem, int window) {
  const bool build_each_time = state.range(0) != 0;
  auto solver = std::make_unique<swf::tools::KittiVoSolver>();
  swf::tools::KittiVoResult r;
  for (auto _ : state) {
    if (build_each_time) solver = std::make_unique<swf::tools::KittiVoSolver>();
    r = solver->Solve(problem, window);
    if (!r.ok) Die(r.error);
    // A const copy: DoNotOptimize on the member itself ("+m,r") corrupted the reported cost
    // (GCC 12, Google Benchmark 1.7.1: 6.95e-310 read back).
    const double cost = r.final_cost;
    benchmark::DoNotOptimize(cost);
  }
  state.counters["final_cost"] = r.final_cost;
  state.counters["instance_MB"] = static_cast<double>(r.instance.bytes) * 1e-6;
  state.counters["iterations"] = r.iterations;
  state.counters["max_prior_landmarks"] = r.max_prior_landmarks;
}

// Ceres (kitti_vo_ceres.hpp: SPARSE_SCHUR, one thread, swf-vo's tolerances): problem build +
// solve per iteration.
void CeresSolves(benchmark::State& state, const swf::tools::KittiVoProblem& problem) {
  double cost = 0;
  for (auto _ : state) {
    cost = swf::tools::SolveKittiVoWithCeres(problem).summary.final_cost;
    benchmark::DoNotOptimize(cost);
  }
  state.counters["final_cost"] = cost;
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_KittiVo_Swf(benchmark::State& state) { SwfSolves(state, Kitti(), 0); }
BENCHMARK(BM_KittiVo_Swf)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Repetitions(5);
// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_KittiVo_Ceres(benchmark::State& state) { CeresSolves(state, Kitti()); }
BENCHMARK(BM_KittiVo_Ceres)->Unit(benchmark::kMillisecond)->Repetitions(5);

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Kitti00_Swf(benchmark::State& state) { SwfSolves(state, Kitti00(), 0); }
BENCHMARK(BM_Kitti00_Swf)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Repetitions(5);
// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Kitti00_Ceres(benchmark::State& state) { CeresSolves(state, Kitti00()); }
BENCHMARK(BM_Kitti00_Ceres)->Unit(benchmark::kMillisecond)->Repetitions(5);

// Both solvers in the same iteration, interleaved (swf-vo built per solve, as a one-shot run),
// so the ratio does not depend on the machine's load: ratio = Ceres CPU / swf-vo CPU.
// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_ convention
void BM_Kitti00_SwfVsCeres(benchmark::State& state) {
  double swf_s = 0.0;
  double ceres_s = 0.0;
  double swf_cost = 0.0;
  double ceres_cost = 0.0;
  for (auto _ : state) {
    const double t0 = ThreadCpuSeconds();
    const swf::tools::KittiVoResult r = swf::tools::SolveKittiVo(Kitti00(), 0);
    const double t1 = ThreadCpuSeconds();
    ceres_cost = swf::tools::SolveKittiVoWithCeres(Kitti00()).summary.final_cost;
    const double t2 = ThreadCpuSeconds();
    if (!r.ok) Die(r.error);
    swf_cost = r.final_cost;
    swf_s += t1 - t0;
    ceres_s += t2 - t1;
  }
  const auto iterations = static_cast<double>(state.iterations());
  state.counters["swf_ms"] = 1e3 * swf_s / iterations;
  state.counters["ceres_ms"] = 1e3 * ceres_s / iterations;
  state.counters["ratio_ceres_over_swf"] = ceres_s / swf_s;
  state.counters["cost_rel_diff"] = std::abs(swf_cost - ceres_cost) / ceres_cost;
}
BENCHMARK(BM_Kitti00_SwfVsCeres)->Unit(benchmark::kMillisecond)->Repetitions(5);

// Sliding windows over the KITTI-00-sized problem (Arg: window; filter built once). Each holds
// ~680 landmarks in its prior and one solve takes minutes, so these are registered only when
// SWF_BENCH_KITTI00_WINDOWS is set (docs/benchmarks.md has the command).
void Kitti00SwfWindow(benchmark::State& state) {
  auto solver = std::make_unique<swf::tools::KittiVoSolver>();
  swf::tools::KittiVoResult r;
  for (auto _ : state) {
    r = solver->Solve(Kitti00(), static_cast<int>(state.range(0)));
    if (!r.ok) Die(r.error);
    // A const copy: DoNotOptimize on the member itself ("+m,r") corrupted the reported cost
    // (GCC 12, Google Benchmark 1.7.1: 6.95e-310 read back).
    const double cost = r.final_cost;
    benchmark::DoNotOptimize(cost);
  }
  state.counters["final_cost"] = r.final_cost;
  state.counters["iterations"] = r.iterations;
  state.counters["max_prior_landmarks"] = r.max_prior_landmarks;
  state.counters["factors_behind_camera"] = r.factors_behind_camera;
}
[[maybe_unused]] const bool kKitti00WindowsRegistered = [] {
  if (std::getenv("SWF_BENCH_KITTI00_WINDOWS") == nullptr) return false;
  benchmark::RegisterBenchmark("BM_Kitti00_SwfWindow", Kitti00SwfWindow)
      ->Arg(5)
      ->Arg(10)
      ->Arg(20)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1)
      ->Repetitions(1);
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
