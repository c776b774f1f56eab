// ImuModel: a simulated strapdown IMU riding on the simulator's trajectory, so its samples agree
// with the rendered camera motion.
//
// The continuous motion. Trajectory defines camera poses only at frames: position
// p(t) = start + velocity (t - t_0) (exact between frames) and attitude
// world_R_camera = S(t - t_0) Exp(phi_k) (S the steered attitude of trajectory.hpp: heading,
// nadir, the constant offset and the constant body rate omega; phi_k the attitude jitter).
// Between frames the attitude is S(t - t_0) Exp(phi(t)) with phi(t) the natural cubic spline
// through the phi_k: it passes through every frame's pose and its angular acceleration is
// continuous (a curve with kinks in the acceleration, e.g. Catmull-Rom, puts steps into the
// specific force through the lever arm that no sampled integration follows). Then, analytically,
//     camera body rate       w_c = Exp(phi)^T omega + Jr(phi) phi'    (Jr: right Jacobian, SO(3))
//     IMU pose               world_T_imu = world_T_camera * camera_T_imu
//     IMU rate               w = R_ci^T w_c
//     IMU acceleration       a = R_c (w_c' x r + w_c x (w_c x r))   (r = camera_t_imu lever arm;
//                                                                     the camera itself does not
//                                                                     accelerate: its velocity,
//                                                                     vertical and horizontal, is
//                                                                     constant)
//     specific force         f = R_imu^T (a - g_world),  g_world = (0, 0, -gravity)
// (w_c' by a central difference of the analytic w_c, 1e-5 s: only the small lever-arm term
// uses it).
//
// The sensor. Each axis of each triad reads
//     y = (1 + s) x + b(t) + n,     clipped to +-range (then flagged saturated)
// with s a scale-factor error drawn once, n white noise of density N (variance N^2 rate), and the
// bias b = turn-on offset (drawn once) + a first-order Gauss-Markov in-run term (stationary
// sigma = the bias instability, correlation time tau) + a random walk (density K). The true bias
// of every sample and the scale factors are kept for evaluation. Seeded: same seed, same bits.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/estimator/imu_preintegration.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sim {

// Error model of one triad (gyroscope: rad/s; accelerometer: m/s^2).
struct ImuTriadErrors {
  double noise_density = 0.0;     // unit / sqrt(Hz)
  double bias_random_walk = 0.0;  // unit / s / sqrt(Hz)
  double bias_instability = 0.0;  // unit, stationary sigma of the Gauss-Markov term
  double bias_correlation_s = 100.0;
  double turn_on_bias_sigma = 0.0;  // unit
  double scale_factor_sigma = 0.0;  // fraction (1e-6 = 1 ppm)
  double range = 0.0;               // unit; 0 = never saturates
};

struct ImuModelOptions {
  const char* part = "ideal";  // the unit the parameters describe
  double rate_hz = 400.0;
  double gravity_mps2 = 1.625;  // the Moon's surface gravity (the simulator's terrain is lunar)
  ImuTriadErrors gyro;
  ImuTriadErrors accel;
  estimator::Pose<double> camera_T_imu;  // the IMU in the left camera frame
  std::uint64_t seed = 1;
  // Sampling goes on this long past the last frame (seconds, at most 10): a consumer whose frame
  // stamps may come late (jittered exposure stamps) still finds samples up to them.
  double tail_s = 0.0;
  // The unit's clock against the cameras': an instant t is stamped t + clock_offset_s (a
  // camera-IMU desynchronization; at most 1 s either way). The samples still cover the
  // trajectory's instants; only their stamps move.
  double clock_offset_s = 0.0;
};

// Honeywell HG1700 (tactical grade, ring-laser gyros).
ImuModelOptions TacticalImu();
// Analog Devices ADIS16448 (MEMS; the unit on EuRoC's MAV, ../shared/data/euroc-v101).
ImuModelOptions MemsImu();
// The same unit without any error (no noise, bias, scale factor or clipping).
ImuModelOptions Noiseless(ImuModelOptions options);
// A unit's noise densities and random walks as the estimator's ImuNoise (the Gauss-Markov term
// added as the random walk it looks like over its correlation time, sigma sqrt(2 / tau)).
estimator::ImuNoise<double> NoiseModelOf(const ImuModelOptions& options);

class ImuModel {
 public:
  // Samples the whole trajectory, from its first frame to one sample past its last (plus
  // tail_s). Returns kInvalidArgument for a rate outside [10, 10000] Hz, negative error terms, a
  // non-positive correlation time, a tail outside [0, 10] s or an unconfigured trajectory.
  core::Status Configure(const ImuModelOptions& options, const Trajectory& trajectory);

  const std::vector<estimator::ImuSample<double>>& Samples() const { return samples_; }
  // The bias each sample carries (what an estimator should converge to).
  const std::vector<estimator::ImuBiases<double>>& TrueBiases() const { return true_biases_; }
  const Eigen::Vector3d& GyroScaleFactor() const { return gyro_scale_; }
  const Eigen::Vector3d& AccelScaleFactor() const { return accel_scale_; }
  // NoiseModelOf(the unit).
  estimator::ImuNoise<double> NoiseModel() const;
  Eigen::Vector3d GravityWorld() const { return {0.0, 0.0, -options_.gravity_mps2}; }

  // The continuous truth at t_s seconds on the trajectory's clock (t_s = FrameTimeNs / 1e9 at
  // frames): IMU pose and velocity, and the error-free rate and specific force.
  estimator::InertialState<double> TrueState(double t_s) const;
  Eigen::Vector3d TrueRate(double t_s) const;
  Eigen::Vector3d TrueSpecificForce(double t_s) const;

 private:
  // Jitter curve phi(t) and its first derivative, in the camera frame.
  void Jitter(double t_s, Eigen::Vector3d* phi, Eigen::Vector3d* phi_rate) const;
  Eigen::Vector3d CameraRate(double t_s) const;

  ImuModelOptions options_;
  TrajectoryOptions trajectory_;
  std::vector<Eigen::Vector3d> knots_;       // phi_k per frame
  std::vector<Eigen::Vector3d> knot_rates_;  // d phi / dt at the knots (spline)
  std::vector<estimator::ImuSample<double>> samples_;
  std::vector<estimator::ImuBiases<double>> true_biases_;
  Eigen::Vector3d gyro_scale_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_scale_ = Eigen::Vector3d::Zero();
};

}  // namespace swf::sim
