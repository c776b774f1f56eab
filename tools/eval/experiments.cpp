#include "experiments.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace swf::eval {
namespace {

using estimator::Mat3;
using estimator::Mat6;
using estimator::Vec3;
using estimator::Vec6;

// x^T C^-1 x, or a negative number when C is not positive definite.
template <int D>
double Mahalanobis(const Eigen::Matrix<double, D, 1>& x, const Eigen::Matrix<double, D, D>& c) {
  const Eigen::LLT<Eigen::Matrix<double, D, D>> llt(c);
  if (llt.info() != Eigen::Success || !c.allFinite()) return -1.0;
  return x.dot(llt.solve(x));
}

}  // namespace

double ChiSquareQuantile(double p, double dof) {
  // Standard normal quantile by bisection on erfc (monotone; 60 halvings reach double precision).
  double lo = -10.0;
  double hi = 10.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  const double z = 0.5 * (lo + hi);
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

NeesResult RunNees(const std::string& name, const NeesOptions& options) {
  NeesResult result;
  result.name = name;
  result.runs = options.runs;
  const std::size_t frames = static_cast<std::size_t>(options.scene.frames);
  result.pose_nees.assign(frames, 0.0);
  result.landmark_nees.assign(frames, 0.0);
  std::vector<int> pose_count(frames, 0);
  std::vector<int> landmark_count(frames, 0);
  for (int r = 0; r < options.runs; ++r) {
    SceneOptions so = options.scene;
    so.seed = 5000 + static_cast<std::uint64_t>(r);
    const SyntheticScene scene(so);
    auto hook = [&](Filter* swf, std::size_t j) {
      result.mean_poses += swf->NumPoses() / static_cast<double>(frames * options.runs);
      result.max_poses = std::max(result.max_poses, swf->NumPoses());
      if (swf->ComputeCovariances() != core::Status::kOk) {
        ++result.covariance_failures;
        return;
      }
      const estimator::Pose<double>& est = swf->NewestPose();
      const Vec6<double> delta = est.LocalDifference(scene.frames()[j].truth);
      const double pose = Mahalanobis<6>(delta, swf->NewestPoseCovariance());
      if (j + 1 == frames) {
        for (int k = 0; k < 3; ++k) {
          result.final_error_m[k] += delta[k] * delta[k] / options.runs;
          result.final_sigma_m[k] +=
              std::sqrt(std::max(0.0, swf->NewestPoseCovariance()(k, k))) / options.runs;
        }
      }
      if (pose < 0) {
        ++result.covariance_failures;
      } else {
        result.pose_nees[j] += pose;
        ++pose_count[j];
      }
      double sum = 0.0;
      int n = 0;
      swf->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) {
        Mat3<double> c;
        if (!swf->GetLandmarkCovariance(id, &c)) return;
        const double e = Mahalanobis<3>(Vec3<double>(p - scene.landmarks()[id]), c);
        if (e < 0) {
          ++result.covariance_failures;
          return;
        }
        sum += e;
        ++n;
      });
      if (n > 0) {
        result.landmark_nees[j] += sum / n;
        ++landmark_count[j];
      }
    };
    const Trace t =
        RunFilter<Filter>(scene, options.mode, options.window, 9000 + static_cast<std::uint64_t>(r),
                          hook, kMotionSigmaM, kMotionSigmaRad, true, false, options.hold_sightings,
                          options.hold_depth_precision);
    result.update_failures += t.failures;
  }
  for (std::size_t j = 0; j < frames; ++j) {
    result.pose_nees[j] /= std::max(pose_count[j], 1);
    result.landmark_nees[j] /= std::max(landmark_count[j], 1);
  }
  for (double& e : result.final_error_m) e = std::sqrt(e);
  const double n = options.runs;
  result.pose_lower = ChiSquareQuantile(0.025, 6 * n) / n;
  result.pose_upper = ChiSquareQuantile(0.975, 6 * n) / n;
  result.landmark_lower = ChiSquareQuantile(0.025, 3 * n) / n;
  result.landmark_upper = ChiSquareQuantile(0.975, 3 * n) / n;
  int inside_pose = 0;
  int inside_landmark = 0;
  for (std::size_t j = 1; j < frames; ++j) {
    result.mean_pose_nees += result.pose_nees[j] / static_cast<double>(frames - 1);
    result.mean_landmark_nees += result.landmark_nees[j] / static_cast<double>(frames - 1);
    inside_pose +=
        result.pose_nees[j] >= result.pose_lower && result.pose_nees[j] <= result.pose_upper;
    inside_landmark += result.landmark_nees[j] >= result.landmark_lower &&
                       result.landmark_nees[j] <= result.landmark_upper;
  }
  result.pose_fraction_inside = inside_pose / static_cast<double>(frames - 1);
  result.landmark_fraction_inside = inside_landmark / static_cast<double>(frames - 1);
  return result;
}

std::vector<TrackLengthPoint> RunTrackLengthStudy(const TrackLengthOptions& options) {
  std::vector<TrackLengthPoint> points;
  for (double step : options.steps_m) {
    TrackLengthPoint point;
    point.step_m = step;
    point.windows = options.windows;
    point.final_mse_m2.assign(options.windows.size(), 0.0);
    for (int r = 0; r < options.runs; ++r) {
      SceneOptions so;
      so.motion = SceneOptions::Motion::kSideways;
      so.start_altitude_m = 50.0;
      so.step_m = step;
      so.landmark_density_per_m2 = 0.08;  // ~30 features per frame at 50 m
      so.frames = options.frames;
      so.seed = 300 + static_cast<std::uint64_t>(r);
      const SyntheticScene scene(so);
      std::vector<int> length(scene.landmarks().size(), 0);
      double observations = 0.0;
      for (const auto& f : scene.frames()) {
        for (const auto& o : f.obs) ++length[o.id];
        observations += static_cast<double>(f.obs.size());
      }
      const auto seen = std::count_if(length.begin(), length.end(), [](int l) { return l > 0; });
      point.mean_track_length += observations / std::max<double>(1.0, seen) / options.runs;
      point.mean_features_per_frame += observations / options.frames / options.runs;
      for (std::size_t w = 0; w < options.windows.size(); ++w) {
        const int k = options.windows[w];
        const Trace t = RunFilter<Filter>(scene, estimator::SwfMode::kSlidingWindow, k,
                                          700 + static_cast<std::uint64_t>(r));
        point.final_mse_m2[w] += t.mse_m2.back() / options.runs;
      }
    }
    points.push_back(point);
  }
  return points;
}

}  // namespace swf::eval
