// Feeds a scene to a SlidingWindowFilter the way a lander would (the first pose from the initial
// state, later poses from an IMU-like motion input or the preintegrated IMU, the observations
// with the scene's pixel noise as R) and runs the filter over a whole scene, scoring the
// landmark map against truth after every frame. The estimator's tests, the benchmarks,
// swf-eval's experiments and swf-hazard's flight all run scenes through these.
#pragma once

#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <type_traits>
#include <vector>

#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/scene/inertial_scene.hpp"
#include "swf/scene/synthetic_scene.hpp"

namespace swf::scene {

using estimator::Mat6;
using estimator::SwfMode;
using estimator::SwfOptions;
using estimator::Vec15;
using estimator::Vec6;

// The filter options of a scene run: the first pose is the truth, stated to 1 mm and 10 urad.
SwfOptions FilterOptions(SwfMode mode);

// The motion input of an IMU-like source: the true relative motion between two frames,
// perturbed (when seeded) by exactly the Gaussian noise its square-root information states.
class MotionInput {
 public:
  // The paper experiments' motion-input noise: 10 cm and 2 mrad per frame (1 sigma).
  static constexpr double kSigmaM = 0.1;
  static constexpr double kSigmaRad = 0.002;

  // The exact relative motion, stated with these sigmas.
  explicit MotionInput(double sigma_m = kSigmaM, double sigma_rad = kSigmaRad);
  // The relative motion perturbed with draws from a generator seeded with `seed`.
  MotionInput(double sigma_m, double sigma_rad, std::uint64_t seed);

  // from^-1 * to, perturbed when seeded (one draw per axis per call).
  Pose<double> Between(const Pose<double>& from, const Pose<double>& to);
  const Mat6<double>& SqrtInformation() const { return sqrt_information_; }

