#include "kitti_vo.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "kitti_vo_instance.hpp"
#include "swf/estimator/stereo_model.hpp"
#include "swf/ground_cli/ground_cli.hpp"

namespace swf::tools {
namespace {

using estimator::Pose;
using estimator::Vec3;

// "path:line: what", or "path: what" for the file as a whole (line 0).
bool Fail(std::string* error, const std::string& path, int line, const std::string& what) {
  std::ostringstream os;
  os << path;
  if (line > 0) os << ":" << line;
  os << ": " << what;
  *error = os.str();
  return false;
}

// Calls parse_line(line stream, line number) on every non-blank line of the file until it
// returns false (it has set *error); a file without such a line is an error too: "no <what>".
template <typename ParseLine>
bool ForEachDataLine(std::istream& in, const std::string& path, const std::string& what,
                     std::string* error, ParseLine parse_line) {
  std::string text;
  int line = 0;
  bool any = false;
  while (std::getline(in, text)) {
    ++line;
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ls(text);
    if (!parse_line(ls, line)) return false;
    any = true;
  }
  if (!any)
    return Fail(error, path, 0, "no " + what + " in the file (" + std::to_string(line) + " lines)");
  return true;
}

// Fills the poses and `index` (file id -> position) and `lines` (position -> file line).
bool ReadPoses(std::istream& in, const std::string& path, KittiVoProblem* problem,
               std::map<std::int64_t, int>* index, std::vector<int>* lines, std::string* error) {
  return ForEachDataLine(in, path, "poses", error, [&](std::istringstream& ls, int line) {
    std::int64_t id = 0;
    Eigen::Matrix4d m;
    ls >> id;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) ls >> m(r, c);
    if (!ls) return Fail(error, path, line, "expected: id + 16 numbers (row-major 4x4)");
    if (!m.allFinite()) return Fail(error, path, line, "non-finite pose");
    const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
    if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-4)
      return Fail(error, path, line, "rotation block is not orthonormal");
    if (index->count(id) != 0) return Fail(error, path, line, "duplicate pose id");
    (*index)[id] = static_cast<int>(problem->poses.size());
    lines->push_back(line);
    problem->pose_ids.push_back(id);
    // Re-orthonormalize: the file keeps six digits, the solver wants an exact rotation.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    problem->poses.push_back(
        Pose<double>{svd.matrixU() * svd.matrixV().transpose(), m.topRightCorner<3, 1>()});
    return true;
  });
}

bool ReadFactors(std::istream& in, const std::string& path,
                 const std::map<std::int64_t, int>& index, KittiVoProblem* problem,
                 std::string* error) {
  std::map<std::pair<int, std::int64_t>, int> seen;  // (pose, landmark) -> first line
  return ForEachDataLine(in, path, "factors", error, [&](std::istringstream& ls, int line) {
    std::int64_t pose_id = 0;
    KittiFactor f;
    double x = 0, y = 0, z = 0;
    ls >> pose_id >> f.landmark >> f.z.x() >> f.z.y() >> f.z.z() >> x >> y >> z;
    if (!ls) return Fail(error, path, line, "expected: pose_id landmark_id uL uR v X Y Z");
    const auto it = index.find(pose_id);
    if (it == index.end()) return Fail(error, path, line, "unknown pose id");
    if (!f.z.allFinite()) return Fail(error, path, line, "non-finite measurement");
    if (!(f.z.x() - f.z.y() > 0.0)) {
      std::ostringstream os;
      os << "disparity uL - uR = " << f.z.x() - f.z.y()
         << " is not positive (uL and uR swapped?): stereo cannot place this point";
      return Fail(error, path, line, os.str());
    }
    f.pose = it->second;
    f.line = line;
    const auto [first, inserted] = seen.emplace(std::make_pair(f.pose, f.landmark), line);
    if (!inserted) {
      return Fail(error, path, line,
                  "duplicate factor: pose " + std::to_string(pose_id) +
                      " already observes landmark " + std::to_string(f.landmark) + " on line " +
                      std::to_string(first->second));
    }
    problem->factors.push_back(f);
    return true;
  });
}

