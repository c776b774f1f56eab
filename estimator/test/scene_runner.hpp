// Runs a SlidingWindowFilter over a SyntheticScene the way a lander would feed it (first pose
// from the initial state, later poses from an IMU-like relative motion with matching noise) and
// scores the landmark map against truth. Shared by the estimator's scenario tests.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "synthetic_scene.hpp"

namespace swf::estimator::testing {

struct RunResult {
  double rms_m = 0;                  // final landmark error against truth (all landmarks seen)
  std::vector<double> mse_by_frame;  // mean squared error of the estimates after each frame
  double final_pose_error_m = 0;
  int failures = 0;
};

template <typename Filter>
inline RunResult RunScene(Filter* swf, const SyntheticScene& scene, SwfOptions options,
                          bool track_mse = false, double max_init_depth_m = 0.0) {
  typename Filter::ModelType model;
  model.camera = scene.camera();
  model.max_init_depth_m = max_init_depth_m;
  EXPECT_EQ(swf->Configure(model, options), core::Status::kOk);
  // Relative motion from an IMU-like source: truth perturbed with the noise Q describes.
  constexpr double kSigmaT = 0.1;
  constexpr double kSigmaR = 0.002;
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  q_sqrt.diagonal() << Vec3<double>::Constant(1 / kSigmaT), Vec3<double>::Constant(1 / kSigmaR);
  std::mt19937_64 rng(scene.options().seed + 1000);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options().sigma_px;
  std::vector<Vec3<double>> estimate(scene.landmarks().size());
  std::vector<bool> known(scene.landmarks().size(), false);
  RunResult out;
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    const testing::SceneFrame& f = scene.frames()[j];
    core::Status added = core::Status::kOk;
    if (j == 0) {
      added = swf->AddPose(f.truth);
    } else {
      Pose<double> u = scene.frames()[j - 1].truth.Inverse() * f.truth;
      Vec6<double> noise;
      for (int k = 0; k < 6; ++k) noise[k] = (k < 3 ? kSigmaT : kSigmaR) * gauss(rng);
      u = u.Retract(noise);
      added = swf->AddPoseWithMotion(u, q_sqrt);
    }
    EXPECT_EQ(added, core::Status::kOk);
    for (const testing::SceneObservation& o : f.obs) (void)swf->AddObservation(o.id, o.z, r_sqrt);
    const core::Status s = swf->Update();
    out.failures += (s == core::Status::kOk || s == core::Status::kNotConverged) ? 0 : 1;
    for (const auto& r : swf->Retired()) {
      estimate[r.id] = r.position;
      known[r.id] = true;
    }
    swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) {
      estimate[id] = p;
      known[id] = true;
    });
    if (track_mse) {
      double sum = 0;
      int n = 0;
      for (std::size_t i = 0; i < estimate.size(); ++i) {
        if (!known[i]) continue;
        sum += (estimate[i] - scene.landmarks()[i]).squaredNorm();
        ++n;
      }
      out.mse_by_frame.push_back(n > 0 ? sum / n : 0.0);
    }
  }
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    if (!known[i]) continue;
    sum += (estimate[i] - scene.landmarks()[i]).squaredNorm();
    ++n;
  }
  out.rms_m = std::sqrt(sum / std::max(n, 1));
  out.final_pose_error_m = (swf->NewestPose().t - scene.frames().back().truth.t).norm();
  return out;
}

template <int K, int P = 160>
using StereoSwf = SlidingWindowFilter<StereoModel<double>, K, 160, 160, P>;
template <int K, int P = 160>
using InverseDepthSwf = SlidingWindowFilter<InverseDepthStereoModel<double>, K, 160, 160, P>;

inline SwfOptions ModeOptions(SwfMode mode) {
  SwfOptions o;
  o.mode = mode;
  o.first_pose_sigma_m = 1e-3;
  o.first_pose_sigma_rad = 1e-5;
  return o;
}

}  // namespace swf::estimator::testing
