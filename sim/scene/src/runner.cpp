#include "swf/scene/runner.hpp"

namespace swf::scene {

SwfOptions FilterOptions(SwfMode mode) {
  SwfOptions o;
  o.mode = mode;
  o.first_pose_sigma_m = 1e-3;
  o.first_pose_sigma_rad = 1e-5;
  return o;
}

MotionInput::MotionInput(double sigma_m, double sigma_rad) : MotionInput(sigma_m, sigma_rad, 0) {
  perturbed_ = false;
}

MotionInput::MotionInput(double sigma_m, double sigma_rad, std::uint64_t seed)
    : sigma_m_(sigma_m), sigma_rad_(sigma_rad), perturbed_(true), rng_(seed) {
  sqrt_information_.diagonal() << Vec3<double>::Constant(1 / sigma_m),
      Vec3<double>::Constant(1 / sigma_rad);
}

Pose<double> MotionInput::Between(const Pose<double>& from, const Pose<double>& to) {
  const Pose<double> u = from.Inverse() * to;
  if (!perturbed_) return u;
  Vec6<double> noise;
  for (int k = 0; k < 6; ++k) noise[k] = (k < 3 ? sigma_m_ : sigma_rad_) * gauss_(rng_);
  return u.Retract(noise);
}

Mat15<double> FirstPoseCovariance(double sigma_m, double sigma_rad) {
  Vec15<double> sigma;
  sigma << Vec3<double>::Constant(sigma_m), Vec3<double>::Constant(sigma_rad),
      Vec3<double>::Constant(0.05), Vec3<double>::Constant(0.01), Vec3<double>::Constant(0.1);
  return Mat15<double>(sigma.cwiseAbs2().asDiagonal());
}

}  // namespace swf::scene