// The first pose (in file order) that no chain of shared landmarks connects to the first pose, or
// -1. Such a pose (or group of poses) can move freely against the rest: the solve would end in
// "not positive definite" without saying where.
int FirstPoseUnlinkedToTheFirst(const KittiVoProblem& problem) {
  std::vector<int> parent(problem.poses.size());
  for (std::size_t j = 0; j < parent.size(); ++j) parent[j] = static_cast<int>(j);
  auto root = [&](int j) {
    while (parent[j] != j) j = parent[j] = parent[parent[j]];
    return j;
  };
  std::unordered_map<std::int64_t, int> first_pose;  // landmark -> a pose that observes it
  for (const KittiFactor& f : problem.factors) {
    const auto [it, inserted] = first_pose.emplace(f.landmark, f.pose);
    if (!inserted) parent[root(f.pose)] = root(it->second);
  }
  for (std::size_t j = 1; j < parent.size(); ++j)
    if (root(static_cast<int>(j)) != root(0)) return static_cast<int>(j);
  return -1;
}

}  // namespace

bool LoadKittiVoCalibration(const std::string& path, estimator::StereoCamera<double>* camera,
                            std::string* error) {
  std::ifstream in(path);
  if (!in) return Fail(error, path, 0, "cannot open");
  return ReadKittiVoCalibration(in, path, camera, error);
}

bool ReadKittiVoCalibration(std::istream& in, const std::string& path,
                            estimator::StereoCamera<double>* camera, std::string* error) {
  double skew = 0.0;
  in >> camera->fx >> camera->fy >> skew >> camera->cx >> camera->cy >> camera->baseline_m;
  if (!in) return Fail(error, path, 1, "expected: fx fy skew u0 v0 baseline_m");
  if (!camera->Valid()) return Fail(error, path, 1, "invalid camera values");
  if (skew != 0.0) return Fail(error, path, 1, "non-zero skew is not supported");
  return true;
}

bool LoadKittiVo(const std::string& calib_path, const std::string& poses_path,
                 const std::string& factors_path, KittiVoProblem* problem, std::string* error) {
  std::ifstream calib(calib_path);
  std::ifstream poses(poses_path);
  std::ifstream factors(factors_path);
  if (!calib) return Fail(error, calib_path, 0, "cannot open");
  if (!poses) return Fail(error, poses_path, 0, "cannot open");
  if (!factors) return Fail(error, factors_path, 0, "cannot open");
  return ReadKittiVo({&calib, calib_path}, {&poses, poses_path}, {&factors, factors_path}, problem,
                     error);
}

bool ReadKittiVo(const NamedStream& calib, const NamedStream& poses, const NamedStream& factors,
                 KittiVoProblem* problem, std::string* error) {
  *problem = KittiVoProblem{};
  problem->factors_path = factors.name;
  const std::string& poses_path = poses.name;
  const std::string& factors_path = factors.name;
  std::map<std::int64_t, int> index;
  std::vector<int> pose_lines;
  if (!ReadKittiVoCalibration(*calib.in, calib.name, &problem->camera, error) ||
      !ReadPoses(*poses.in, poses_path, problem, &index, &pose_lines, error) ||
      !ReadFactors(*factors.in, factors_path, index, problem, error))
    return false;
  std::vector<int> count(problem->poses.size(), 0);
  for (const KittiFactor& f : problem->factors) ++count[f.pose];
  for (std::size_t j = 0; j < count.size(); ++j) {
    if (count[j] == 0)
      return Fail(error, poses_path, pose_lines[j],
                  "pose id " + std::to_string(problem->pose_ids[j]) + " has no factor in " +
                      factors_path + ": nothing constrains it");
  }
  const int unlinked = FirstPoseUnlinkedToTheFirst(*problem);
  if (unlinked >= 0)
    return Fail(error, poses_path, pose_lines[unlinked],
                "pose id " + std::to_string(problem->pose_ids[unlinked]) +
                    " shares no landmark, directly or through other poses, with the first pose: "
                    "nothing ties it to the fixed gauge");
  std::stable_sort(problem->factors.begin(), problem->factors.end(),
                   [](const KittiFactor& a, const KittiFactor& b) { return a.pose < b.pose; });
  return true;
}

// ---- sizing ----------------------------------------------------------------------------------

