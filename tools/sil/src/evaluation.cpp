#include "swf/sil/evaluation.hpp"

#include "swf/evaluation/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "swf/app/hazard_stage.hpp"

namespace swf::sil {

void Evaluation::OnNav(const app::NavRecord& r) {
  Nav n{r.nav.frame_seq,
        {r.nav.position_world_m[0], r.nav.position_world_m[1], r.nav.position_world_m[2]},
        {r.nav.orientation_world_q[0], r.nav.orientation_world_q[1], r.nav.orientation_world_q[2],
         r.nav.orientation_world_q[3]},
        r.nav.status,
        r.nav.horizontal_protection_m,
        r.nav.vertical_protection_m,
        {}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) n.position_covariance[3 * i + j] = r.nav.covariance[6 * i + j];
  navs_.push_back(n);
}

namespace {
// e^T P^-1 e, NaN when P is not positive definite (an output without covariance).
double Nees(const Eigen::Vector3d& e, const double* covariance) {
  const Eigen::Matrix3d p =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(covariance);
  const Eigen::LLT<Eigen::Matrix3d> llt(p);
  if (llt.info() != Eigen::Success || !(p.trace() > 0.0)) return NAN;
  return e.dot(llt.solve(e));
}

// The angle of est_R^T true_R in degrees (est_R from a w, x, y, z quaternion).
double AttitudeErrorDeg(const double* q, const Eigen::Matrix3d& true_rotation) {
  const Eigen::Quaterniond est(q[0], q[1], q[2], q[3]);
  if (!(est.norm() > 0.0)) return NAN;
  const Eigen::AngleAxisd d(est.normalized().toRotationMatrix().transpose() * true_rotation);
  return d.angle() * 180.0 / M_PI;
}
}  // namespace

double ImuOnlyPoseRms(const sim::ImuModel& unit, const sim::Trajectory& trajectory,
                      const app::ImuOptions& imu,
                      const estimator::Pose<double>& initial_world_T_camera) {
  estimator::InertialStereoModel<double> model;
  model.imu_T_camera = imu.imu_T_camera;
  model.gravity_world_mps2 = imu.gravity_world_mps2;
  estimator::NavState<double> x;
  x.world_T_imu = initial_world_T_camera * imu.imu_T_camera.Inverse();
  x.velocity_world_mps = imu.initial_velocity_world_mps;
  const std::vector<estimator::ImuSample<double>>& samples = unit.Samples();
  double sum2 = 0.0;
  for (std::int32_t k = 1; k < trajectory.NumFrames(); ++k) {
    estimator::ImuPreintegration<double> pim;
    estimator::IntervalSummary summary;
    if (pim.Reset(imu.noise, x.biases) != core::Status::kOk ||
        estimator::PreintegrateInterval(
            samples.data(), static_cast<int>(samples.size()), trajectory.FrameTimeNs(k - 1) / 1000,
            trajectory.FrameTimeNs(k) / 1000, imu.hold, 1.0, &pim, &summary) != core::Status::kOk) {
      return NAN;
    }
    x = model.Propagate(x, pim);
    sum2 += (model.CameraPose(x).t - trajectory.WorldTCamera(k).t).squaredNorm();
  }
  return trajectory.NumFrames() > 1 ? std::sqrt(sum2 / trajectory.NumFrames()) : 0.0;
}

void Evaluation::OnMap(const app::MapRecord& r) {
  Map m;
  m.frame_seq = r.map.frame_seq;
  m.landmarks.reserve(r.map.num_landmarks);
  for (int i = 0; i < r.map.num_landmarks; ++i) {
    const app::MapLandmark& l = r.map.landmarks[i];
    m.landmarks.push_back(
        Landmark{l.id, {l.position_world_m[0], l.position_world_m[1], l.position_world_m[2]}});
  }
  maps_.push_back(std::move(m));
}

EvaluationResult Evaluation::Evaluate(const app::Pipeline& pipeline,
                                      const sim::Trajectory& trajectory,
                                      const sim::Terrain& terrain,
                                      const std::string& plot_dir) const {
  EvaluationResult result;
  const estimator::StereoCamera<double>& cam = pipeline.Camera();
  std::FILE* traj =
      plot_dir.empty() ? nullptr : std::fopen((plot_dir + "/trajectory.dat").c_str(), "w");
  if (traj != nullptr) {
    std::fprintf(traj, "# frame est_x est_y est_z true_x true_y true_z error_m\n");
  }
  std::vector<double> pose_errors;
  double nees_sum = 0.0;
  int nees_count = 0;
  for (const Nav& n : navs_) {
    if (n.frame_seq < 0 || n.frame_seq >= trajectory.NumFrames()) continue;
    const estimator::Pose<double>& truth =
        trajectory.WorldTCamera(static_cast<std::int32_t>(n.frame_seq));
    const Eigen::Vector3d& t = truth.t;
    const double e = (Eigen::Vector3d(n.p[0], n.p[1], n.p[2]) - t).norm();
    EvaluationResult::Output o;
    o.frame_seq = n.frame_seq;
    o.altitude_m = t.z() - terrain.HeightAt(t.x(), t.y());
    o.horizontal_error_m = std::hypot(n.p[0] - t.x(), n.p[1] - t.y());
    o.vertical_error_m = std::abs(n.p[2] - t.z());
    o.attitude_error_deg = AttitudeErrorDeg(n.q, truth.R);
    o.status = n.status;
    o.hpl_m = n.hpl_m;
    o.vpl_m = n.vpl_m;
    result.outputs.push_back(o);
    result.final_attitude_error_deg = o.attitude_error_deg;
    pose_errors.push_back(e);
    const double nees = Nees(Eigen::Vector3d(n.p[0], n.p[1], n.p[2]) - t, n.position_covariance);
    result.position_nees.push_back(nees);
    if (std::isfinite(nees)) {
      nees_sum += nees;
      ++nees_count;
    }
    ++result.navs;
    result.final_pose_error_m = e;
    if (n.status == static_cast<std::int8_t>(estimator::NavIntegrity::kValid)) {
      const double ratio = std::max(n.hpl_m > 0.0 ? o.horizontal_error_m / n.hpl_m : 1e9,
                                    n.vpl_m > 0.0 ? o.vertical_error_m / n.vpl_m : 1e9);
      ++result.valid_navs;
      result.protection_violations += ratio > 1.0 ? 1 : 0;
      result.max_error_over_protection =
          std::max(result.max_error_over_protection, std::min(ratio, 1e9));
    }
    if (traj != nullptr) {
      std::fprintf(traj, "%lld %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n",
                   static_cast<long long>(n.frame_seq), n.p[0], n.p[1], n.p[2], t.x(), t.y(), t.z(),
                   e);
    }
  }
  if (traj != nullptr) std::fclose(traj);
  result.pose_rms_error_m = result.navs > 0 ? evaluation::Rms(pose_errors) : 0.0;
  result.mean_position_nees = nees_count > 0 ? nees_sum / nees_count : NAN;

  // True landmark positions, computed once per id.
  std::map<std::int64_t, Eigen::Vector3d> truth;
  auto true_position = [&](std::int64_t id, Eigen::Vector3d* p) {
    const auto it = truth.find(id);
    if (it != truth.end()) {
      *p = it->second;
      return std::isfinite(p->x());
    }
    const app::FirstSighting& s = pipeline.Sighting(id);
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
    // NaN for a map with no landmark evaluated (the summary then says null).
    const double rms = evaluation::Rms(errors);
    const double median = evaluation::Quantile(errors, 0.5);  // the upper median
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

}  // namespace swf::sil

namespace swf::sil {

void Evaluation::OnHazard(const app::HazardRecord& r) {
  PublishedHazardMap m;
  m.frame_seq = r.frame_seq;
  m.origin_m[0] = r.origin_world_m[0];
  m.origin_m[1] = r.origin_world_m[1];
  m.cell_m = r.cell_size_m;
  m.cells_per_side = r.cells_per_side;
  const std::size_t cells = static_cast<std::size_t>(r.cells_per_side) * r.cells_per_side;
  m.elevation_m.assign(r.elevation_m.get(), r.elevation_m.get() + cells);
  m.sigma_m.assign(r.sigma_m.get(), r.sigma_m.get() + cells);
  m.classes.assign(r.hazard_class.get(), r.hazard_class.get() + cells);
  m.site_valid = r.safe_site_valid;
  m.site_m[0] = r.safe_site_world_m[0];
  m.site_m[1] = r.safe_site_world_m[1];
  m.site_score = r.safe_site_score;
  hazard_maps_.push_back(std::move(m));
}

std::vector<HazardEvaluation> Evaluation::EvaluateHazard(
    const hazard::HazardMapperOptions& thresholds, const sim::Trajectory& trajectory,
    const sim::Terrain& terrain) const {
  std::vector<HazardEvaluation> result;
  sim::HazardOptions ho;
  ho.max_slope_deg = thresholds.max_slope_deg;
  ho.max_rock_height_m = thresholds.max_rock_height_m;
  sim::HazardMap truth;
  if (hazard_maps_.empty() || sim::ComputeHazardTruth(terrain, ho, &truth) != core::Status::kOk)
    return result;
  for (const PublishedHazardMap& m : hazard_maps_) {
    HazardEvaluation e = EvaluateHazardMap(m, thresholds, terrain, truth);
    if (m.frame_seq >= 0 && m.frame_seq < trajectory.NumFrames()) {
      const Eigen::Vector3d& t = trajectory.WorldTCamera(static_cast<std::int32_t>(m.frame_seq)).t;
      e.altitude_m = t.z() - terrain.HeightAt(t.x(), t.y());
    }
    result.push_back(e);
  }
  return result;
}

namespace {
// The height class of a rock of height h against the threshold (kRockHeightClasses classes).
int RockHeightClass(double h, double threshold) {
  if (h < 2.0 * threshold) return 0;
  return h < 4.0 * threshold ? 1 : 2;
}
}  // namespace

HazardEvaluation Evaluation::EvaluateHazardMap(const PublishedHazardMap& m,
                                               const hazard::HazardMapperOptions& o,
                                               const sim::Terrain& terrain,
                                               const sim::HazardMap& truth) {
  HazardEvaluation r;
  r.frame_seq = m.frame_seq;
  const int n = m.cells_per_side;
  const double cell = m.cell_m;
  if (n <= 0 || !(cell > 0.0)) return r;
  const std::int8_t rock_code = app::HazardClassCode(hazard::HazardClass::kRock);
  const int tn = truth.size;
  const double tcell = terrain.CellM();
  const auto cell_of = [&](double x, double y, int* i, int* j) {
    const double fx = (x - m.origin_m[0]) / cell;
    const double fy = (y - m.origin_m[1]) / cell;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < n && fy < n)) return false;
    *i = static_cast<int>(fx);
    *j = static_cast<int>(fy);
    return true;
  };
  // Truth nodes within radius of (x, y); f(node index, distance) for each.
  const auto for_nodes_near = [&](double x, double y, double radius, auto&& f) {
    const int ci = static_cast<int>(std::lround((x - terrain.NodeX(0)) / tcell));
    const int cj = static_cast<int>(std::lround((y - terrain.NodeY(0)) / tcell));
    const int rn = static_cast<int>(std::ceil(radius / tcell));
    for (int j = std::max(0, cj - rn); j <= std::min(tn - 1, cj + rn); ++j) {
      for (int i = std::max(0, ci - rn); i <= std::min(tn - 1, ci + rn); ++i) {
        const double d = std::hypot(terrain.NodeX(i) - x, terrain.NodeY(j) - y);
        if (d <= radius) f(static_cast<std::size_t>(j) * tn + i, d);
      }
    }
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      if (std::isnan(m.elevation_m[c])) continue;
      ++r.known_cells;
      float rock = 0.0f;
      for_nodes_near(m.origin_m[0] + (i + 0.5) * cell, m.origin_m[1] + (j + 0.5) * cell,
                     0.5 * cell + 0.3,
                     [&](std::size_t k, double) { rock = std::max(rock, truth.rock_height_m[k]); });
      if (rock >= 0.5 * o.max_rock_height_m) continue;
      ++r.rock_free_cells;
      r.false_rock_cells += m.classes[c] == rock_code;
    }
  }
  if (r.rock_free_cells > 0) {
    r.false_alarm_rate = static_cast<double>(r.false_rock_cells) / r.rock_free_cells;
  }
  for (const sim::Rock& rock : terrain.Rocks()) {
    if (rock.height_m < o.max_rock_height_m) continue;
    int ci = 0;
    int cj = 0;
    if (!cell_of(rock.center_m.x(), rock.center_m.y(), &ci, &cj)) continue;
    const float sigma = m.sigma_m[static_cast<std::size_t>(cj) * n + ci];
    if (!(3.0 * sigma <= o.max_rock_height_m)) continue;
    const int height_class = RockHeightClass(rock.height_m, o.max_rock_height_m);
    ++r.rocks_resolved;
    ++r.rocks_resolved_by_height[height_class];
    const double radius = 0.5 * rock.diameter_m + cell;
    const int rc = static_cast<int>(std::ceil(radius / cell));
    bool found = false;
    for (int j = std::max(0, cj - rc); j <= std::min(n - 1, cj + rc) && !found; ++j) {
      for (int i = std::max(0, ci - rc); i <= std::min(n - 1, ci + rc); ++i) {
        const double dx = m.origin_m[0] + (i + 0.5) * cell - rock.center_m.x();
        const double dy = m.origin_m[1] + (j + 0.5) * cell - rock.center_m.y();
        if (std::hypot(dx, dy) <= radius &&
            m.classes[static_cast<std::size_t>(j) * n + i] == rock_code) {
          found = true;
          break;
        }
      }
    }
    r.rocks_detected += found;
    r.rocks_detected_by_height[height_class] += found;
  }
  if (r.rocks_resolved > 0) {
    r.detection_probability = static_cast<double>(r.rocks_detected) / r.rocks_resolved;
  }
  r.site_valid = m.site_valid;
  if (m.site_valid) {
    r.site_x_m = m.site_m[0];
    r.site_y_m = m.site_m[1];
    r.site_score = m.site_score;
    constexpr double kSearchM = 20.0;
    double nearest = kSearchM;
    for_nodes_near(r.site_x_m, r.site_y_m, kSearchM, [&](std::size_t k, double d) {
      if (truth.hazard[k] != 0) nearest = std::min(nearest, d);
    });
    r.site_clearance_m = nearest;
    r.site_on_hazard = nearest <= o.footprint_radius_m;
  }
  return r;
}

}  // namespace swf::sil
