// The estimator's scenario tests run a SyntheticScene through swf::scene's runner with the
// motion input perturbed by the noise its information states; these wrappers add the checks
// every run must pass (the filter configures and accepts every pose).
#pragma once

#include <gtest/gtest.h>

#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/scene/runner.hpp"

namespace swf::estimator::testing {

using scene::EdlRig;
using scene::Fig15Sideways;
using scene::SceneFrame;
using scene::SceneObservation;
using scene::SceneOptions;
using scene::StaticRig;
using scene::SyntheticScene;
using RunResult = scene::Trace;

template <typename Filter>
RunResult RunScene(Filter* swf, const SyntheticScene& scene, const SwfOptions& options,
                   double max_init_depth_m = 0.0) {
  const RunResult r =
      scene::RunScene(swf, scene, options,
                      scene::MotionInput(scene::MotionInput::kSigmaM, scene::MotionInput::kSigmaRad,
                                         scene.options().seed + 1000),
                      {}, max_init_depth_m);
  EXPECT_EQ(r.configured, core::Status::kOk);
  EXPECT_EQ(r.rejected_poses, 0);
  return r;
}

template <int K, int P = 160>
using StereoSwf = SlidingWindowFilter<StereoModel<double>, K, 160, 160, P>;
template <int K, int P = 160>
using InverseDepthSwf = SlidingWindowFilter<InverseDepthStereoModel<double>, K, 160, 160, P>;

inline SwfOptions ModeOptions(SwfMode mode) { return scene::FilterOptions(mode); }

}  // namespace swf::estimator::testing
