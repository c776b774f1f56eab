#include "swf/sim/imu_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "swf/sim/rng.hpp"

namespace swf::sim {
namespace {

constexpr double kDegPerHourToRadPerS = std::numbers::pi / 180.0 / 3600.0;
constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kStandardGravity = 9.80665;
// Angle / velocity random walk per sqrt(hour) -> noise density per sqrt(Hz): divide by 60.
constexpr double kPerSqrtHourToPerSqrtHz = 1.0 / 60.0;

bool TriadValid(const ImuTriadErrors& e) {
  const double values[] = {e.noise_density,      e.bias_random_walk,   e.bias_instability,
                           e.turn_on_bias_sigma, e.scale_factor_sigma, e.range};
  for (const double v : values)
    if (!(v >= 0.0) || !std::isfinite(v)) return false;
  return e.bias_correlation_s > 0.0 && std::isfinite(e.bias_correlation_s);
}

// One triad's bias process: turn-on + Gauss-Markov + random walk.
class BiasProcess {
 public:
  BiasProcess(const ImuTriadErrors& e, Rng* rng) : e_(e) {
    for (int i = 0; i < 3; ++i) turn_on_(i) = e.turn_on_bias_sigma * rng->Gaussian();
    for (int i = 0; i < 3; ++i) markov_(i) = e.bias_instability * rng->Gaussian();
  }
  Eigen::Vector3d Value() const { return turn_on_ + markov_ + walk_; }
  void Advance(double dt_s, Rng* rng) {
    const double decay = std::exp(-dt_s / e_.bias_correlation_s);
    const double markov_step = e_.bias_instability * std::sqrt(1.0 - decay * decay);
    const double walk_step = e_.bias_random_walk * std::sqrt(dt_s);
    for (int i = 0; i < 3; ++i) markov_(i) = decay * markov_(i) + markov_step * rng->Gaussian();
    for (int i = 0; i < 3; ++i) walk_(i) += walk_step * rng->Gaussian();
  }

