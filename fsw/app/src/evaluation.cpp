#include "swf/app/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace swf::app {

void Evaluation::OnNav(const NavRecord& r) {
  navs_.push_back(
      Nav{r.nav.frame_seq,
          {r.nav.position_world_m[0], r.nav.position_world_m[1], r.nav.position_world_m[2]}});
}

void Evaluation::OnMap(const MapRecord& r) {
  Map m;
  m.frame_seq = r.map.frame_seq;
  m.landmarks.reserve(r.map.num_landmarks);
  for (int i = 0; i < r.map.num_landmarks; ++i) {
    const MapLandmark& l = r.map.landmarks[i];
    m.landmarks.push_back(
        Landmark{l.id, {l.position_world_m[0], l.position_world_m[1], l.position_world_m[2]}});
  }
  maps_.push_back(std::move(m));
}

EvaluationResult Evaluation::Evaluate(const Pipeline& pipeline, const sim::Trajectory& trajectory,
                                      const sim::Terrain& terrain,
                                      const std::string& plot_dir) const {
  EvaluationResult result;
  const estimator::StereoCamera<double>& cam = pipeline.Camera();
  std::FILE* traj =
      plot_dir.empty() ? nullptr : std::fopen((plot_dir + "/trajectory.dat").c_str(), "w");
  if (traj != nullptr) {
    std::fprintf(traj, "# frame est_x est_y est_z true_x true_y true_z error_m\n");
  }
  double sum2 = 0.0;
  for (const Nav& n : navs_) {
    if (n.frame_seq < 0 || n.frame_seq >= trajectory.NumFrames()) continue;
    const Eigen::Vector3d t = trajectory.WorldTCamera(static_cast<std::int32_t>(n.frame_seq)).t;
    const double e = (Eigen::Vector3d(n.p[0], n.p[1], n.p[2]) - t).norm();
    sum2 += e * e;
    ++result.navs;
    result.final_pose_error_m = e;
    if (traj != nullptr) {
      std::fprintf(traj, "%lld %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n",
                   static_cast<long long>(n.frame_seq), n.p[0], n.p[1], n.p[2], t.x(), t.y(), t.z(),
                   e);
    }
  }
  if (traj != nullptr) std::fclose(traj);
  result.pose_rms_error_m = result.navs > 0 ? std::sqrt(sum2 / result.navs) : 0.0;

  // True landmark positions, computed once per id.
  std::map<std::int64_t, Eigen::Vector3d> truth;
  auto true_position = [&](std::int64_t id, Eigen::Vector3d* p) {
    const auto it = truth.find(id);
    if (it != truth.end()) {
      *p = it->second;
      return std::isfinite(p->x());
    }
    const FirstSighting& s = pipeline.Sighting(id);
    Eigen::Vector3d value = Eigen::Vector3d::Constant(NAN);
    if (s.frame_seq >= 0 && s.frame_seq < trajectory.NumFrames()) {
      const estimator::Pose<double>& pose =
          trajectory.WorldTCamera(static_cast<std::int32_t>(s.frame_seq));
      const Eigen::Vector3d ray =
          pose.R * Eigen::Vector3d((s.u_left - cam.cx) / cam.fx, (s.v - cam.cy) / cam.fy, 1.0);
      double t = 0.0;
      if (terrain.Intersect(pose.t, ray, &t)) value = pose.t + t * ray;
    }
    truth[id] = value;
    *p = value;
    return std::isfinite(value.x());
  };
  std::FILE* err =
      plot_dir.empty() ? nullptr : std::fopen((plot_dir + "/landmark_error.dat").c_str(), "w");
  if (err != nullptr) std::fprintf(err, "# frame rms_error_m median_error_m landmarks\n");
  std::vector<double> errors;
  for (const Map& m : maps_) {
    errors.clear();
    for (const Landmark& l : m.landmarks) {
      Eigen::Vector3d t;
      if (!true_position(l.id, &t)) continue;
      errors.push_back((Eigen::Vector3d(l.p[0], l.p[1], l.p[2]) - t).norm());
    }
    ++result.maps;
    double s2 = 0.0;
    for (double e : errors) s2 += e * e;
    const double rms = errors.empty() ? 0.0 : std::sqrt(s2 / errors.size());
    double median = 0.0;
    if (!errors.empty()) {
      std::vector<double> sorted = errors;
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      median = sorted[sorted.size() / 2];
    }
    result.landmark_rms_error_m = rms;
    result.landmark_median_error_m = median;
    result.landmarks_evaluated = static_cast<std::int64_t>(errors.size());
    if (err != nullptr) {
      std::fprintf(err, "%lld %.6f %.6f %zu\n", static_cast<long long>(m.frame_seq), rms, median,
                   errors.size());
    }
  }
  if (err != nullptr) std::fclose(err);
  // The last map with its truth, for the map view.
  if (!plot_dir.empty() && !maps_.empty()) {
    if (std::FILE* f = std::fopen((plot_dir + "/map.dat").c_str(), "w")) {
      std::fprintf(f, "# est_x est_y est_z true_x true_y true_z error_m\n");
      for (const Landmark& l : maps_.back().landmarks) {
        Eigen::Vector3d t;
        if (!true_position(l.id, &t)) continue;
        std::fprintf(f, "%.6f %.6f %.6f %.6f %.6f %.6f %.6f\n", l.p[0], l.p[1], l.p[2], t.x(),
                     t.y(), t.z(), (Eigen::Vector3d(l.p[0], l.p[1], l.p[2]) - t).norm());
      }
      std::fclose(f);
    }
  }
  return result;
}

}  // namespace swf::app
