// Internal to swf_kitti_vo: one compiled SlidingWindowFilter instance behind a small interface,
// and the solve that feeds a kitti-vo problem to it. The tiers instantiate MakeTier<K, N, M, P> in
// one translation unit (kitti_vo_tiers.cpp): a unit's first filter instance costs most of the
// compile time and the others share it, and the rest of the library does not instantiate the
// filter.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <memory>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "kitti_vo.hpp"
#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"

namespace swf::tools::detail {

class KittiVoInstance {
 public:
  virtual ~KittiVoInstance() = default;
  virtual KittiVoResult Solve(const KittiVoProblem& problem, int window) = 0;
};

struct KittiVoTier {
  KittiVoTierInfo info;
  std::unique_ptr<KittiVoInstance> (*make)() = nullptr;  // allocates the filter (info.bytes)
};

// The compiled tiers. Batch tiers have P = 1: without marginalization the prior spans the first
// pose only.
// kitti_vo_tiers.cpp: batch
KittiVoTier TierBatch32();   // the kitti-vo sample (26 poses, 2,634 landmarks)
KittiVoTier TierBatch128();  // KITTI-00-sized excerpts (77 poses, 15,638 landmarks)
// batch, long sequences
KittiVoTier TierBatch512();
KittiVoTier TierBatch2048();
KittiVoTier TierBatch4800();  // the longest KITTI odometry sequence (02: 4,661 frames)
// sliding windows
KittiVoTier TierWindow32();
KittiVoTier TierWindow32Wide();  // KITTI-00-sized windows (up to 686 prior landmarks)
KittiVoTier TierWindow128();

std::string FaultNames(std::uint32_t bits);  // "not positive definite, non-finite, ..."

inline estimator::SwfOptions KittiVoOptions(int window_size, bool batch) {
  estimator::SwfOptions options;
  options.mode = batch ? estimator::SwfMode::kBatch : estimator::SwfMode::kSlidingWindow;
  options.window_size = window_size;
  options.fix_first_pose = true;  // the data set's gauge
  options.robust = false;         // plain least squares, as the reference cost
  options.max_iterations = 100;
  options.relative_cost_tolerance = 1e-14;
  options.step_tolerance = 1e-12;
  // The plain least-squares cost Ceres solves uses every factor once: no integrity gates (they
  // remove measurements after a solve, so the optimum would be another cost's).
  options.gate_probability = 0.0;
  return options;
}

// "factors.txt:123: factor refused (pose id 7, landmark 4411): full" plus what is full.
// (Built with a stream: GCC 12 at -O3 warns falsely on chains of std::string operator+.)
template <typename Filter>
std::string RefusedFactor(const KittiVoProblem& problem, const KittiFactor& f, core::Status s,
                          const Filter& filter) {
  std::ostringstream os;
  os << problem.factors_path << ":" << f.line << ": factor refused (pose id "
     << problem.pose_ids[f.pose] << ", landmark " << f.landmark << "): " << core::ToString(s);
  const std::uint32_t bits = filter.FaultBits();
  if ((bits & estimator::kFaultMeasurementCapacity) != 0u)
    os << " (this instance holds " << Filter::kMaxObservations / Filter::kMaxPoses
       << " factors per pose)";
  if ((bits & estimator::kFaultLandmarkCapacity) != 0u)
    os << " (this instance holds " << filter.NumLandmarks() << " active landmarks)";
  return os.str();
}

// "update at pose id 9 (window of poses 5..9) failed: numerical failure (not positive definite)"
inline std::string FailedUpdate(const KittiVoProblem& problem, bool batch, int first, int last,
                                core::Status s, std::uint32_t fault_bits) {
  std::ostringstream os;
  if (batch) {
    os << "batch solve over " << problem.poses.size() << " poses";
  } else {
    os << "update at pose id " << problem.pose_ids[last] << " (window of poses "
       << problem.pose_ids[first] << ".." << problem.pose_ids[last] << ")";
  }
  os << " failed: " << core::ToString(s) << " (fault bits " << fault_bits << ": "
     << FaultNames(fault_bits) << ")";
  return os.str();
}

// The initial cost: stereo-initialized landmarks (first factor of each, in pose order, as the
// filter initializes them) at the input poses.
inline double InitialCost(const KittiVoProblem& problem,
                          const std::vector<std::int64_t>& landmark_ids) {
  estimator::StereoModel<double> model;
  model.camera = problem.camera;
  std::vector<estimator::Vec3<double>> initial(landmark_ids.size(),
                                               estimator::Vec3<double>::Zero());
  std::unordered_map<std::int64_t, int> where;
  for (std::size_t i = 0; i < landmark_ids.size(); ++i)
    where[landmark_ids[i]] = static_cast<int>(i);
  std::vector<bool> done(landmark_ids.size(), false);
  for (const KittiFactor& f : problem.factors) {
    const auto it = where.find(f.landmark);
    if (it == where.end() || done[it->second]) continue;
    estimator::Vec3<double> p;
    if (model.InitLandmark(problem.poses[f.pose], f.z, &p)) initial[it->second] = p;
    done[it->second] = true;
  }
  return KittiVoCost(problem, problem.poses, landmark_ids, initial);
}

template <typename Filter>
KittiVoResult SolveWith(Filter* filter, const KittiVoProblem& problem, int window) {
  KittiVoResult result;
  const int n = static_cast<int>(problem.poses.size());
  const bool batch = window <= 0 || window >= n;  // a window over everything never marginalizes
  estimator::StereoModel<double> model;
  model.camera = problem.camera;
  if (filter->Configure(model, KittiVoOptions(batch ? n : window, batch)) != core::Status::kOk) {
    result.error = "invalid filter options";
    return result;
  }
  const Eigen::Matrix3d sqrt_info = Eigen::Matrix3d::Identity();  // sigma 1 px
  std::vector<estimator::Pose<double>> final_poses(problem.poses);
  std::vector<std::int64_t> landmark_ids;
  std::vector<estimator::Vec3<double>> landmarks;
  std::size_t next = 0;
  int first_in_window = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int j = 0; j < n; ++j) {
    if (filter->AddPose(problem.poses[j]) != core::Status::kOk) {
      result.error = "pose id " + std::to_string(problem.pose_ids[j]) + " refused by the filter";
      return result;
    }
    for (; next < problem.factors.size() && problem.factors[next].pose == j; ++next) {
      const KittiFactor& f = problem.factors[next];
      // Every factor must be used: the reported cost counts all of them.
      const core::Status s = filter->AddObservation(f.landmark, f.z, sqrt_info);
      if (s != core::Status::kOk) {
        result.error = RefusedFactor(problem, f, s, *filter);
        return result;
      }
    }
    if (batch && j + 1 < n) continue;  // batch: one solve over everything
    if (!batch && filter->NumPoses() > window) final_poses[first_in_window++] = filter->PoseAt(0);
    const core::Status s = filter->Update();
    if (s != core::Status::kOk && s != core::Status::kNotConverged) {
      result.error = FailedUpdate(problem, batch, first_in_window, j, s, filter->FaultBits());
      return result;
    }
    result.iterations += filter->Summary().iterations;
    result.max_prior_landmarks = std::max(result.max_prior_landmarks, filter->NumPriorLandmarks());
    for (const auto& r : filter->Retired()) {
      landmark_ids.push_back(r.id);
      landmarks.push_back(r.position);
    }
  }
  result.solve_time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  for (int j = 0; j < filter->NumPoses(); ++j) final_poses[first_in_window + j] = filter->PoseAt(j);
  filter->ForEachLandmark([&](std::int64_t id, const estimator::Vec3<double>& p, int) {
    landmark_ids.push_back(id);
    landmarks.push_back(p);
  });
  result.initial_cost = InitialCost(problem, landmark_ids);
  result.final_cost =
      KittiVoCost(problem, final_poses, landmark_ids, landmarks, &result.factors_behind_camera);
  result.poses = std::move(final_poses);
  result.fault_bits = filter->FaultBits();
  result.ok = true;
  return result;
}

template <typename Filter>
class FilterInstance final : public KittiVoInstance {
 public:
  FilterInstance() : filter_(std::make_unique<Filter>()) {}
  KittiVoResult Solve(const KittiVoProblem& problem, int window) override {
    return SolveWith(filter_.get(), problem, window);
  }

 private:
  std::unique_ptr<Filter> filter_;  // allocated (and zeroed) once
};

template <int K, int N, int M, int P>
KittiVoTier MakeTier(const char* name) {
  using Filter = estimator::SlidingWindowFilter<estimator::StereoModel<double>, K, N, M, P>;
  KittiVoTier tier;
  tier.info.name = name;
  tier.info.capacity = KittiVoCapacity{K, N, M, P};
  tier.info.bytes = sizeof(Filter);
  tier.make = []() -> std::unique_ptr<KittiVoInstance> {
    return std::make_unique<FilterInstance<Filter>>();
  };
  return tier;
}

}  // namespace swf::tools::detail