 private:
  ImuTriadErrors e_;
  Eigen::Vector3d turn_on_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d markov_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d walk_ = Eigen::Vector3d::Zero();
};

// (1 + s) x + b + n, clipped to the range; true when clipped.
bool Measure(const Eigen::Vector3d& truth, const Eigen::Vector3d& scale,
             const Eigen::Vector3d& bias, const ImuTriadErrors& e, double rate_hz, Rng* rng,
             Eigen::Vector3d* out) {
  const double white = e.noise_density * std::sqrt(rate_hz);
  bool clipped = false;
  for (int i = 0; i < 3; ++i) {
    double y = (1.0 + scale(i)) * truth(i) + bias(i) + white * rng->Gaussian();
    if (e.range > 0.0 && std::abs(y) >= e.range) {
      y = std::copysign(e.range, y);
      clipped = true;
    }
    (*out)(i) = y;
  }
  return clipped;
}

// Knot derivatives (per second) of the natural cubic spline through `knots` at spacing h_s: the
// C2 interpolant, so the angular acceleration (and with a lever arm the specific force) is
// continuous. Continuity of the second derivative at interior knots gives
//     m_k-1 + 4 m_k + m_k+1 = 3 (p_k+1 - p_k-1) / h,
// and a zero second derivative at the ends 2 m_0 + m_1 = 3 (p_1 - p_0) / h (mirrored at the
// last knot); solved by the Thomas algorithm.
std::vector<Eigen::Vector3d> SplineRates(const std::vector<Eigen::Vector3d>& knots, double h_s) {
  const std::size_t n = knots.size();
  std::vector<Eigen::Vector3d> m(n, Eigen::Vector3d::Zero());
  if (n < 2) return m;
  std::vector<double> diag(n, 4.0);
  std::vector<Eigen::Vector3d> rhs(n);
  diag.front() = 2.0;
  diag.back() = 2.0;
  rhs.front() = 3.0 * (knots[1] - knots[0]) / h_s;
  rhs.back() = 3.0 * (knots[n - 1] - knots[n - 2]) / h_s;
  for (std::size_t k = 1; k + 1 < n; ++k) rhs[k] = 3.0 * (knots[k + 1] - knots[k - 1]) / h_s;
  // Forward elimination (all off-diagonals are 1), then back substitution.
  for (std::size_t k = 1; k < n; ++k) {
    const double w = 1.0 / diag[k - 1];
    diag[k] -= w;
    rhs[k] -= w * rhs[k - 1];
  }
  m[n - 1] = rhs[n - 1] / diag[n - 1];
  for (std::size_t k = n - 1; k-- > 0;) m[k] = (rhs[k] - m[k + 1]) / diag[k];
  return m;
}

}  // namespace

ImuModelOptions TacticalImu() {
  // Honeywell HG1700 product brochure (N61-1619-000-001), 1 sigma: gyro bias 1 deg/h, angle
  // random walk 0.125 deg/sqrt(h); accelerometer bias 1 mg, velocity random walk
  // 0.065 ft/s/sqrt(h). The brochure's bias is taken as both the turn-on offset and the in-run
  // instability; the correlation time, scale factors and ranges are not in it and are assumed
  // (tactical-grade typical: 150 / 300 ppm, +-1000 deg/s, +-50 g).
  ImuModelOptions o;
  o.part = "Honeywell HG1700";
  o.gyro.noise_density = 0.125 * kDegToRad * kPerSqrtHourToPerSqrtHz;
  o.gyro.turn_on_bias_sigma = 1.0 * kDegPerHourToRadPerS;
  o.gyro.bias_instability = 1.0 * kDegPerHourToRadPerS;
  o.gyro.bias_correlation_s = 300.0;
  o.gyro.scale_factor_sigma = 150e-6;
  o.gyro.range = 1000.0 * kDegToRad;
  o.accel.noise_density = 0.065 * 0.3048 * kPerSqrtHourToPerSqrtHz;
  o.accel.turn_on_bias_sigma = 1e-3 * kStandardGravity;
  o.accel.bias_instability = 1e-3 * kStandardGravity;
  o.accel.bias_correlation_s = 300.0;
  o.accel.scale_factor_sigma = 300e-6;
  o.accel.range = 50.0 * kStandardGravity;
  return o;
}

ImuModelOptions MemsImu() {
  // Analog Devices ADIS16448. White noise and bias random walks: the calibration EuRoC ships
  // with its recordings of this unit (../shared/data/euroc-v101/mav0/imu0/sensor.yaml):
  // gyro 1.6968e-4 rad/s/sqrt(Hz) and 1.9393e-5 rad/s^2/sqrt(Hz), accelerometer 2.0e-3
  // m/s^2/sqrt(Hz) and 3.0e-3 m/s^3/sqrt(Hz). Data sheet: gyro in-run bias stability
  // 14.5 deg/h, ranges +-1000 deg/s and +-18 g; accelerometer in-run bias stability 0.25 mg.
  // Assumed (factory-calibrated MEMS after a power cycle): turn-on offsets 0.1 deg/s and 5 mg,
  // scale factors 0.2 %, in-run correlation time 100 s.
  ImuModelOptions o;
  o.part = "Analog Devices ADIS16448";
  o.gyro.noise_density = 1.6968e-4;
  o.gyro.bias_random_walk = 1.9393e-5;
  o.gyro.bias_instability = 14.5 * kDegPerHourToRadPerS;
  o.gyro.bias_correlation_s = 100.0;
  o.gyro.turn_on_bias_sigma = 0.1 * kDegToRad;
  o.gyro.scale_factor_sigma = 2e-3;
  o.gyro.range = 1000.0 * kDegToRad;
  o.accel.noise_density = 2.0e-3;
  o.accel.bias_random_walk = 3.0e-3;
  o.accel.bias_instability = 0.25e-3 * kStandardGravity;
  o.accel.bias_correlation_s = 100.0;
  o.accel.turn_on_bias_sigma = 5e-3 * kStandardGravity;
  o.accel.scale_factor_sigma = 2e-3;
  o.accel.range = 18.0 * kStandardGravity;
  return o;
}

ImuModelOptions Noiseless(ImuModelOptions options) {
  const double gyro_tau = options.gyro.bias_correlation_s;
  const double accel_tau = options.accel.bias_correlation_s;
  options.gyro = ImuTriadErrors{};
  options.accel = ImuTriadErrors{};
  options.gyro.bias_correlation_s = gyro_tau;
  options.accel.bias_correlation_s = accel_tau;
  return options;
}

core::Status ImuModel::Configure(const ImuModelOptions& options, const Trajectory& trajectory) {
  samples_.clear();
  true_biases_.clear();
  if (!(options.rate_hz >= 10.0) || !(options.rate_hz <= 10000.0) || !TriadValid(options.gyro) ||
      !TriadValid(options.accel) || !(options.gravity_mps2 >= 0.0) ||
      !std::isfinite(options.gravity_mps2) || trajectory.NumFrames() < 1 ||
      !options.camera_T_imu.R.allFinite() || !options.camera_T_imu.t.allFinite() ||
      !(options.tail_s >= 0.0) || !(options.tail_s <= 10.0) ||
      !(std::abs(options.clock_offset_s) <= 1.0)) {
    return core::Status::kInvalidArgument;
  }
  options_ = options;
  trajectory_ = trajectory.Options();
  const std::int32_t n = trajectory.NumFrames();
  knots_.assign(n, Eigen::Vector3d::Zero());
  for (std::int32_t k = 0; k < n; ++k) {
    const Eigen::Matrix3d steered = SteeredAttitude(trajectory_, k / trajectory_.rate_hz);
    knots_[k] = estimator::LogSO3<double>(
        Eigen::Matrix3d(steered.transpose() * trajectory.WorldTCamera(k).R));
  }
  knot_rates_ = SplineRates(knots_, 1.0 / trajectory_.rate_hz);

  Rng rng(options.seed);
  for (int i = 0; i < 3; ++i) gyro_scale_(i) = options.gyro.scale_factor_sigma * rng.Gaussian();
  for (int i = 0; i < 3; ++i) accel_scale_(i) = options.accel.scale_factor_sigma * rng.Gaussian();
  BiasProcess gyro_bias(options.gyro, &rng);
  BiasProcess accel_bias(options.accel, &rng);
  const double dt_s = 1.0 / options.rate_hz;
  const std::int64_t start_us = trajectory_.start_time_ns / 1000;
  const double duration_s = (n - 1) / trajectory_.rate_hz + options.tail_s;
  const auto count = static_cast<std::int64_t>(std::floor(duration_s * options.rate_hz)) + 2;
  samples_.reserve(count);
  true_biases_.reserve(count);
  for (std::int64_t i = 0; i < count; ++i) {
    estimator::ImuSample<double> s;
    s.seq = i;
    const std::int64_t true_us = start_us + std::llround(i * 1e6 / options.rate_hz);
    const double t_s = true_us * 1e-6;
    s.t_us = true_us + std::llround(options.clock_offset_s * 1e6);
    estimator::ImuBiases<double> bias;
    bias.gyro_radps = gyro_bias.Value();
    bias.accel_mps2 = accel_bias.Value();
    s.flags = estimator::kImuValid;
    if (Measure(TrueRate(t_s), gyro_scale_, bias.gyro_radps, options.gyro, options.rate_hz, &rng,
                &s.gyro_radps))
      s.flags |= estimator::kImuGyroSaturated;
    if (Measure(TrueSpecificForce(t_s), accel_scale_, bias.accel_mps2, options.accel,
                options.rate_hz, &rng, &s.accel_mps2))
      s.flags |= estimator::kImuAccelSaturated;
    samples_.push_back(s);
    true_biases_.push_back(bias);
    gyro_bias.Advance(dt_s, &rng);
    accel_bias.Advance(dt_s, &rng);
  }
  return core::Status::kOk;
}

estimator::ImuNoise<double> ImuModel::NoiseModel() const { return NoiseModelOf(options_); }

estimator::ImuNoise<double> NoiseModelOf(const ImuModelOptions& options) {
  const auto walk = [](const ImuTriadErrors& e) {
    const double markov = e.bias_instability * std::sqrt(2.0 / e.bias_correlation_s);
    return std::sqrt(e.bias_random_walk * e.bias_random_walk + markov * markov);
  };
  estimator::ImuNoise<double> n;
  n.gyro_noise_density = options.gyro.noise_density;
  n.accel_noise_density = options.accel.noise_density;
  n.gyro_random_walk = walk(options.gyro);
  n.accel_random_walk = walk(options.accel);
  return n;
}

void ImuModel::Jitter(double t_s, Eigen::Vector3d* phi, Eigen::Vector3d* phi_rate) const {
  const double h = 1.0 / trajectory_.rate_hz;
  const double tau = t_s - trajectory_.start_time_ns * 1e-9;
  const auto last = static_cast<std::int32_t>(knots_.size()) - 1;
  if (last == 0) {
    *phi = knots_[0];
    phi_rate->setZero();
    return;
  }
  // The segment holding t; before the first or after the last frame the end segment's cubic
  // continues.
  const auto k = std::clamp(static_cast<std::int32_t>(std::floor(tau / h)), 0, last - 1);
  const double s = tau / h - k;
  const double s2 = s * s;
  const double s3 = s2 * s;
  const Eigen::Vector3d& p0 = knots_[k];
  const Eigen::Vector3d& p1 = knots_[k + 1];
  const Eigen::Vector3d m0 = knot_rates_[k] * h;
  const Eigen::Vector3d m1 = knot_rates_[k + 1] * h;
  *phi = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 +
         (s3 - s2) * m1;
  *phi_rate = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1 +
               (3 * s2 - 2 * s) * m1) /
              h;
}

