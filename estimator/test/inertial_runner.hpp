// The stereo-inertial filter run over an InertialScene, for the estimator's inertial tests: the
// newest state (and, when asked, its covariance) after every frame, the landmark RMS at the end,
// failed updates and the heap allocations counted over the run.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "inertial_scene.hpp"
#include "swf/estimator/inertial_model.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/testing/allocation_counter.hpp"

namespace swf::estimator::testing {

using State = NavState<double>;
using Pim = ImuPreintegration<double>;

// The default descent (inertial_scene.hpp) with this seed and length.
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

struct RunResult {
  std::vector<State> newest;              // the newest state after each frame
  std::vector<Mat15<double>> covariance;  // its covariance, when computed
  double landmark_rms_m = 0.0;
  int failed_updates = 0;
  std::uint64_t allocations = 0;
};

template <int K, int P>
RunResult RunFilter(const InertialScene& s, SwfMode mode, int covariance_every) {
  using Filter = SlidingWindowFilter<InertialStereoModel<double>, K, 200, 200, P>;
  auto swf = std::make_unique<Filter>();
  SwfOptions options;
  options.mode = mode;
  EXPECT_EQ(swf->Configure(s.model, options), core::Status::kOk);
  // Start: the true pose and velocity known to a few cm, biases unknown (zero) with the
  // datasheet's turn-on sigmas.
  State start = s.truth[0];
  start.biases = ImuBiases<double>{};
  Vec15<double> sigma;
  sigma << Vec3<double>::Constant(0.05), Vec3<double>::Constant(0.002),
      Vec3<double>::Constant(0.05), Vec3<double>::Constant(0.01), Vec3<double>::Constant(0.1);
  EXPECT_EQ(swf->AddFirstPose(start, Mat15<double>(sigma.cwiseAbs2().asDiagonal())),
            core::Status::kOk);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / s.options.sigma_px;
  RunResult result;
  result.newest.reserve(s.truth.size());
  result.covariance.reserve(s.truth.size());
  Pim pim;
  Mat15<double> q_sqrt;
  swf::testing::AllocationScope scope;
  for (std::size_t j = 0; j < s.truth.size(); ++j) {
    if (j > 0) {
      // Integrated at the current bias estimate, so the first-order correction stays small.
      EXPECT_TRUE(PreintegrateFrame(s, j, swf->NewestPose().biases, &pim, &q_sqrt));
      EXPECT_EQ(swf->AddPoseWithMotion(pim, q_sqrt), core::Status::kOk);
    }
    for (const auto& [id, z] : s.obs[j]) (void)swf->AddObservation(id, z, r_sqrt);
    const core::Status status = swf->Update();
    result.failed_updates +=
        status == core::Status::kOk || status == core::Status::kNotConverged ? 0 : 1;
    result.newest.push_back(swf->NewestPose());
    // Every covariance_every frames and at the last (0: never).
    const bool last = j + 1 == s.truth.size();
    if (covariance_every > 0 && (last || j % covariance_every == 0) &&
        swf->ComputeCovariances() == core::Status::kOk)
      result.covariance.push_back(swf->NewestStateCovariance());
  }
  result.allocations = scope.Count();
  double sum = 0.0;
  int n = 0;
  swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& position, int) {
    sum += (position - s.landmarks[static_cast<std::size_t>(id)]).squaredNorm();
    ++n;
  });
  result.landmark_rms_m = n > 0 ? std::sqrt(sum / n) : 1e9;
  return result;
}

}  // namespace swf::estimator::testing