namespace {

// Landmark ids renumbered 0..L-1, and the sorted poses that observe each.
std::vector<std::vector<int>> PosesPerLandmark(const KittiVoProblem& problem) {
  std::unordered_map<std::int64_t, int> dense;
  std::vector<std::vector<int>> poses;
  for (const KittiFactor& f : problem.factors) {
    const auto [it, inserted] = dense.emplace(f.landmark, static_cast<int>(poses.size()));
    if (inserted) poses.emplace_back();
    poses[it->second].push_back(f.pose);
  }
  for (auto& p : poses) std::sort(p.begin(), p.end());
  return poses;
}

// Most distinct landmarks observed from `span` consecutive poses.
int MostLandmarksInSpan(const KittiVoProblem& problem, int span) {
  const int n = static_cast<int>(problem.poses.size());
  std::vector<std::vector<std::int64_t>> by_pose(n);
  for (const KittiFactor& f : problem.factors) by_pose[f.pose].push_back(f.landmark);
  std::unordered_map<std::int64_t, int> count;  // observations inside the span
  int distinct = 0;
  int most = 0;
  for (int j = 0; j < n; ++j) {
    for (std::int64_t id : by_pose[j]) distinct += count[id]++ == 0 ? 1 : 0;
    most = std::max(most, distinct);
    if (j - span + 1 >= 0)
      for (std::int64_t id : by_pose[j - span + 1]) distinct -= --count[id] == 0 ? 1 : 0;
  }
  return most;
}

// Most landmarks in the prior while pose m is marginalized (m = 0 .. n-1-window): those seen
// from m, and those seen before m that the window [m, m + window - 1] still observes (the
// prior as the previous update left it; landmarks the window no longer sees were retired).
// Exact for tracks without gaps; a track that leaves the window and comes back is a new landmark
// to the filter, which this counts as held: an upper bound then.
int MostPriorLandmarks(const KittiVoProblem& problem, int window) {
  const int n = static_cast<int>(problem.poses.size());
  const int last_marginalized = n - 1 - window;
  if (last_marginalized < 0) return 1;
  std::vector<int> in_prior(last_marginalized + 1, 0);
  for (const std::vector<int>& poses : PosesPerLandmark(problem)) {
    std::size_t k = 0;  // first observing pose >= m
    for (int m = poses.front(); m <= std::min(poses.back(), last_marginalized); ++m) {
      while (poses[k] < m) ++k;
      const bool seen_from_m = poses[k] == m;
      const bool held = poses.front() < m && poses[k] <= m + window - 1;
      in_prior[m] += seen_from_m || held ? 1 : 0;
    }
  }
  return std::max(1, *std::max_element(in_prior.begin(), in_prior.end()));
}

}  // namespace

KittiVoCapacity KittiVoNeeds(const KittiVoProblem& problem, int window) {
  const int n = static_cast<int>(problem.poses.size());
  KittiVoCapacity needs;
  std::vector<int> per_pose(n, 0);
  for (const KittiFactor& f : problem.factors) ++per_pose[f.pose];
  needs.factors_per_pose = n > 0 ? *std::max_element(per_pose.begin(), per_pose.end()) : 0;
  if (window <= 0 || window >= n) {  // batch: everything at once, prior over the first pose
    needs.window_poses = n;
    needs.landmarks = MostLandmarksInSpan(problem, n);
    needs.prior_landmarks = 1;
  } else {
    needs.window_poses = window;
    needs.landmarks = MostLandmarksInSpan(problem, window + 1);
    needs.prior_landmarks = MostPriorLandmarks(problem, window);
  }
  return needs;
}

