// The stereo visual-odometry text format of ../shared/data/kitti-vo (GTSAM's KITTI example):
// parsing with clear errors, and solving it with the Sliding Window Filter, batch or windowed.
//
// The flight filter has compile-time capacities (SlidingWindowFilter<Model, K, N, M, P>). The
// tool does not: it carries a small set of compiled instances ("tiers", kitti_vo_tiers.cpp) and
// picks, per problem, the smallest one that holds it (KittiVoNeeds -> PlanKittiVo). It refuses a
// problem only when that instance needs more memory than the machine has available, or when no
// compiled instance is large enough (the message names the count that does not fit).
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "swf/estimator/geometry.hpp"

namespace swf::tools {

struct KittiFactor {
  int pose = 0;  // index into KittiVoProblem::poses
  std::int64_t landmark = 0;
  estimator::Vec3<double> z;  // (uL, uR, v), pixels
  int line = 0;               // line in the factors file (1-based), for error messages
};

struct KittiVoProblem {
  estimator::StereoCamera<double> camera;
  std::vector<std::int64_t> pose_ids;          // ids as in the file, in file order
  std::vector<estimator::Pose<double>> poses;  // camera-to-world initial estimates
  std::vector<KittiFactor> factors;            // grouped by pose on return
  std::string factors_path;                    // where the factors came from (messages)
};

// Reads the three files. On failure returns false and sets *error to a message naming the file
// and line. Refused besides malformed lines: a duplicate pose id, a duplicate factor (same pose
// and landmark twice: the filter would use it once and the cost would count it twice), a
// non-positive disparity uL - uR (swapped columns, or a point behind the rig: stereo cannot place
// it), an empty factors file, a pose without any factor and a pose that no chain of shared
// landmarks links to the first (fixed) pose: nothing would constrain them.
bool LoadKittiVo(const std::string& calib_path, const std::string& poses_path,
                 const std::string& factors_path, KittiVoProblem* problem, std::string* error);

// The same from streams (the fuzz harness reads from memory); `name` stands for the file.
struct NamedStream {
  std::istream* in = nullptr;
  std::string name;
};
bool ReadKittiVo(const NamedStream& calib, const NamedStream& poses, const NamedStream& factors,
                 KittiVoProblem* problem, std::string* error);

// Reads only the calibration file (fx fy skew u0 v0 baseline_m).
bool LoadKittiVoCalibration(const std::string& path, estimator::StereoCamera<double>* camera,
                            std::string* error);
bool ReadKittiVoCalibration(std::istream& in, const std::string& path,
                            estimator::StereoCamera<double>* camera, std::string* error);

// Capacities of a filter instance (its template parameters K, N, M, P), or what a problem
// needs from one.
struct KittiVoCapacity {
  int window_poses = 0;      // K: poses in the window
  int landmarks = 0;         // N: landmarks active at once
  int factors_per_pose = 0;  // M: measurements of one pose
  int prior_landmarks = 0;   // P: landmarks the prior holds (1 suffices without marginalization)
};

// What solving `problem` with `window` (<= 0: batch) needs. Batch: all poses, all landmarks,
// the largest factor count of a pose, P = 1 (the prior spans the first pose only). Windowed:
// `window` poses; the most distinct landmarks seen from window + 1 consecutive poses (the newest
// pose is added before the oldest leaves); and the most landmarks a marginalization can hold in
// the prior at once (those seen from the leaving pose, and those already in the prior that the
// window still observes).
KittiVoCapacity KittiVoNeeds(const KittiVoProblem& problem, int window);

struct KittiVoTierInfo {
  std::string name;
  KittiVoCapacity capacity;
  std::size_t bytes = 0;  // sizeof the filter instance
};
// The compiled instances, smallest first.
std::vector<KittiVoTierInfo> KittiVoTiers();

struct KittiVoPlan {
  bool ok = false;
  std::string error;
  int tier = -1;  // index into KittiVoTiers()
  KittiVoCapacity needs;
};
// Picks the smallest compiled instance that holds `needs` and fits in `available_bytes`.
KittiVoPlan PlanKittiVo(const KittiVoCapacity& needs, std::uint64_t available_bytes);

// MemAvailable from /proc/meminfo in bytes; 0 when it cannot be read (then nothing is refused
// for memory).
std::uint64_t AvailableMemoryBytes();

struct KittiVoResult {
  bool ok = false;
  std::string error;
  double initial_cost = 0.0;  // 0.5 * sum of squared whitened residuals (sigma 1 px)
  double final_cost = 0.0;
  int iterations = 0;  // Gauss-Newton iterations (summed over updates when windowed)
  double solve_time_ms = 0.0;
  std::vector<estimator::Pose<double>> poses;  // final estimates, one per input pose
  std::uint32_t fault_bits = 0;
  KittiVoCapacity needs;        // what the problem needed
  KittiVoTierInfo instance;     // the instance that solved it
  int max_prior_landmarks = 0;  // most landmarks the prior held after an update
  // Factors whose landmark ends behind its camera: the filter skips such a measurement, the
  // cost above counts it as Ceres does. Non-zero means the estimate is wrong there.
  int factors_behind_camera = 0;
};

namespace detail {
class KittiVoInstance;
}

// Solves with a filter instance built once and reused while the problem fits it (Configure
// resets it). The filter keeps every buffer inside itself, as in flight: building it (zeroing,
// page faults) can cost more than a small solve, so build one solver for repeated solves. A
// problem that needs another instance replaces the one held (the old one is freed first).
class KittiVoSolver {
 public:
  KittiVoSolver();
  ~KittiVoSolver();
  KittiVoSolver(const KittiVoSolver&) = delete;
  KittiVoSolver& operator=(const KittiVoSolver&) = delete;

  // window <= 0: batch over all poses (first pose held fixed). Otherwise a sliding window of
  // that many poses, each pose reported as it leaves the window.
  KittiVoResult Solve(const KittiVoProblem& problem, int window);

  // Memory to plan against instead of MemAvailable (tests of the refusal).
  void SetAvailableMemoryForTesting(std::uint64_t bytes) { memory_override_ = bytes; }

 private:
  std::unique_ptr<detail::KittiVoInstance> instance_;
  int tier_ = -1;
  std::uint64_t memory_override_ = 0;
};

// One solve with a solver of its own (see KittiVoSolver).
KittiVoResult SolveKittiVo(const KittiVoProblem& problem, int window);

// 0.5 * sum over all factors of the squared residual at the given poses and landmarks, as Ceres
// evaluates it (also where a landmark is behind the camera; *behind_camera counts those
// factors). Infinite when a factor's landmark is not given.
double KittiVoCost(const KittiVoProblem& problem, const std::vector<estimator::Pose<double>>& poses,
                   const std::vector<std::int64_t>& landmark_ids,
                   const std::vector<estimator::Vec3<double>>& landmarks,
                   int* behind_camera = nullptr);

// swf-vo's output: one JSON object, its fields in this order. Numbers that are not finite are
// null (JSON has no inf or nan).
nlohmann::ordered_json KittiVoReport(const KittiVoProblem& problem, const KittiVoResult& result,
                                     int window);

}  // namespace swf::tools
