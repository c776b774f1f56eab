// A small measurement-level scene generator for the estimator's own tests and benchmarks:
// a stereo rig looking straight down over a ground plane with relief, moving on a descent,
// sideways or not at all, observing landmarks with Gaussian pixel noise. (The simulator in sim/
// is the full generator; this one keeps estimator tests independent of it.)
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "swf/estimator/geometry.hpp"

namespace swf::estimator::testing {

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
inline StereoCamera<double> EdlRig() {
  const double fx = 512.0 / std::tan(12.5 * M_PI / 180.0);
  return StereoCamera<double>{fx, fx, 512.0, 384.0, 1.0};
}

// A landmark uniform in the disc of `radius` about (cx, cy) (rejection sampling), its height
// uniform in +-relief.
inline Vec3<double> LandmarkInDisc(std::mt19937_64* rng, double cx, double cy, double radius,
                                   double relief) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double x = 0.0;
  double y = 0.0;
  do {
    x = unit(*rng);
    y = unit(*rng);
  } while (x * x + y * y > 1.0);
  return Vec3<double>(cx + radius * x, cy + radius * y, relief * unit(*rng));
}

class SyntheticScene {
 public:
  explicit SyntheticScene(const SceneOptions& options) : options_(options), camera_(EdlRig()) {
    std::mt19937_64 rng(options.seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    // Camera looking down: camera x = world x, camera y = -world y, camera z = -world z (up).
    Mat3<double> down;
    down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
    const double extent = options.motion == SceneOptions::Motion::kSideways
                              ? options.step_m * options.frames + 60.0
                              : 0.0;
    if (options.motion == SceneOptions::Motion::kSideways) {
      const double half_width = 30.0;
      const int count = static_cast<int>(options.landmark_density_per_m2 * extent * 2 * half_width);
      for (int i = 0; i < count; ++i) {
        landmarks_.emplace_back(-30.0 + (unit(rng) + 1.0) * 0.5 * extent, half_width * unit(rng),
                                options.relief_m * unit(rng));
      }
    } else {
      for (int i = 0; i < options.num_landmarks; ++i)
        landmarks_.push_back(
            LandmarkInDisc(&rng, 0.0, 0.0, options.landmark_radius_m, options.relief_m));
    }
    frames_.resize(options.frames);
    for (int j = 0; j < options.frames; ++j) {
      SceneFrame& f = frames_[j];
      Vec3<double> jitter(gauss(rng), gauss(rng), gauss(rng));
      f.truth.R = down * ExpSO3<double>(Vec3<double>(options.jitter_rad * jitter));
      const double s = options.step_m * j;
      switch (options.motion) {
        case SceneOptions::Motion::kDescent:
          f.truth.t = Vec3<double>(0.0, 0.0, options.start_altitude_m - s);
          break;
        case SceneOptions::Motion::kSideways:
          f.truth.t = Vec3<double>(s, 0.0, options.start_altitude_m);
          break;
        case SceneOptions::Motion::kStatic:
          f.truth.t = Vec3<double>(0.0, 0.0, options.start_altitude_m);
          break;
      }
      for (std::size_t i = 0; i < landmarks_.size(); ++i) {
        const Vec3<double> p = f.truth.ApplyInverse(landmarks_[i]);
        if (p.z() <= 1.0) continue;
        const Vec3<double> z = camera_.Project(p);
        if (z.x() < 0 || z.x() >= 1024 || z.y() < 0 || z.z() < 0 || z.z() >= 768) continue;
        if (static_cast<int>(f.obs.size()) >= options.max_obs_per_frame) break;
        Vec3<double> noisy = z;
        for (int k = 0; k < 3; ++k) noisy[k] += options.sigma_px * gauss(rng);
        f.obs.push_back({static_cast<std::int64_t>(i), noisy});
      }
    }
  }

  // Plain-data accessors named like the members they expose (test fixture used by the tests,
  // benchmarks and swf-eval alike; renaming would churn every user for no reader's benefit).
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

}  // namespace swf::estimator::testing