namespace {

const std::vector<detail::KittiVoTier>& Tiers() {
  static const std::vector<detail::KittiVoTier> kTiers = [] {
    std::vector<detail::KittiVoTier> t = {detail::TierBatch32(),      detail::TierBatch128(),
                                          detail::TierBatch512(),     detail::TierBatch2048(),
                                          detail::TierBatch4800(),    detail::TierWindow32(),
                                          detail::TierWindow32Wide(), detail::TierWindow128()};
    std::stable_sort(t.begin(), t.end(),
                     [](const auto& a, const auto& b) { return a.info.bytes < b.info.bytes; });
    return t;
  }();
  return kTiers;
}

bool Holds(const KittiVoCapacity& c, const KittiVoCapacity& needs) {
  return needs.window_poses <= c.window_poses && needs.landmarks <= c.landmarks &&
         needs.factors_per_pose <= c.factors_per_pose && needs.prior_landmarks <= c.prior_landmarks;
}

std::string Describe(const KittiVoCapacity& c) {
  std::ostringstream os;
  os << "K=" << c.window_poses << " poses, N=" << c.landmarks
     << " landmarks, M=" << c.factors_per_pose << " factors per pose, P=" << c.prior_landmarks
     << " prior landmarks";
  return os.str();
}

std::string Megabytes(std::uint64_t bytes) {
  return std::to_string((bytes + 500000) / 1000000) + " MB";
}

// Which counts no compiled instance reaches, against the largest value any instance has.
std::string BeyondEveryTier(const KittiVoCapacity& needs) {
  KittiVoCapacity most;
  for (const auto& t : Tiers()) {
    const KittiVoCapacity& c = t.info.capacity;
    most.window_poses = std::max(most.window_poses, c.window_poses);
    most.landmarks = std::max(most.landmarks, c.landmarks);
    most.factors_per_pose = std::max(most.factors_per_pose, c.factors_per_pose);
    most.prior_landmarks = std::max(most.prior_landmarks, c.prior_landmarks);
  }
  std::ostringstream os;
  os << "no compiled filter instance holds this problem (it needs " << Describe(needs) << ")";
  auto beyond = [&](const char* what, int need, int have) {
    if (need > have) os << "; " << need << " " << what << " > " << have << ", the most any has";
  };
  beyond("window poses", needs.window_poses, most.window_poses);
  beyond("landmarks", needs.landmarks, most.landmarks);
  beyond("factors per pose", needs.factors_per_pose, most.factors_per_pose);
  beyond("prior landmarks", needs.prior_landmarks, most.prior_landmarks);
  return os.str();
}

}  // namespace

std::vector<KittiVoTierInfo> KittiVoTiers() {
  std::vector<KittiVoTierInfo> out;
  for (const auto& t : Tiers()) out.push_back(t.info);
  return out;
}

KittiVoPlan PlanKittiVo(const KittiVoCapacity& needs, std::uint64_t available_bytes) {
  KittiVoPlan plan;
  plan.needs = needs;
  const auto& tiers = Tiers();
  for (std::size_t i = 0; i < tiers.size(); ++i) {
    if (!Holds(tiers[i].info.capacity, needs)) continue;
    if (available_bytes != 0 && tiers[i].info.bytes > available_bytes) {
      plan.error = "the problem needs a filter instance of " + Megabytes(tiers[i].info.bytes) +
                   " (" + tiers[i].info.name + ": " + Describe(tiers[i].info.capacity) +
                   "; the problem needs " + Describe(needs) + ") but only " +
                   Megabytes(available_bytes) + " of memory is available";
      return plan;
    }
    plan.tier = static_cast<int>(i);
    plan.ok = true;
    return plan;
  }
  plan.error = BeyondEveryTier(needs);
  return plan;
}

std::uint64_t AvailableMemoryBytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  std::uint64_t value = 0;
  std::string unit;
  while (in >> key >> value) {
    std::getline(in, unit);
    if (key == "MemAvailable:") return value * 1024;  // the kernel reports kB
  }
  return 0;
}

// ---- solving ---------------------------------------------------------------------------------

namespace detail {

std::string FaultNames(std::uint32_t bits) {
  static const std::pair<std::uint32_t, const char*> kNames[] = {
      {estimator::kFaultNotPositiveDefinite, "not positive definite"},
      {estimator::kFaultNonFinite, "non-finite residual or update"},
      {estimator::kFaultNotConverged, "not converged"},
      {estimator::kFaultLandmarkCapacity, "landmark capacity"},
      {estimator::kFaultMeasurementCapacity, "measurement capacity"},
      {estimator::kFaultPriorCapacity, "prior capacity"},
      {estimator::kFaultDegenerateLandmark, "degenerate landmark"},
      {estimator::kFaultReset, "filter reset"},
      {estimator::kFaultGateSuspended, "gate suspended"},
  };
  std::string out;
  for (const auto& [bit, name] : kNames) {
    if ((bits & bit) == 0u) continue;
    out += (out.empty() ? "" : ", ");
    out += name;
    bits &= ~bit;
  }
  if (bits != 0u) out += (out.empty() ? "" : ", ") + std::string("other");
  return out.empty() ? "no fault bit" : out;
}

}  // namespace detail

KittiVoSolver::KittiVoSolver() = default;
KittiVoSolver::~KittiVoSolver() = default;

KittiVoResult SolveKittiVo(const KittiVoProblem& problem, int window) {
  return KittiVoSolver().Solve(problem, window);
}

