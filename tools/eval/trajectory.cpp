#include "trajectory.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

namespace swf::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRadToDeg = 57.29577951308232;

double RotationAngleRad(const estimator::Mat3<double>& r) {
  const double c = std::clamp(0.5 * (r.trace() - 1.0), -1.0, 1.0);
  return std::acos(c);
}

void Fill(TrajectoryErrors* e, double value) {
  for (double* x :
       {&e->ate_rmse_m, &e->ate_max_m, &e->final_aligned_error_m, &e->final_anchored_error_m,
        &e->max_anchored_error_m, &e->step_translation_mean_m, &e->step_translation_max_m,
        &e->step_rotation_mean_deg, &e->step_rotation_max_deg, &e->step_translation_percent,
        &e->step_rotation_deg_per_m}) {
    *x = value;
  }
}

void ScoreAligned(const std::vector<PoseD>& truth, const std::vector<PoseD>& estimate,
                  TrajectoryErrors* e) {
  std::vector<Vec3D> gt;
  std::vector<Vec3D> est;
  for (std::size_t j = 0; j < truth.size(); ++j) {
    gt.push_back(truth[j].t);
    est.push_back(estimate[j].t);
  }
  const PoseD align = AlignRigid(gt, est);
  double sum = 0.0;
  e->ate_max_m = 0.0;
  for (std::size_t j = 0; j < gt.size(); ++j) {
    const double d = (gt[j] - align.Apply(est[j])).norm();
    e->aligned_error_m.push_back(d);
    sum += d * d;
    e->ate_max_m = std::max(e->ate_max_m, d);
  }
  e->ate_rmse_m = std::sqrt(sum / static_cast<double>(gt.size()));
  e->final_aligned_error_m = e->aligned_error_m.back();
}

void ScoreAnchored(const std::vector<PoseD>& truth, const std::vector<PoseD>& estimate,
                   TrajectoryErrors* e) {
  const PoseD truth0_inv = truth.front().Inverse();
  const PoseD estimate0_inv = estimate.front().Inverse();
  e->max_anchored_error_m = 0.0;
  for (std::size_t j = 0; j < truth.size(); ++j) {
    const Vec3D t = (truth0_inv * truth[j]).t;
    const Vec3D s = (estimate0_inv * estimate[j]).t;
    e->anchored_error_m.push_back((t - s).norm());
    e->max_anchored_error_m = std::max(e->max_anchored_error_m, e->anchored_error_m.back());
  }
  e->final_anchored_error_m = e->anchored_error_m.back();
}

void ScoreSteps(const std::vector<PoseD>& truth, const std::vector<PoseD>& estimate,
                TrajectoryErrors* e) {
  double sum_t = 0.0;
  double sum_r = 0.0;
  e->truth_path_m = 0.0;
  e->step_translation_max_m = 0.0;
  e->step_rotation_max_deg = 0.0;
  for (std::size_t j = 1; j < truth.size(); ++j) {
    const PoseD gt_step = truth[j - 1].Inverse() * truth[j];
    const PoseD est_step = estimate[j - 1].Inverse() * estimate[j];
    const PoseD err = gt_step.Inverse() * est_step;
    const double t = err.t.norm();
    const double r = kRadToDeg * RotationAngleRad(err.R);
    e->step_translation_error_m.push_back(t);
    e->step_rotation_error_deg.push_back(r);
    e->truth_path_m += gt_step.t.norm();
    sum_t += t;
    sum_r += r;
    e->step_translation_max_m = std::max(e->step_translation_max_m, t);
    e->step_rotation_max_deg = std::max(e->step_rotation_max_deg, r);
  }
  const double steps = static_cast<double>(truth.size() - 1);
  e->step_translation_mean_m = sum_t / steps;
  e->step_rotation_mean_deg = sum_r / steps;
  // A percentage of a path the truth did not travel would be noise over zero.
  const bool moved = e->truth_path_m >= 0.01;
  e->step_translation_percent = moved ? 100.0 * sum_t / e->truth_path_m : kNaN;
  e->step_rotation_deg_per_m = moved ? sum_r / e->truth_path_m : kNaN;
}

}  // namespace

PoseD AlignRigid(const std::vector<Vec3D>& a, const std::vector<Vec3D>& b) {
  PoseD out;
  const std::size_t n = std::min(a.size(), b.size());
  if (n == 0) return out;
  Vec3D mean_a = Vec3D::Zero();
  Vec3D mean_b = Vec3D::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean_a += a[i] / static_cast<double>(n);
    mean_b += b[i] / static_cast<double>(n);
  }
  estimator::Mat3<double> cross = estimator::Mat3<double>::Zero();  // sum (a - ma)(b - mb)^T
  for (std::size_t i = 0; i < n; ++i) cross += (a[i] - mean_a) * (b[i] - mean_b).transpose();
  const Eigen::JacobiSVD<estimator::Mat3<double>> svd(cross,
                                                      Eigen::ComputeFullU | Eigen::ComputeFullV);
  estimator::Mat3<double> sign = estimator::Mat3<double>::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) sign(2, 2) = -1.0;
  out.R = svd.matrixU() * sign * svd.matrixV().transpose();
  out.t = mean_a - out.R * mean_b;
  return out;
}

bool IsFinite(const PoseD& pose) { return pose.R.allFinite() && pose.t.allFinite(); }

TrajectoryErrors ScoreTrajectory(const std::vector<PoseD>& truth,
                                 const std::vector<PoseD>& estimate) {
  TrajectoryErrors e;
  Fill(&e, kNaN);
  if (truth.size() < 2 || truth.size() != estimate.size()) {
    e.reason = "needs the same number (>= 2) of estimated and true poses";
    return e;
  }
  for (std::size_t j = 0; j < estimate.size(); ++j) {
    if (!IsFinite(estimate[j])) {
      e.reason = "the estimate of frame " + std::to_string(j) + " is not finite";
      return e;
    }
  }
  e.finite = true;
  ScoreAligned(truth, estimate, &e);
  ScoreAnchored(truth, estimate, &e);
  ScoreSteps(truth, estimate, &e);
  return e;
}

}  // namespace swf::eval
