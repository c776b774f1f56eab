#include "kitti_vo_synth.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <random>

namespace swf::tools {
namespace {

using estimator::Mat3;
using estimator::Pose;
using estimator::Vec3;

// Uniform and normal deviates from the raw 64-bit Mersenne twister output, which the standard
// fixes bit for bit; std::*_distribution is implementation-defined, so it would make the problem
// depend on the standard library.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  int Below(int n) { return static_cast<int>(Uniform() * n); }
  double Normal() {                     // Box-Muller
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  Vec3<double> Normal3(double sigma) {
    const double x = Normal();
    const double y = Normal();
    return Vec3<double>(x, y, Normal()) * sigma;
  }

 private:
  std::mt19937_64 engine_;
};

Mat3<double> RotationY(double a) {
  Mat3<double> r;
  r << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return r;
}

// A car-like path in the x-z plane of the first camera (y down): ~step_m per pose with a slowly
// varying speed, a gentle S-curve in heading, small pitch and roll from the suspension.
std::vector<Pose<double>> CarPath(const KittiLikeOptions& o) {
  std::vector<Pose<double>> path(o.poses);
  Vec3<double> t = Vec3<double>::Zero();
  for (int j = 0; j < o.poses; ++j) {
    const double s = static_cast<double>(j) / std::max(1, o.poses - 1);
    const double heading = 0.25 * std::sin(2.0 * M_PI * s) + 0.1 * s;
    const double pitch = 0.01 * std::sin(0.7 * j);
    const double roll = 0.005 * std::sin(0.45 * j);
    const Vec3<double> tilt(pitch, 0.0, roll);
    path[j].R = RotationY(heading) * estimator::ExpSO3<double>(tilt);
    path[j].t = t + Vec3<double>(0.0, 0.03 * std::sin(0.3 * j), 0.0);
    if (j == 0) path[j] = Pose<double>::Identity();  // the data set's first pose
    const double speed = o.step_m * (1.0 + 0.08 * std::sin(0.2 * j));
    t += speed * Vec3<double>(std::sin(heading), 0.0, std::cos(heading));
  }
  return path;
}

// Run lengths 2 + Geometric, capped, then nudged one at a time until they sum to observations.
std::vector<int> TrackLengths(const KittiLikeOptions& o, int max_track, Rng* rng) {
  const double extra_mean = static_cast<double>(o.observations) / o.landmarks - 2.0;
  const double p = 1.0 / (1.0 + std::max(extra_mean, 1e-9));  // success probability
  std::vector<int> length(o.landmarks);
  long total = 0;
  for (int& l : length) {
    l = 2;
    while (l < max_track && rng->Uniform() >= p) ++l;
    total += l;
  }
  while (total != o.observations) {
    int& l = length[rng->Below(o.landmarks)];
    if (total < o.observations && l < max_track) {
      ++l;
      ++total;
    } else if (total > o.observations && l > 2) {
      --l;
      --total;
    }
  }
  return length;
}

// First pose of each run: longest runs first, each where the poses it covers are least loaded
// so far (scanning from a random offset to break ties), which evens out the factors per pose.
std::vector<int> RunStarts(const std::vector<int>& length, int poses, Rng* rng) {
  std::vector<int> order(length.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return length[a] > length[b]; });
  std::vector<long> load(poses, 0);
  std::vector<int> start(length.size(), 0);
  for (int i : order) {
    const int choices = poses - length[i] + 1;
    const int offset = rng->Below(choices);
    long best = -1;
    for (int c = 0; c < choices; ++c) {
      const int s = (offset + c) % choices;
      long sum = 0;
      for (int j = s; j < s + length[i]; ++j) sum += load[j];
      if (best < 0 || sum < best) {
        best = sum;
        start[i] = s;
      }
    }
    for (int j = start[i]; j < start[i] + length[i]; ++j) ++load[j];
  }
  return start;
}

// A point first seen from pose `first` at a random pixel and log-uniform depth that projects
// into the image from every pose of its run; its noisy measurements go to *z. Retries until
// one fits (false after many tries).
bool PlaceLandmark(const estimator::StereoCamera<double>& camera, const KittiLikeOptions& o,
                   const std::vector<Pose<double>>& truth, int first, int length, Rng* rng,
                   std::vector<Vec3<double>>* z) {
  auto inside = [&](const Vec3<double>& m) {
    return m.x() >= 0 && m.x() < o.width_px && m.y() >= 0 && m.y() < o.width_px && m.z() >= 0 &&
           m.z() < o.height_px;
  };
  for (int attempt = 0; attempt < 10000; ++attempt) {
    const double u = rng->Uniform() * o.width_px;
    const double v = rng->Uniform() * o.height_px;
    const double depth = o.min_depth_m * std::pow(o.max_depth_m / o.min_depth_m, rng->Uniform());
    const Vec3<double> p_c((u - camera.cx) * depth / camera.fx, (v - camera.cy) * depth / camera.fy,
                           depth);
    const Vec3<double> world = truth[first].Apply(p_c);
    z->clear();
    for (int j = first; j < first + length; ++j) {
      const Vec3<double> p = truth[j].ApplyInverse(world);
      if (!(p.z() > 1.0)) break;
      const Vec3<double> m = camera.Project(p);
      if (!inside(m)) break;
      const Vec3<double> noisy = m + rng->Normal3(o.pixel_sigma);
      // Keep every measurement a point stereo can place with some margin (the loader refuses a
      // non-positive disparity); a far point's noisy disparity could otherwise reach zero.
      if (!(noisy.x() - noisy.y() > 0.5)) break;
      z->push_back(noisy);
    }
    if (static_cast<int>(z->size()) == length) return true;
  }
  return false;
}

// Initial estimates: the true relative motions, each with a small random error (VO-like drift).
std::vector<Pose<double>> Drifted(const std::vector<Pose<double>>& truth, const KittiLikeOptions& o,
                                  Rng* rng) {
  std::vector<Pose<double>> init(truth.size());
  init[0] = truth[0];
  for (std::size_t j = 1; j < truth.size(); ++j) {
    const Vec3<double> dt = rng->Normal3(o.drift_sigma_m);
    const Pose<double> error{estimator::ExpSO3<double>(rng->Normal3(o.drift_sigma_rad)), dt};
    init[j] = init[j - 1] * (truth[j - 1].Inverse() * truth[j]) * error;
  }
  return init;
}

bool Check(const KittiLikeOptions& o, std::string* error) {
  const char* why = nullptr;
  if (o.poses < 2)
    why = "at least 2 poses";
  else if (o.landmarks < 1)
    why = "at least 1 landmark";
  else if (o.observations < 2L * o.landmarks)
    why = "at least 2 observations per landmark";
  else if (o.observations > static_cast<long>(std::min(o.max_track, o.poses)) * o.landmarks)
    why = "at most min(max_track, poses) observations per landmark";
  else if (!(o.pixel_sigma >= 0 && o.drift_sigma_m >= 0 && o.drift_sigma_rad >= 0))
    why = "non-negative noise";
  else if (!(o.min_depth_m > 1.0 && o.max_depth_m >= o.min_depth_m))
    why = "1 m < min_depth_m <= max_depth_m";
  if (why != nullptr) *error = std::string("generator options: need ") + why;
  return why == nullptr;
}

}  // namespace