 private:
  double sigma_m_;
  double sigma_rad_;
  bool perturbed_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  Mat6<double> sqrt_information_ = Mat6<double>::Zero();
};

// Adds frame j: its pose (frame 0 the truth, later frames through the motion input) and its
// observations. Returns the status of adding the pose (observations beyond the filter's capacity
// are refused by the filter, as in flight).
template <typename Filter>
core::Status AddFrame(Filter* swf, const SyntheticScene& scene, std::size_t j,
                      MotionInput* motion) {
  const SceneFrame& f = scene.frames()[j];
  const core::Status added =
      j == 0 ? swf->AddPose(f.truth)
             : swf->AddPoseWithMotion(motion->Between(scene.frames()[j - 1].truth, f.truth),
                                      motion->SqrtInformation());
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options().sigma_px;
  for (const SceneObservation& o : f.obs) (void)swf->AddObservation(o.id, o.z, r_sqrt);
  return added;
}

// The first-pose prior of an inertial scene run: the true pose (1 sigma per position axis and
// attitude axis as given) and velocity (5 cm/s), the biases unknown (zero) with the MEMS turn-on
// sigmas (0.01 rad/s, 0.1 m/s^2).
Mat15<double> FirstPoseCovariance(double sigma_m, double sigma_rad);

// Adds frame j of an inertial scene: frame 0 the true state with zero biases under
// `first_pose_covariance`, later frames the IMU preintegrated at the filter's current bias
// estimate (so the first-order bias correction stays small); then its observations. Returns the
// status of adding the state (kNumericalFailure when the preintegration failed).
template <typename Filter>
core::Status AddFrame(Filter* swf, const InertialScene& scene, std::size_t j,
                      const Mat15<double>& first_pose_covariance) {
  core::Status added = core::Status::kNumericalFailure;
  if (j == 0) {
    NavState<double> start = scene.truth[0];
    start.biases = ImuBiases<double>{};
    added = swf->AddFirstPose(start, first_pose_covariance);
  } else {
    ImuPreintegration<double> pim;
    Mat15<double> q_sqrt;
    if (PreintegrateFrame(scene, j, swf->NewestPose().biases, &pim, &q_sqrt))
      added = swf->AddPoseWithMotion(pim, q_sqrt);
  }
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / scene.options.sigma_px;
  for (const auto& [id, z] : scene.obs[j]) (void)swf->AddObservation(id, z, r_sqrt);
  return added;
}

inline bool UpdateFailed(core::Status s) {
  return s != core::Status::kOk && s != core::Status::kNotConverged;
}

// Per-frame record of a stereo scene run.
struct Trace {
  std::vector<double> mse_m2;     // mean squared error of every landmark estimated so far
  std::vector<double> update_ms;  // wall time of Update()
  std::vector<double> state_dim;  // the filter's state dimension after the update
  double rms_m = 0.0;             // landmark RMS after the last frame
  double final_pose_error_m = 0.0;
  int failures = 0;  // Update() results other than kOk / kNotConverged
  core::Status configured = core::Status::kOk;
  int rejected_poses = 0;  // poses the filter refused
};

// Configures *swf for the scene (the scene's camera, `max_init_depth_m`) and runs every frame
// through it; `after_update(swf, j)`, when given, is called after each frame's Update (to read
// covariances, say). Stops at once when Configure fails (Trace::configured says why).
template <typename Filter>
Trace RunScene(
    Filter* swf, const SyntheticScene& scene, const SwfOptions& options, MotionInput motion,
    const std::type_identity_t<std::function<void(Filter*, std::size_t)>>& after_update = {},
    double max_init_depth_m = 0.0) {
  Trace trace;
  typename Filter::ModelType model;
  model.camera = scene.camera();
  model.max_init_depth_m = max_init_depth_m;
  trace.configured = swf->Configure(model, options);
  if (trace.configured != core::Status::kOk) return trace;
  std::vector<Vec3<double>> estimate(scene.landmarks().size());
  std::vector<bool> known(scene.landmarks().size(), false);
  for (std::size_t j = 0; j < scene.frames().size(); ++j) {
    trace.rejected_poses += AddFrame(swf, scene, j, &motion) == core::Status::kOk ? 0 : 1;
    const auto start = std::chrono::steady_clock::now();
    const core::Status status = swf->Update();
    trace.update_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    trace.failures += UpdateFailed(status) ? 1 : 0;
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
    if (after_update) after_update(swf, j);
  }
  if (!trace.mse_m2.empty()) trace.rms_m = std::sqrt(trace.mse_m2.back());
  trace.final_pose_error_m = (swf->NewestPose().t - scene.frames().back().truth.t).norm();
  return trace;
}

// Per-frame record of an inertial scene run.
struct InertialTrace {
  std::vector<NavState<double>> newest;   // the newest state after each frame
  std::vector<Mat15<double>> covariance;  // its covariance, when computed
  double landmark_rms_m = 0.0;            // active landmarks after the last frame (1e9: none)
  int failed_updates = 0;
  std::uint64_t allocations = 0;  // heap allocations over the frames, counted by Scope
  core::Status configured = core::Status::kOk;
  int rejected_frames = 0;  // states the filter refused or whose preintegration failed
};

// A Scope that counts nothing (Scope: constructed where counting starts, Count() read at the
// end; the tests pass swf::testing::AllocationScope).
struct NoAllocationCount {
  std::uint64_t Count() const {
    return 0;
  }  // NOLINT(readability-convert-member-functions-to-static)
};

// Configures *swf with the scene's model and `mode`, then runs every frame (AddFrame above) and
// its Update; the newest state's covariance is computed every `covariance_every` frames and at
// the last (0: never). Stops at once when Configure fails.
template <typename Scope = NoAllocationCount, typename Filter>
InertialTrace RunInertialScene(Filter* swf, const InertialScene& s, SwfMode mode,
                               const Mat15<double>& first_pose_covariance, int covariance_every) {
  InertialTrace result;
  SwfOptions options;
  options.mode = mode;
  result.configured = swf->Configure(s.model, options);
  if (result.configured != core::Status::kOk) return result;
  result.newest.reserve(s.truth.size());
  result.covariance.reserve(s.truth.size());
  Scope scope;
  for (std::size_t j = 0; j < s.truth.size(); ++j) {
    result.rejected_frames +=
        AddFrame(swf, s, j, first_pose_covariance) == core::Status::kOk ? 0 : 1;
    result.failed_updates += UpdateFailed(swf->Update()) ? 1 : 0;
    result.newest.push_back(swf->NewestPose());
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

}  // namespace swf::scene
