// The stereo visual-odometry text format of ../shared/data/kitti-vo (GTSAM's KITTI example):
// parsing with clear errors, and solving it with the Sliding Window Filter, batch or windowed.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "swf/estimator/geometry.hpp"

namespace swf::tools {

struct KittiFactor {
  int pose = 0;  // index into KittiVoProblem::poses
  std::int64_t landmark = 0;
  estimator::Vec3<double> z;  // (uL, uR, v), pixels
};

struct KittiVoProblem {
  estimator::StereoCamera<double> camera;
  std::vector<std::int64_t> pose_ids;          // ids as in the file, in file order
  std::vector<estimator::Pose<double>> poses;  // camera-to-world initial estimates
  std::vector<KittiFactor> factors;            // grouped by pose on return
};

// Reads the three files. On failure returns false and sets *error to a message naming the file
// and line.
bool LoadKittiVo(const std::string& calib_path, const std::string& poses_path,
                 const std::string& factors_path, KittiVoProblem* problem, std::string* error);

struct KittiVoResult {
  bool ok = false;
  std::string error;
  double initial_cost = 0.0;  // 0.5 * sum of squared whitened residuals (sigma 1 px)
  double final_cost = 0.0;
  int iterations = 0;  // Gauss-Newton iterations (summed over updates when windowed)
  double solve_time_ms = 0.0;
  std::vector<estimator::Pose<double>> poses;  // final estimates, one per input pose
  std::uint32_t fault_bits = 0;
};

// Solves with one Sliding Window Filter built once and reused (Configure resets it). The filter
// keeps every buffer inside itself, as in flight; at this data set's capacities it is ~40 MB, and
// building it (zeroing, page faults) costs ~0.1 s, several times the solve: build one solver for
// repeated solves.
class KittiVoSolver {
 public:
  KittiVoSolver();
  ~KittiVoSolver();
  KittiVoSolver(const KittiVoSolver&) = delete;
  KittiVoSolver& operator=(const KittiVoSolver&) = delete;

  // window <= 0: batch over all poses (first pose held fixed). Otherwise a sliding window of
  // that many poses (at most KittiVoCapacity()), each pose reported as it leaves the window.
  KittiVoResult Solve(const KittiVoProblem& problem, int window);

 private:
  struct Workspace;
  std::unique_ptr<Workspace> workspace_;
};

// One solve with a solver of its own (see KittiVoSolver).
KittiVoResult SolveKittiVo(const KittiVoProblem& problem, int window);
int KittiVoCapacity();

// 0.5 * sum over all factors of the squared residual at the given poses and landmarks.
double KittiVoCost(const KittiVoProblem& problem, const std::vector<estimator::Pose<double>>& poses,
                   const std::vector<std::int64_t>& landmark_ids,
                   const std::vector<estimator::Vec3<double>>& landmarks);

}  // namespace swf::tools