bool GenerateKittiLike(const estimator::StereoCamera<double>& camera_in,
                       const KittiLikeOptions& options, KittiVoProblem* problem,
                       std::vector<Pose<double>>* truth, std::string* error) {
  const estimator::StereoCamera<double> camera = camera_in;  // may alias problem->camera
  if (!Check(options, error)) return false;
  Rng rng(options.seed);
  const std::vector<Pose<double>> path = CarPath(options);
  const int max_track = std::min(options.max_track, options.poses);
  const std::vector<int> length = TrackLengths(options, max_track, &rng);
  const std::vector<int> start = RunStarts(length, options.poses, &rng);
  // Landmark ids in order of first sight, as a front end numbers them.
  std::vector<int> order(length.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return start[a] < start[b]; });

  *problem = KittiVoProblem{};
  problem->camera = camera;
  problem->factors_path = "<generated>";
  for (int j = 0; j < options.poses; ++j) problem->pose_ids.push_back(j + 1);
  std::vector<Vec3<double>> z;
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    const int i = order[rank];
    if (!PlaceLandmark(camera, options, path, start[i], length[i], &rng, &z)) {
      *error = "generator: cannot place a landmark seen from poses " + std::to_string(start[i]) +
               ".." + std::to_string(start[i] + length[i] - 1);
      return false;
    }
    for (int k = 0; k < length[i]; ++k) {
      KittiFactor f;
      f.pose = start[i] + k;
      f.landmark = static_cast<std::int64_t>(rank) + 1;
      f.z = z[k];
      f.line = static_cast<int>(problem->factors.size()) + 1;  // landmark by landmark
      problem->factors.push_back(f);
    }
  }
  problem->poses = Drifted(path, options, &rng);
  std::stable_sort(problem->factors.begin(), problem->factors.end(),
                   [](const KittiFactor& a, const KittiFactor& b) { return a.pose < b.pose; });
  if (truth != nullptr) *truth = path;
  return true;
}

bool WriteKittiVo(const KittiVoProblem& problem, const std::string& calib_path,
                  const std::string& poses_path, const std::string& factors_path,
                  std::string* error) {
  auto fail = [&](const std::string& path) {
    *error = path + ": cannot write";
    return false;
  };
  char buf[512];
  {
    std::ofstream out(calib_path);
    const auto& c = problem.camera;
    std::snprintf(buf, sizeof(buf), "%.17g %.17g 0 %.17g %.17g %.17g\n", c.fx, c.fy, c.cx, c.cy,
                  c.baseline_m);
    out << buf;
    if (!out) return fail(calib_path);
  }
  {
    std::ofstream out(poses_path);
    for (std::size_t j = 0; j < problem.poses.size(); ++j) {
      const Eigen::Matrix4d m = problem.poses[j].Matrix();
      out << problem.pose_ids[j];
      for (int k = 0; k < 16; ++k) {
        std::snprintf(buf, sizeof(buf), " %.17g", m(k / 4, k % 4));
        out << buf;
      }
      out << '\n';
    }
    if (!out) return fail(poses_path);
  }
  std::vector<const KittiFactor*> by_line;
  for (const KittiFactor& f : problem.factors) by_line.push_back(&f);
  std::stable_sort(by_line.begin(), by_line.end(),
                   [](const KittiFactor* a, const KittiFactor* b) { return a->line < b->line; });
  std::ofstream out(factors_path);
  for (const KittiFactor* f : by_line) {
    Vec3<double> p(0, 0, 0);
    (void)problem.camera.Triangulate(f->z, &p);
    std::snprintf(buf, sizeof(buf), "%lld %lld %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  static_cast<long long>(problem.pose_ids[f->pose]),
                  static_cast<long long>(f->landmark), f->z.x(), f->z.y(), f->z.z(), p.x(), p.y(),
                  p.z());
    out << buf;
  }
  if (!out) return fail(factors_path);
  return true;
}

}  // namespace swf::tools
