// swf-eval's experiments run a SlidingWindowFilter over a measurement-level scene (swf::scene):
// first pose from truth (with the tight first-pose prior), later poses from an IMU-like relative
// motion perturbed with exactly the noise its information matrix states, and pixel noise
// matching R; the trace records the landmark MSE, run time and state size per frame, and an
// optional hook runs after every Update (the NEES experiment reads covariances there).
#pragma once

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <memory>

#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/scene/runner.hpp"

namespace swf::eval {

using scene::SceneOptions;
using scene::SyntheticScene;
using scene::Trace;

// Capacities: windows up to 40 poses, 300 landmarks active, 200 per frame, 160 in the prior.
using Filter = estimator::SlidingWindowFilter<estimator::StereoModel<double>, 40, 300, 200, 160>;
using BigBatch = estimator::SlidingWindowFilter<estimator::StereoModel<double>, 160, 4000, 64, 1>;
// The same capacities with anchored inverse-depth landmarks.
using InverseDepthFilter =
    estimator::SlidingWindowFilter<estimator::InverseDepthStereoModel<double>, 40, 300, 200, 160>;

}  // namespace swf::eval

// Compiled once, in run_filter.cpp: each translation unit that compiles a filter instance pays a
// minute of CPU for it (Eigen's machinery), and swf-eval's units and swf-hazard share these.
namespace swf::estimator {
extern template class SlidingWindowFilter<StereoModel<double>, 40, 300, 200, 160>;
extern template class SlidingWindowFilter<StereoModel<double>, 160, 4000, 64, 1>;
extern template class SlidingWindowFilter<InverseDepthStereoModel<double>, 40, 300, 200, 160>;
}  // namespace swf::estimator

namespace swf::eval {

// Motion-input noise of the experiments: 10 cm and 2 mrad per frame (1 sigma).
inline constexpr double kMotionSigmaM = scene::MotionInput::kSigmaM;
inline constexpr double kMotionSigmaRad = scene::MotionInput::kSigmaRad;

template <typename F>
Trace RunFilter(const SyntheticScene& scene, estimator::SwfMode mode, int window,
                std::uint64_t seed, const std::function<void(F*, std::size_t)>& after_update = {},
                double q_t = kMotionSigmaM, double q_r = kMotionSigmaRad,
                bool first_estimate_jacobians = true, bool vsdf_scalar_diagonal = false,
                int hold_sightings = 0, double hold_depth_precision = 0.0) {
  auto swf = std::make_unique<F>();
  estimator::SwfOptions options = scene::FilterOptions(mode);
  options.window_size = window;
  options.first_estimate_jacobians = first_estimate_jacobians;
  options.vsdf_scalar_diagonal = vsdf_scalar_diagonal;
  options.hold_sightings = hold_sightings;
  options.hold_depth_precision = hold_depth_precision;
  const Trace trace =
      scene::RunScene(swf.get(), scene, options, scene::MotionInput(q_t, q_r, seed), after_update);
  if (trace.configured != core::Status::kOk) std::abort();
  return trace;
}

}  // namespace swf::eval