Eigen::Vector3d ImuModel::CameraRate(double t_s) const {
  Eigen::Vector3d phi;
  Eigen::Vector3d phi_rate;
  Jitter(t_s, &phi, &phi_rate);
  // The steered attitude turns at omega in its own frame, seen through the jitter rotation.
  return estimator::ExpSO3<double>(phi).transpose() * trajectory_.body_rate_radps +
         estimator::RightJacobianSO3<double>(phi) * phi_rate;
}

estimator::InertialState<double> ImuModel::TrueState(double t_s) const {
  Eigen::Vector3d phi;
  Eigen::Vector3d phi_rate;
  Jitter(t_s, &phi, &phi_rate);
  const double tau = t_s - trajectory_.start_time_ns * 1e-9;
  estimator::Pose<double> world_T_camera;
  world_T_camera.R = SteeredAttitude(trajectory_, tau) * estimator::ExpSO3<double>(phi);
  world_T_camera.t = trajectory_.start_world_m + trajectory_.velocity_world_mps * tau;
  const Eigen::Vector3d camera_rate = CameraRate(t_s);
  const Eigen::Vector3d& lever_m = options_.camera_T_imu.t;
  estimator::InertialState<double> state;
  state.world_T_imu = world_T_camera * options_.camera_T_imu;
  state.velocity_world_mps =
      trajectory_.velocity_world_mps + world_T_camera.R * camera_rate.cross(lever_m);
  return state;
}

Eigen::Vector3d ImuModel::TrueRate(double t_s) const {
  return options_.camera_T_imu.R.transpose() * CameraRate(t_s);
}

Eigen::Vector3d ImuModel::TrueSpecificForce(double t_s) const {
  const double step_s = 1e-5;
  const Eigen::Vector3d w = CameraRate(t_s);
  const Eigen::Vector3d w_dot =
      (CameraRate(t_s + step_s) - CameraRate(t_s - step_s)) / (2 * step_s);
  const Eigen::Vector3d& lever_m = options_.camera_T_imu.t;
  const estimator::InertialState<double> state = TrueState(t_s);
  const Eigen::Matrix3d world_R_camera = state.world_T_imu.R * options_.camera_T_imu.R.transpose();
  const Eigen::Vector3d accel_world =
      world_R_camera * (w_dot.cross(lever_m) + w.cross(w.cross(lever_m)));
  return state.world_T_imu.R.transpose() * (accel_world - GravityWorld());
}

}  // namespace swf::sim
