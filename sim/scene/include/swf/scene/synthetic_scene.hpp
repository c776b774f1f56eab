// The measurement-level stereo scene of the estimator's tests, the benchmarks and swf-eval's
// paper experiments: a stereo rig looking straight down over a ground plane with relief, moving
// on a descent, sideways or not at all, observing landmarks with Gaussian pixel noise. Every
// landmark is observed in every frame it projects into (no track lengths, outliers or
// occlusion: those are sim::MeasurementScenario's). Needs only the estimator's geometry, so the
// flight-only build (estimator tests under emulation) has it too.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "swf/estimator/geometry.hpp"

namespace swf::scene {

using estimator::Pose;
using estimator::StereoCamera;
using estimator::Vec3;

struct SceneObservation {
  std::int64_t id;
  Vec3<double> z;
};

struct SceneFrame {
  Pose<double> truth;  // world_T_camera
  std::vector<SceneObservation> obs;
};

struct SceneOptions {
  enum class Motion { kDescent, kSideways, kStatic };
  Motion motion = Motion::kDescent;
  int frames = 40;
  double start_altitude_m = 100.0;
  double step_m = 1.5;  // per frame: down (descent) or along x (sideways)
  int num_landmarks = 150;
  double landmark_radius_m = 2.0;         // descent/static: disc around the nadir point
  double landmark_density_per_m2 = 0.05;  // sideways: landmarks per square metre of ground
  double relief_m = 1.0;
  double sigma_px = 0.5;
  double jitter_rad = 0.005;  // attitude jitter per frame (1 sigma)
  int max_obs_per_frame = 1000;
  std::uint64_t seed = 1;
};

// The paper's EDL rig: 1 m baseline, ~25 deg horizontal FOV, 1024 x 768.
StereoCamera<double> EdlRig();

// A landmark uniform in the disc of `radius` about (cx, cy) (rejection sampling), its height
// uniform in +-relief.
Vec3<double> LandmarkInDisc(std::mt19937_64* rng, double cx, double cy, double radius,
                            double relief);

// The paper's static rig (Fig. 12, section 4.2.4): cameras 30 m above 30 landmarks within 5 m
// of the nadir, no jitter, every landmark seen in every frame.
SceneOptions StaticRig();

// The paper's sideways passes at 50 m: Fig. 15's at 3.3 m per frame (~85% overlap, ~25 features
// per frame, landmarks entering and leaving) and Fig. 14's run-time scene at 2.2 m per frame.
SceneOptions Fig15Sideways();
SceneOptions Fig14Sideways();

class SyntheticScene {
 public:
  explicit SyntheticScene(const SceneOptions& options);

  // Plain-data accessors named like the members they expose (used by the tests, benchmarks and
  // swf-eval alike; renaming would churn every user for no reader's benefit).
  // NOLINTBEGIN(readability-identifier-naming)
  const std::vector<SceneFrame>& frames() const { return frames_; }
  std::vector<SceneFrame>& mutable_frames() { return frames_; }  // to inject faults
  const std::vector<Vec3<double>>& landmarks() const { return landmarks_; }
  const StereoCamera<double>& camera() const { return camera_; }
  const SceneOptions& options() const { return options_; }
  // NOLINTEND(readability-identifier-naming)

 private:
  SceneOptions options_;
  StereoCamera<double> camera_;
  std::vector<Vec3<double>> landmarks_;
  std::vector<SceneFrame> frames_;
};

}  // namespace swf::scene
