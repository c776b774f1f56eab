// The stereo-inertial scene of the estimator's tests and the benchmarks: the IMU moves on a
// smooth analytic path (position p0 + v0 t + a t^2 / 2, attitude R0 Exp(w t) with a constant
// body rate w), so its samples are exact (rate w, specific force R(t)^T (a - g)) before the
// sensor's white noise and constant biases are added. A camera looking down through a lever arm
// sees landmarks on the ground: a disc under the start (a descent, paper Fig. 13) or a strip
// along the path (a sideways pass, Fig. 14a).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "swf/estimator/imu_preintegration.hpp"
#include "swf/estimator/inertial_model.hpp"
#include "swf/scene/synthetic_scene.hpp"

namespace swf::scene {

using estimator::ImuBiases;
using estimator::ImuNoise;
using estimator::ImuPreintegration;
using estimator::ImuSample;
using estimator::InertialStereoModel;
using estimator::Mat15;
using estimator::Mat3;
using estimator::NavState;

struct InertialSceneOptions {
  int frames = 40;
  double frame_rate_hz = 10.0;
  double imu_rate_hz = 200.0;
  Vec3<double> p0{0.0, 0.0, 60.0};
  Vec3<double> v0{0.4, -0.3, -4.0};
  Vec3<double> accel_world{0.05, 0.04, 0.6};  // braking
  Vec3<double> rate_body{0.02, -0.03, 0.05};
  // Landmarks: a disc of this radius under the start, or (strip_density > 0) a strip 60 m wide
  // along x with this many landmarks per square metre.
  int disc_landmarks = 150;
  double disc_radius_m = 8.0;
  double strip_density_per_m2 = 0.0;
  double relief_m = 1.0;
  double sigma_px = 0.5;
  std::uint64_t seed = 1;
};

struct InertialScene {
  InertialStereoModel<double> model;
  InertialSceneOptions options;
  ImuNoise<double> noise;
  ImuBiases<double> true_biases;
  std::vector<ImuSample<double>> samples;
  std::vector<std::int64_t> frame_us;
  std::vector<NavState<double>> truth;                                  // per frame
  std::vector<std::vector<std::pair<std::int64_t, Vec3<double>>>> obs;  // per frame
  std::vector<Vec3<double>> landmarks;

  // The noiseless IMU state at t seconds (biases zero).
  NavState<double> TrueState(double t) const {
    NavState<double> x;
    x.world_T_imu.R = r0 * estimator::ExpSO3<double>(Vec3<double>(options.rate_body * t));
    x.world_T_imu.t = options.p0 + options.v0 * t + 0.5 * t * t * options.accel_world;
    x.velocity_world_mps = options.v0 + options.accel_world * t;
    return x;
  }
  Mat3<double> r0 = Mat3<double>::Identity();
};

InertialScene MakeInertialScene(const InertialSceneOptions& o);

// Preintegrates the scene's samples between frames j - 1 and j at the biases `at` (the filter's
// current estimate) into *pim and its process square-root information; false on failure.
bool PreintegrateFrame(const InertialScene& s, std::size_t j, const ImuBiases<double>& at,
                       ImuPreintegration<double>* pim, Mat15<double>* sqrt_information);

}  // namespace swf::scene
