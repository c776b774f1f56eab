#include "swf/scene/synthetic_scene.hpp"

#include <cmath>

namespace swf::scene {

using estimator::Mat3;

StereoCamera<double> EdlRig() {
  const double fx = 512.0 / std::tan(12.5 * M_PI / 180.0);
  return StereoCamera<double>{fx, fx, 512.0, 384.0, 1.0};
}

Vec3<double> LandmarkInDisc(std::mt19937_64* rng, double cx, double cy, double radius,
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

SceneOptions StaticRig() {
  SceneOptions so;
  so.motion = SceneOptions::Motion::kStatic;
  so.start_altitude_m = 30.0;
  so.num_landmarks = 30;
  so.landmark_radius_m = 5.0;
  so.jitter_rad = 0.0;
  return so;
}

SceneOptions Fig15Sideways() {
  SceneOptions so;
  so.motion = SceneOptions::Motion::kSideways;
  so.start_altitude_m = 50.0;
  so.step_m = 3.3;
  so.landmark_density_per_m2 = 0.07;
  return so;
}

SceneOptions Fig14Sideways() {
  SceneOptions so = Fig15Sideways();
  so.step_m = 2.2;
  so.landmark_density_per_m2 = 0.055;
  return so;
}

SyntheticScene::SyntheticScene(const SceneOptions& options) : options_(options), camera_(EdlRig()) {
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
    f.truth.R = down * estimator::ExpSO3<double>(Vec3<double>(options.jitter_rad * jitter));
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

}  // namespace swf::scene
