#include "kitti_vo.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <unordered_map>

#include "swf/estimator/sliding_window_filter.hpp"
#include "swf/estimator/stereo_model.hpp"

namespace swf::tools {
namespace {

using estimator::Pose;
using estimator::Vec3;

// Capacities for the KITTI sequence: 26 poses, 2634 landmarks, at most 369 factors per pose.
constexpr int kMaxPoses = 32;
constexpr int kMaxLandmarks = 3000;
constexpr int kMaxPerPose = 400;
constexpr int kMaxPrior = 400;
using Filter = estimator::SlidingWindowFilter<estimator::StereoModel<double>, kMaxPoses,
                                              kMaxLandmarks, kMaxPerPose, kMaxPrior>;

bool Fail(std::string* error, const std::string& path, int line, const std::string& what) {
  std::ostringstream os;
  os << path << ":" << line << ": " << what;
  *error = os.str();
  return false;
}

}  // namespace

int KittiVoCapacity() { return kMaxPoses; }

bool LoadKittiVo(const std::string& calib_path, const std::string& poses_path,
                 const std::string& factors_path, KittiVoProblem* problem, std::string* error) {
  *problem = KittiVoProblem{};
  {
    std::ifstream in(calib_path);
    if (!in) return Fail(error, calib_path, 0, "cannot open");
    double skew = 0.0;
    in >> problem->camera.fx >> problem->camera.fy >> skew >> problem->camera.cx >>
        problem->camera.cy >> problem->camera.baseline_m;
    if (!in) return Fail(error, calib_path, 1, "expected: fx fy skew u0 v0 baseline_m");
    if (!problem->camera.Valid()) return Fail(error, calib_path, 1, "invalid camera values");
    if (skew != 0.0) return Fail(error, calib_path, 1, "non-zero skew is not supported");
  }
  std::map<std::int64_t, int> index;
  {
    std::ifstream in(poses_path);
    if (!in) return Fail(error, poses_path, 0, "cannot open");
    std::string text;
    int line = 0;
    while (std::getline(in, text)) {
      ++line;
      if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::istringstream ls(text);
      std::int64_t id = 0;
      Eigen::Matrix4d m;
      ls >> id;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) ls >> m(r, c);
      if (!ls) return Fail(error, poses_path, line, "expected: id + 16 numbers (row-major 4x4)");
      if (!m.allFinite()) return Fail(error, poses_path, line, "non-finite pose");
      const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
      if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-4)
        return Fail(error, poses_path, line, "rotation block is not orthonormal");
      if (index.count(id) != 0) return Fail(error, poses_path, line, "duplicate pose id");
      index[id] = static_cast<int>(problem->poses.size());
      problem->pose_ids.push_back(id);
      // Re-orthonormalize: the file keeps six digits, the solver wants an exact rotation.
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
      problem->poses.push_back(
          Pose<double>{svd.matrixU() * svd.matrixV().transpose(), m.topRightCorner<3, 1>()});
    }
    if (problem->poses.empty()) return Fail(error, poses_path, line, "no poses");
  }
  {
    std::ifstream in(factors_path);
    if (!in) return Fail(error, factors_path, 0, "cannot open");
    std::string text;
    int line = 0;
    while (std::getline(in, text)) {
      ++line;
      if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::istringstream ls(text);
      std::int64_t pose_id = 0;
      KittiFactor f;
      double x = 0, y = 0, z = 0;
      ls >> pose_id >> f.landmark >> f.z.x() >> f.z.y() >> f.z.z() >> x >> y >> z;
      if (!ls)
        return Fail(error, factors_path, line, "expected: pose_id landmark_id uL uR v X Y Z");
      const auto it = index.find(pose_id);
      if (it == index.end()) return Fail(error, factors_path, line, "unknown pose id");
      if (!f.z.allFinite()) return Fail(error, factors_path, line, "non-finite measurement");
      f.pose = it->second;
      problem->factors.push_back(f);
    }
  }
  std::stable_sort(problem->factors.begin(), problem->factors.end(),
                   [](const KittiFactor& a, const KittiFactor& b) { return a.pose < b.pose; });
  return true;
}

double KittiVoCost(const KittiVoProblem& problem, const std::vector<Pose<double>>& poses,
                   const std::vector<std::int64_t>& landmark_ids,
                   const std::vector<Vec3<double>>& landmarks) {
  std::unordered_map<std::int64_t, int> where;
  for (std::size_t i = 0; i < landmark_ids.size(); ++i)
    where[landmark_ids[i]] = static_cast<int>(i);
  estimator::StereoModel<double> model;
  model.camera = problem.camera;
  double cost = 0.0;
  for (const KittiFactor& f : problem.factors) {
    const auto it = where.find(f.landmark);
    if (it == where.end()) continue;
    Vec3<double> h;
    if (!model.Predict(poses[f.pose], landmarks[it->second], &h, nullptr, nullptr)) continue;
    cost += 0.5 * (f.z - h).squaredNorm();
  }
  return cost;
}

