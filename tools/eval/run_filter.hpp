// Runs a SlidingWindowFilter over a measurement-level SyntheticScene the way swf-eval's
// experiments need it: first pose from truth (with the tight first-pose prior), later poses from
// an IMU-like relative motion perturbed with exactly the noise its information matrix states,
// and pixel noise matching R. Records the landmark MSE, run time and state size per frame, and
// calls an optional hook after every Update (used by the NEES experiment to read covariances).
#pragma once

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "../../estimator/test/synthetic_scene.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"

namespace swf::eval {

using estimator::testing::SceneOptions;
using estimator::testing::SyntheticScene;

// Per-frame record of one run.
struct Trace {
  std::vector<double> mse_m2;     // mean squared landmark error of every landmark seen so far
  std::vector<double> update_ms;  // wall time of Update()
  std::vector<double> state_dim;  // 6 * poses + 3 * active landmarks
  double final_rms_m = 0.0;
  int failures = 0;  // Update() results other than kOk / kNotConverged
};

// Capacities: windows up to 40 poses, 300 landmarks active, 200 per frame, 160 in the prior.
using Filter = estimator::SlidingWindowFilter<estimator::StereoModel<double>, 40, 300, 200, 160>;
using BigBatch = estimator::SlidingWindowFilter<estimator::StereoModel<double>, 160, 4000, 64, 1>;
// The same capacities with anchored inverse-depth landmarks.
using InverseDepthFilter =
    estimator::SlidingWindowFilter<estimator::InverseDepthStereoModel<double>, 40, 300, 200, 160>;

// Motion-input noise of the experiments: 10 cm and 2 mrad per frame (1 sigma).
inline constexpr double kMotionSigmaM = 0.1;
inline constexpr double kMotionSigmaRad = 0.002;

template <typename F>
Trace RunFilter(const SyntheticScene& scene, estimator::SwfMode mode, int window,
                std::uint64_t seed, const std::function<void(F*, std::size_t)>& after_update = {},
                double q_t = kMotionSigmaM, double q_r = kMotionSigmaRad,
                bool first_estimate_jacobians = true) {
  using estimator::Mat3;
  using estimator::Mat6;
  using estimator::Vec3;
  auto swf = std::make_unique<F>();
  typename F::ModelType model;
  model.camera = scene.camera();
  estimator::SwfOptions options;
  options.mode = mode;
  options.window_size = window;
  options.first_pose_sigma_m = 1e-3;
  options.first_pose_sigma_rad = 1e-5;
  options.first_estimate_jacobians = first_estimate_jacobians;
  if (swf->Configure(model, options) != core::Status::kOk) std::abort();
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  q_sqrt.diagonal() << Vec3<double>::Constant(1 / q_t), Vec3<double>::Constant(1 / q_r);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options().sigma_px;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vec3<double>> estimate(scene.landmarks().size());
  std::vector<bool> known(scene.landmarks().size(), false);
  Trace trace;
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    const auto& f = scene.frames()[j];
    if (j == 0) {
      (void)swf->AddPose(f.truth);
    } else {
      const estimator::Pose<double> u = scene.frames()[j - 1].truth.Inverse() * f.truth;
      estimator::Vec6<double> noise;
      for (int k = 0; k < 6; ++k) noise[k] = (k < 3 ? q_t : q_r) * gauss(rng);
      (void)swf->AddPoseWithMotion(u.Retract(noise), q_sqrt);
    }
    for (const auto& o : f.obs) (void)swf->AddObservation(o.id, o.z, r_sqrt);
    const auto start = std::chrono::steady_clock::now();
    const core::Status status = swf->Update();
    trace.update_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    trace.failures +=
        (status == core::Status::kOk || status == core::Status::kNotConverged) ? 0 : 1;
    trace.state_dim.push_back(swf->Summary().state_dimension);
    for (const auto& r : swf->Retired()) {
      estimate[r.id] = r.position;
      known[r.id] = true;
    }
    swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) {
      estimate[id] = p;
      known[id] = true;
    });
    double sum = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < estimate.size(); ++i) {
      if (!known[i]) continue;
      sum += (estimate[i] - scene.landmarks()[i]).squaredNorm();
      ++n;
    }
    trace.mse_m2.push_back(n > 0 ? sum / n : 0.0);
    if (after_update) after_update(swf.get(), j);
  }
  trace.final_rms_m = std::sqrt(trace.mse_m2.back());
  return trace;
}

}  // namespace swf::eval
