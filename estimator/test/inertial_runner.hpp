// The stereo-inertial filter run over an InertialScene (swf::scene's runner), for the
// estimator's inertial tests: the newest state (and, when asked, its covariance) after every
// frame, the landmark RMS at the end, failed updates and the heap allocations counted over the
// run; every run must configure and accept every state.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>

#include "swf/estimator/inertial_model.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/scene/runner.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::estimator::testing {

using scene::EdlRig;
using scene::InertialScene;
using scene::InertialSceneOptions;
using scene::MakeInertialScene;
using scene::PreintegrateFrame;
using State = NavState<double>;
using Pim = ImuPreintegration<double>;
using InertialRunResult = scene::InertialTrace;

// The default descent (swf/scene/inertial_scene.hpp) with this seed and length.
inline InertialScene DescentScene(std::uint64_t seed, int frames) {
  InertialSceneOptions o;
  o.seed = seed;
  o.frames = frames;
  return MakeInertialScene(o);
}

// Position error (m) and the biases' errors of a state against the truth.
struct StateError {
  double position_m = 0.0;
  double gyro_bias = 0.0;
  double accel_bias = 0.0;
};
inline StateError ErrorOf(const State& estimate, const State& truth) {
  return {(estimate.world_T_imu.t - truth.world_T_imu.t).norm(),
          (estimate.biases.gyro_radps - truth.biases.gyro_radps).norm(),
          (estimate.biases.accel_mps2 - truth.biases.accel_mps2).norm()};
}

// Start: the true pose and velocity known to a few cm, biases unknown (zero) with the
// datasheet's turn-on sigmas.
template <int K, int P>
InertialRunResult RunFilter(const InertialScene& s, SwfMode mode, int covariance_every) {
  auto swf = std::make_unique<SlidingWindowFilter<InertialStereoModel<double>, K, 200, 200, P>>();
  const InertialRunResult r = scene::RunInertialScene<swf::testing::AllocationScope>(
      swf.get(), s, mode, scene::FirstPoseCovariance(0.05, 0.002), covariance_every);
  EXPECT_EQ(r.configured, core::Status::kOk);
  EXPECT_EQ(r.rejected_frames, 0);
  return r;
}

}  // namespace swf::estimator::testing