struct KittiVoSolver::Workspace {
  Filter filter;
};

KittiVoSolver::KittiVoSolver() : workspace_(std::make_unique<Workspace>()) {}
KittiVoSolver::~KittiVoSolver() = default;

KittiVoResult SolveKittiVo(const KittiVoProblem& problem, int window) {
  return KittiVoSolver().Solve(problem, window);
}

KittiVoResult KittiVoSolver::Solve(const KittiVoProblem& problem, int window) {
  KittiVoResult result;
  const int n = static_cast<int>(problem.poses.size());
  const bool batch = window <= 0;
  if (batch && n > kMaxPoses) {
    result.error =
        "batch needs all poses in the window: more than " + std::to_string(kMaxPoses) + " poses";
    return result;
  }
  if (!batch && window > kMaxPoses) {
    result.error = "--window must be at most " + std::to_string(kMaxPoses);
    return result;
  }
  Filter* const filter = &workspace_->filter;
  estimator::StereoModel<double> model;
  model.camera = problem.camera;
  estimator::SwfOptions options;
  options.mode = batch ? estimator::SwfMode::kBatch : estimator::SwfMode::kSlidingWindow;
  options.window_size = batch ? n : window;
  options.fix_first_pose = true;  // the data set's gauge
  options.robust = false;         // plain least squares, as the reference cost
  options.max_iterations = 100;
  options.relative_cost_tolerance = 1e-14;
  options.step_tolerance = 1e-12;
  if (filter->Configure(model, options) != core::Status::kOk) {
    result.error = "invalid filter options";
    return result;
  }
  const Eigen::Matrix3d sqrt_info = Eigen::Matrix3d::Identity();  // sigma 1 px
  std::vector<Pose<double>> final_poses(problem.poses);
  std::vector<std::int64_t> landmark_ids;
  std::vector<Vec3<double>> landmarks;
  std::size_t next = 0;
  int first_in_window = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int j = 0; j < n; ++j) {
    if (filter->AddPose(problem.poses[j]) != core::Status::kOk) {
      result.error = "pose " + std::to_string(problem.pose_ids[j]) + " refused";
      return result;
    }
    for (; next < problem.factors.size() && problem.factors[next].pose == j; ++next) {
      const KittiFactor& f = problem.factors[next];
      const core::Status s = filter->AddObservation(f.landmark, f.z, sqrt_info);
      if (s != core::Status::kOk && s != core::Status::kInvalidArgument) {
        result.error = std::string("factor refused: ") + core::ToString(s);
        return result;
      }
    }
    if (batch && j + 1 < n) continue;  // batch: one solve over everything
    if (batch) result.initial_cost = filter->MeasurementCost();
    if (!batch && filter->NumPoses() > window) final_poses[first_in_window++] = filter->PoseAt(0);
    const core::Status s = filter->Update();
    if (s != core::Status::kOk && s != core::Status::kNotConverged) {
      result.error = std::string("update failed: ") + core::ToString(s);
      return result;
    }
    result.iterations += filter->Summary().iterations;
    for (const auto& r : filter->Retired()) {
      landmark_ids.push_back(r.id);
      landmarks.push_back(r.position);
    }
  }
  result.solve_time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  for (int j = 0; j < filter->NumPoses(); ++j) final_poses[first_in_window + j] = filter->PoseAt(j);
  filter->ForEachLandmark([&](std::int64_t id, const Vec3<double>& p, int) {
    landmark_ids.push_back(id);
    landmarks.push_back(p);
  });
  if (!batch) {
    // The windowed run's initial cost uses the stereo-initialized landmarks at the input poses.
    std::vector<Vec3<double>> initial(landmark_ids.size());
    std::unordered_map<std::int64_t, int> where;
    for (std::size_t i = 0; i < landmark_ids.size(); ++i)
      where[landmark_ids[i]] = static_cast<int>(i);
    std::vector<bool> done(landmark_ids.size(), false);
    for (const KittiFactor& f : problem.factors) {
      const int i = where[f.landmark];
      if (done[i]) continue;
      Vec3<double> p;
      if (model.InitLandmark(problem.poses[f.pose], f.z, &p)) initial[i] = p;
      done[i] = true;
    }
    result.initial_cost = KittiVoCost(problem, problem.poses, landmark_ids, initial);
  }
  result.final_cost = KittiVoCost(problem, final_poses, landmark_ids, landmarks);
  result.poses = final_poses;
  result.fault_bits = filter->FaultBits();
  result.ok = true;
  return result;
}

}  // namespace swf::tools
