#include "swf/scene/inertial_scene.hpp"

#include <cmath>
#include <random>

namespace swf::scene {

InertialScene MakeInertialScene(const InertialSceneOptions& o) {
  InertialScene s;
  s.options = o;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  s.model.stereo.camera = EdlRig();
  s.model.gravity_world_mps2 = Vec3<double>(0.0, 0.0, -1.625);  // the Moon
  // Camera looking down, mounted with a lever arm and a small misalignment from the IMU.
  Mat3<double> down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  s.model.imu_T_camera.R = estimator::ExpSO3<double>(Vec3<double>(0.02, -0.01, 0.5));
  s.model.imu_T_camera.t = Vec3<double>(0.3, -0.2, 0.1);
  s.r0 = down * s.model.imu_T_camera.R.transpose();
  // MEMS-class noise (ADIS16448 datasheet order of magnitude) and turn-on biases.
  s.noise.gyro_noise_density = 2e-4;
  s.noise.accel_noise_density = 2e-3;
  s.noise.gyro_random_walk = 2e-5;
  s.noise.accel_random_walk = 2e-4;
  s.true_biases.gyro_radps = Vec3<double>(3e-3, -2e-3, 4e-3);
  s.true_biases.accel_mps2 = Vec3<double>(0.05, -0.04, 0.03);
  const auto step_us = static_cast<std::int64_t>(std::llround(1e6 / o.imu_rate_hz));
  const auto frame_step_us = static_cast<std::int64_t>(std::llround(1e6 / o.frame_rate_hz));
  const std::int64_t end_us = (o.frames - 1) * frame_step_us + step_us;
  const double sg = s.noise.gyro_noise_density * std::sqrt(o.imu_rate_hz);
  const double sa = s.noise.accel_noise_density * std::sqrt(o.imu_rate_hz);
  for (std::int64_t t = 0, k = 0; t <= end_us; t += step_us, ++k) {
    const NavState<double> x = s.TrueState(1e-6 * static_cast<double>(t));
    const Vec3<double> force =
        x.world_T_imu.R.transpose() * (o.accel_world - s.model.gravity_world_mps2);
    ImuSample<double> sample;
    sample.t_us = t;
    sample.seq = k;
    for (int a = 0; a < 3; ++a) {
      sample.gyro_radps[a] = o.rate_body[a] + s.true_biases.gyro_radps[a] + sg * gauss(rng);
      sample.accel_mps2[a] = force[a] + s.true_biases.accel_mps2[a] + sa * gauss(rng);
    }
    s.samples.push_back(sample);
  }
  if (o.strip_density_per_m2 > 0.0) {
    const double length = std::abs(o.v0.x()) * o.frames / o.frame_rate_hz + 120.0;
    const int count = static_cast<int>(o.strip_density_per_m2 * length * 60.0);
    for (int i = 0; i < count; ++i)
      s.landmarks.emplace_back(o.p0.x() - 60.0 + 0.5 * (unit(rng) + 1.0) * length,
                               o.p0.y() + 30.0 * unit(rng), o.relief_m * unit(rng));
  } else {
    for (int i = 0; i < o.disc_landmarks; ++i)
      s.landmarks.push_back(LandmarkInDisc(&rng, o.p0.x(), o.p0.y(), o.disc_radius_m, o.relief_m));
  }
  for (int j = 0; j < o.frames; ++j) {
    s.frame_us.push_back(j * frame_step_us);
    NavState<double> x = s.TrueState(1e-6 * static_cast<double>(j * frame_step_us));
    x.biases = s.true_biases;
    s.truth.push_back(x);
    const Pose<double> camera = s.model.CameraPose(x);
    s.obs.emplace_back();
    for (std::size_t i = 0; i < s.landmarks.size(); ++i) {
      const Vec3<double> p = camera.ApplyInverse(s.landmarks[i]);
      if (p.z() <= 1.0) continue;
      Vec3<double> z = s.model.stereo.camera.Project(p);
      if (z.x() < 0 || z.x() >= 1024 || z.y() < 0 || z.z() < 0 || z.z() >= 768) continue;
      for (int k = 0; k < 3; ++k) z[k] += o.sigma_px * gauss(rng);
      s.obs.back().emplace_back(static_cast<std::int64_t>(i), z);
    }
  }
  return s;
}

bool PreintegrateFrame(const InertialScene& s, std::size_t j, const ImuBiases<double>& at,
                       ImuPreintegration<double>* pim, Mat15<double>* sqrt_information) {
  estimator::IntervalSummary interval;
  return pim->Reset(s.noise, at) == core::Status::kOk &&
         estimator::PreintegrateInterval(
             s.samples.data(), static_cast<int>(s.samples.size()), s.frame_us[j - 1], s.frame_us[j],
             estimator::SampleHold::kMidpoint, 0.02, pim, &interval) == core::Status::kOk &&
         InertialStereoModel<double>::ProcessSqrtInformation(*pim, sqrt_information);
}

}  // namespace swf::scene