KittiVoResult KittiVoSolver::Solve(const KittiVoProblem& problem, int window) {
  KittiVoResult result;
  if (problem.poses.empty() || problem.factors.empty()) {
    result.error = "empty problem: no poses or no factors";
    return result;
  }
  result.needs = KittiVoNeeds(problem, window);
  // The instance held now is freed before another is built, so its memory counts as available.
  std::uint64_t available = memory_override_ != 0 ? memory_override_ : AvailableMemoryBytes();
  if (available != 0 && tier_ >= 0) available += Tiers()[tier_].info.bytes;
  const KittiVoPlan plan = PlanKittiVo(result.needs, available);
  if (!plan.ok) {
    result.error = plan.error;
    return result;
  }
  const detail::KittiVoTier& tier = Tiers()[plan.tier];
  if (plan.tier != tier_) {
    instance_.reset();
    tier_ = -1;
    try {
      instance_ = tier.make();
    } catch (const std::bad_alloc&) {
      result.error = "allocating the " + tier.info.name + " filter instance (" +
                     Megabytes(tier.info.bytes) + ") failed";
      return result;
    }
    tier_ = plan.tier;
  }
  KittiVoResult solved = instance_->Solve(problem, window);
  solved.needs = result.needs;
  solved.instance = tier.info;
  return solved;
}

double KittiVoCost(const KittiVoProblem& problem, const std::vector<Pose<double>>& poses,
                   const std::vector<std::int64_t>& landmark_ids,
                   const std::vector<Vec3<double>>& landmarks, int* behind_camera) {
  std::unordered_map<std::int64_t, int> where;
  for (std::size_t i = 0; i < landmark_ids.size(); ++i)
    where[landmark_ids[i]] = static_cast<int>(i);
  double cost = 0.0;
  int behind = 0;
  for (const KittiFactor& f : problem.factors) {
    const auto it = where.find(f.landmark);
    const Vec3<double> p_c = poses[f.pose].ApplyInverse(it != where.end() ? landmarks[it->second]
                                                                          : Vec3<double>::Zero());
    // The residual is evaluated as Ceres evaluates it, also for a point behind the camera (the
    // filter skips such a measurement while solving; skipping it here would report a lower cost
    // than the optimum). A landmark the solver did not return counts as infinite cost.
    if (it == where.end()) return std::numeric_limits<double>::infinity();
    behind += p_c.z() > 0.0 ? 0 : 1;
    cost += 0.5 * (f.z - problem.camera.Project(p_c)).squaredNorm();
  }
  if (behind_camera != nullptr) *behind_camera = behind;
  return cost;
}

// ---- output ----------------------------------------------------------------------------------

namespace {

nlohmann::ordered_json CapacityJson(const KittiVoCapacity& c) {
  return {{"K", c.window_poses},
          {"N", c.landmarks},
          {"M", c.factors_per_pose},
          {"P", c.prior_landmarks}};
}

// A finite number, or null (JSON has no inf or nan).
nlohmann::ordered_json Number(double v) { return nlohmann::ordered_json(ground_cli::Number(v)); }

}  // namespace

nlohmann::ordered_json KittiVoReport(const KittiVoProblem& problem, const KittiVoResult& r,
                                     int window) {
  nlohmann::ordered_json report;
  report["mode"] = window > 0 ? "sliding_window" : "batch";
  report["window"] = std::max(window, 0);
  report["instance"] = {{"name", r.instance.name},
                        {"capacity", CapacityJson(r.instance.capacity)},
                        {"bytes", r.instance.bytes}};
  report["needs"] = CapacityJson(r.needs);
  report["initial_cost"] = Number(r.initial_cost);
  report["final_cost"] = Number(r.final_cost);
  report["iterations"] = r.iterations;
  report["solve_time_ms"] = Number(r.solve_time_ms);
  report["max_prior_landmarks"] = r.max_prior_landmarks;
  report["factors_behind_camera"] = r.factors_behind_camera;
  report["fault_bits"] = r.fault_bits;
  nlohmann::ordered_json poses = nlohmann::ordered_json::array();
  for (std::size_t j = 0; j < r.poses.size(); ++j) {
    const Eigen::Matrix4d m = r.poses[j].Matrix();
    nlohmann::ordered_json camera_to_world = nlohmann::ordered_json::array();
    for (int k = 0; k < 16; ++k) camera_to_world.push_back(Number(m(k / 4, k % 4)));
    poses.push_back({{"id", problem.pose_ids[j]}, {"camera_to_world", camera_to_world}});
  }
  report["poses"] = std::move(poses);
  return report;
}

}  // namespace swf::tools
