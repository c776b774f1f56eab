#include "swf/sil/evaluation.hpp"

#include "swf/evaluation/statistics.hpp"
#include "swf/frontend/tracker.hpp"

#include <algorithm>
#include <cmath>

namespace swf::sil {

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

void Evaluation::Attach(const sim::Trajectory* trajectory, const sim::Terrain* terrain,
                        const estimator::StereoCamera<double>& camera,
                        const hazard::HazardMapperOptions& mapper, app::OutputThread* output) {
  trajectory_ = trajectory;
  terrain_ = terrain;
  camera_ = camera;
  output_ = output;
  hazard_options_.max_rock_height_m = mapper.max_rock_height_m;
  hazard_options_.footprint_radius_m = mapper.footprint_radius_m;
  sim::HazardOptions truth;
  truth.max_slope_deg = mapper.max_slope_deg;
  truth.max_rock_height_m = mapper.max_rock_height_m;
  if (sim::ComputeHazardTruth(*terrain, truth, &hazard_truth_) != core::Status::kOk)
    hazard_truth_ = sim::HazardMap{};  // no truth: maps are sent without (and not judged)
  output->AddObserver(this);
}

template <typename Message>
void Evaluation::Send(const std::string& channel, const Message& m) {
  buffer_.resize(static_cast<std::size_t>(m.getEncodedSize()));
  const int n = m.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
  if (n > 0) output_->Send(channel, m.utime, buffer_.data(), n);
}

void Evaluation::OnNav(const app::NavRecord& r) {
  for (std::int32_t k = 0; k < r.num_new_sightings; ++k)
    first_seen_.emplace(r.new_sightings[k].landmark_id, r.new_sightings[k]);
  const std::int64_t frame = r.nav.frame_seq;
  if (frame < 0 || frame >= trajectory_->NumFrames()) return;
  const estimator::Pose<double>& pose = trajectory_->WorldTCamera(static_cast<std::int32_t>(frame));
  const Eigen::Quaterniond q(pose.R);
  truth_.utime = r.nav.utime;
  truth_.frame_seq = frame;
  for (int i = 0; i < 3; ++i) {
    truth_.position_world_m[i] = pose.t[i];
    truth_.velocity_world_mps[i] = trajectory_->Options().velocity_world_mps[i];
  }
  truth_.orientation_world_q[0] = q.w();
  truth_.orientation_world_q[1] = q.x();
  truth_.orientation_world_q[2] = q.y();
  truth_.orientation_world_q[3] = q.z();
  truth_.altitude_m = pose.t.z() - terrain_->HeightAt(pose.t.x(), pose.t.y());
  Send(channels_.truth, truth_);
  if (first_frame_ < 0) first_frame_ = frame;
  ScoreTracking(r, pose);
}

void Evaluation::ScoreTracking(const app::NavRecord& r, const estimator::Pose<double>& pose) {
  for (std::int32_t k = 0; k < r.num_features; ++k) {
    const app::FeatureMark& m = r.features[k];
    if (m.fate != app::FeatureFate::kTracked && m.fate != app::FeatureFate::kNew) continue;
    Eigen::Vector3d p;
    if (!TrueLandmark(m.id, &p)) continue;
    const Eigen::Vector3d c = pose.ApplyInverse(p);
    if (!(c.z() > 0.0)) continue;
    const Eigen::Vector3d z = camera_.Project(c);
    if (m.fate == app::FeatureFate::kNew) {
      ScoreStereo(m, r.nav.frame_seq, z, 0, 1.0, pose);
      continue;
    }
    const double du = m.u_px - z.x();
    const double dv = m.v_px - z.z();
    const double e = std::hypot(du, dv);
    tracking_.all_px.push_back(e);
    tracking_.du_px.push_back(du);
    tracking_.dv_px.push_back(dv);
    const double ru = z.x() - camera_.cx;
    const double rv = z.z() - camera_.cy;
    const double r2 = ru * ru + rv * rv;
    tracking_.radial_fraction.push_back(r2 > 100.0 ? (du * ru + dv * rv) / r2 : NAN);
    const auto relief = relief_fraction_.find(m.id);
    tracking_.relief_fraction.push_back(relief != relief_fraction_.end() ? relief->second : NAN);
    app::NewSighting s;
    const bool seen = FirstSeen(m.id, &s);
    const int age = seen ? static_cast<int>(r.nav.frame_seq - s.frame_seq) : -1;
    double magnification = NAN;
    if (seen && s.frame_seq >= 0 && s.frame_seq < trajectory_->NumFrames()) {
      const double depth_then =
          trajectory_->WorldTCamera(static_cast<std::int32_t>(s.frame_seq)).ApplyInverse(p).z();
      magnification = depth_then / c.z();
    }
    tracking_.age.push_back(age);
    tracking_.magnification.push_back(magnification);
    tracking_.altitude_m.push_back(truth_.altitude_m);
    tracking_.stated_sigma_px.push_back(m.sigma_px);
    if (seen && s.frame_seq == first_frame_) {
      tracking_.first_frame_px.push_back(e);
      tracking_.first_frame_age.push_back(age);
    }
    ScoreStereo(m, r.nav.frame_seq, z, age, magnification, pose);
  }
}

void Evaluation::ScoreStereo(const app::FeatureMark& m, std::int64_t frame_seq,
                             const Eigen::Vector3d& true_z, int age, double magnification,
                             const estimator::Pose<double>& pose) {
  const double du_left = m.u_px - true_z.x();
  const double du_right = m.u_right_px - true_z.y();
  stereo_.du_left_px.push_back(du_left);
  stereo_.du_right_px.push_back(du_right);
  stereo_.dd_px.push_back(du_left - du_right);
  stereo_.true_disparity_px.push_back(true_z.x() - true_z.y());
  stereo_.age.push_back(age);
  stereo_.magnification.push_back(magnification);
  stereo_.altitude_m.push_back(truth_.altitude_m);
  stereo_.stated_sigma_px.push_back(m.sigma_px);
  stereo_.stated_sigma_disparity_px.push_back(m.sigma_disparity_px);
  stereo_.quality.push_back(m.quality);
  stereo_.left_subpixel_phase.push_back(m.u_px - std::floor(m.u_px));
  stereo_.depth_drift_fraction.push_back(DepthDriftFraction(m, age, pose));
  LastStereoError& last = last_stereo_[m.id];
  if (age > 0 && last.frame_seq == frame_seq - 1) {
    stereo_.left_then_px.push_back(last.du_left_px);
    stereo_.left_now_px.push_back(du_left);
    stereo_.disparity_then_px.push_back(last.dd_px);
    stereo_.disparity_now_px.push_back(du_left - du_right);
    stereo_.pair_age.push_back(age);
  }
  last = LastStereoError{frame_seq, du_left, du_left - du_right};
}

double Evaluation::DepthDriftFraction(const app::FeatureMark& m, int age,
                                      const estimator::Pose<double>& pose) {
  Eigen::Vector3d p_camera;
  if (!camera_.Triangulate(estimator::Vec3<double>(m.u_px, m.u_right_px, m.v_px), &p_camera)) {
    return NAN;
  }
  const Eigen::Vector3d p_world = pose.Apply(p_camera);
  if (age == 0) {
    first_stereo_point_[m.id] = p_world;
    return NAN;
  }
  const auto first = first_stereo_point_.find(m.id);
  if (first == first_stereo_point_.end()) return NAN;
  return (pose.R.transpose() * (p_world - first->second)).z() / p_camera.z();
}

bool Evaluation::FirstSeen(std::int64_t id, app::NewSighting* sighting) const {
  const auto it = first_seen_.find(id);
  if (it == first_seen_.end()) return false;
  *sighting = it->second;
  return true;
}

double Evaluation::ReliefFraction(const Eigen::Vector3d& point,
                                  const estimator::Pose<double>& pose) const {
  constexpr int kRing = 16;
  const double patch_radius_px = frontend::TrackerOptions{}.patch_radius;  // the flight's
  const double depth = pose.ApplyInverse(point).z();
  const double radius_m = patch_radius_px * depth / camera_.fx;
  double ring = 0.0;
  for (int k = 0; k < kRing; ++k) {
    const double a = 2.0 * M_PI * k / kRing;
    ring +=
        terrain_->HeightAt(point.x() + radius_m * std::cos(a), point.y() + radius_m * std::sin(a));
  }
  return (point.z() - ring / kRing) / depth;
}

bool Evaluation::TrueLandmark(std::int64_t id, Eigen::Vector3d* position) {
  const auto cached = true_landmarks_.find(id);
  if (cached != true_landmarks_.end()) {
    *position = cached->second;
    return std::isfinite(position->x());
  }
  app::NewSighting s;
  if (!FirstSeen(id, &s)) return false;
  Eigen::Vector3d value = Eigen::Vector3d::Constant(NAN);
  if (s.frame_seq >= 0 && s.frame_seq < trajectory_->NumFrames()) {
    const estimator::Pose<double>& pose =
        trajectory_->WorldTCamera(static_cast<std::int32_t>(s.frame_seq));
    const Eigen::Vector3d ray = pose.R * Eigen::Vector3d((s.u_left - camera_.cx) / camera_.fx,
                                                         (s.v - camera_.cy) / camera_.fy, 1.0);
    double t = 0.0;
    if (terrain_->Intersect(pose.t, ray, &t)) value = pose.t + t * ray;
    if (std::isfinite(value.x())) relief_fraction_[id] = ReliefFraction(value, pose);
  }
  true_landmarks_[id] = value;
  *position = value;
  return std::isfinite(value.x());
}

void Evaluation::OnMap(const app::MapRecord& r) {
  truth_map_.utime = r.map.utime;
  truth_map_.seq = r.seq;
  truth_map_.frame_seq = r.map.frame_seq;
  truth_map_.id.clear();
  truth_map_.position_world_m.clear();
  for (int i = 0; i < r.map.num_landmarks; ++i) {
    Eigen::Vector3d p;
    if (!TrueLandmark(r.map.landmarks[i].id, &p)) continue;
    truth_map_.id.push_back(r.map.landmarks[i].id);
    truth_map_.position_world_m.push_back({p.x(), p.y(), p.z()});
  }
  truth_map_.num_landmarks = static_cast<std::int32_t>(truth_map_.id.size());
  truth_map_.covariance_m2.assign(truth_map_.id.size(), std::vector<double>(6, 0.0));
  truth_map_.num_observations.assign(truth_map_.id.size(), 0);
  Send(channels_.truth_landmarks, truth_map_);
}

void Evaluation::OnHazard(const app::HazardRecord& r) {
  const std::int32_t cells = r.cells_per_side * r.cells_per_side;
  if (last_hazard_map_.capacity_cells < cells &&
      last_hazard_map_.Allocate(cells) != core::Status::kOk)
    return;
  app::HazardRecord& m = last_hazard_map_;
  m.seq = r.seq;
  m.utime = r.utime;
  m.frame_seq = r.frame_seq;
  m.origin_world_m[0] = r.origin_world_m[0];
  m.origin_world_m[1] = r.origin_world_m[1];
  m.cell_size_m = r.cell_size_m;
  m.cells_per_side = r.cells_per_side;
  std::copy_n(r.elevation_m.get(), cells, m.elevation_m.get());
  std::copy_n(r.sigma_m.get(), cells, m.sigma_m.get());
  std::copy_n(r.relief_sigma_m.get(), cells, m.relief_sigma_m.get());
  std::copy_n(r.slope_deg.get(), cells, m.slope_deg.get());
  std::copy_n(r.roughness_m.get(), cells, m.roughness_m.get());
  std::copy_n(r.hazard_class.get(), cells, m.hazard_class.get());
  m.safe_site_valid = r.safe_site_valid;
  m.safe_site_world_m[0] = r.safe_site_world_m[0];
  m.safe_site_world_m[1] = r.safe_site_world_m[1];
  m.safe_site_score = r.safe_site_score;
  m.update_ms = r.update_ms;
  if (hazard_truth_.size == 0) return;
  swf_msgs::hazard_truth_t truth = hazard_eval::HazardTruthOf(
      hazard_eval::ViewOf(r), *terrain_, terrain_->Rocks(), hazard_truth_, hazard_options_);
  truth.utime = r.utime;
  Send(channels_.truth_hazard, truth);
}

void Evaluation::OnMessage(const std::string& channel, const std::uint8_t* data, int size) {
  judge_.Add(channel, data, static_cast<std::size_t>(size));
}

plot::HeightGrid Evaluation::TerrainTruth() const {
  plot::HeightGrid grid;
  if (hazard_truth_.size != terrain_->Size()) return grid;
  grid.size = terrain_->Size();
  grid.cell_m = terrain_->CellM();
  grid.x0_m = terrain_->NodeX(0);
  grid.y0_m = terrain_->NodeY(0);
  grid.height_m = terrain_->Heights();
  grid.hazard_bits = hazard_truth_.hazard;
  return grid;
}

}  // namespace swf::sil
