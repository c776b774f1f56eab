#include "swf/evaluation/run_judge.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

#include "swf/evaluation/statistics.hpp"
#include "swf/messages/checked_decode.hpp"

namespace swf::evaluation {

namespace {

// e^T P^-1 e, NaN when P is not positive definite (an output without covariance).
double Nees(const Eigen::Vector3d& e, const double* covariance) {
  const Eigen::Matrix3d p =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(covariance);
  const Eigen::LLT<Eigen::Matrix3d> llt(p);
  if (llt.info() != Eigen::Success || !(p.trace() > 0.0)) return NAN;
  return e.dot(llt.solve(e));
}

Eigen::Matrix3d RotationOf(const double* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

// est_R^T true_R (both from w, x, y, z quaternions) as angle and rotation vector in degrees;
// NaN when either quaternion is zero.
double AttitudeErrorDeg(const double* estimate_q, const double* truth_q, double* axes_deg) {
  const Eigen::Quaterniond est(estimate_q[0], estimate_q[1], estimate_q[2], estimate_q[3]);
  const Eigen::Quaterniond truth(truth_q[0], truth_q[1], truth_q[2], truth_q[3]);
  if (!(est.norm() > 0.0) || !(truth.norm() > 0.0)) {
    std::fill(axes_deg, axes_deg + 3, NAN);
    return NAN;
  }
  const Eigen::AngleAxisd d(RotationOf(estimate_q).transpose() * RotationOf(truth_q));
  const Eigen::Vector3d phi_deg = d.axis() * (d.angle() * 180.0 / M_PI);
  std::copy(phi_deg.data(), phi_deg.data() + 3, axes_deg);
  return d.angle() * 180.0 / M_PI;
}

template <typename Message>
bool Decode(const void* data, std::size_t size, const std::string& channel, Message* m,
            std::int64_t* undecodable, std::string* first_error) {
  const messages::DecodeError e = messages::CheckedDecode(data, size, m);
  if (e.Ok()) return true;
  if ((*undecodable)++ == 0) {
    char text[160];
    messages::Describe(e, text, sizeof text);
    *first_error = channel + ": " + text;
  }
  return false;
}

}  // namespace

RunJudge::RunJudge(JudgeChannels channels) : channels_(std::move(channels)) {}

bool RunJudge::Add(const std::string& channel, const void* data, std::size_t size) {
  std::int64_t* bad = &undecodable_;
  std::string* why = &first_decode_error_;
  if (channel == channels_.nav) {
    swf_msgs::nav_state_t m;
    if (!Decode(data, size, channel, &m, bad, why)) return false;
    AddNav(m);
  } else if (channel == channels_.landmarks || channel == channels_.truth_landmarks) {
    swf_msgs::landmark_map_t m;
    if (!Decode(data, size, channel, &m, bad, why)) return false;
    if (channel == channels_.landmarks) {
      AddLandmarks(m);
    } else {
      AddTruthLandmarks(m);
    }
  } else if (channel == channels_.truth) {
    swf_msgs::truth_state_t m;
    if (!Decode(data, size, channel, &m, bad, why)) return false;
    AddTruth(m);
  } else if (channel == channels_.hazard) {
    swf_msgs::hazard_map_t m;
    if (!Decode(data, size, channel, &m, bad, why)) return false;
    AddHazard(std::move(m));
  } else if (channel == channels_.truth_hazard) {
    swf_msgs::hazard_truth_t m;
    if (!Decode(data, size, channel, &m, bad, why)) return false;
    AddTruthHazard(std::move(m));
  }
  return true;
}

void RunJudge::AddNav(const swf_msgs::nav_state_t& m) {
  Nav n{m.frame_seq,
        m.utime,
        {m.position_world_m[0], m.position_world_m[1], m.position_world_m[2]},
        {m.orientation_world_q[0], m.orientation_world_q[1], m.orientation_world_q[2],
         m.orientation_world_q[3]},
        m.status,
        m.horizontal_protection_m,
        m.vertical_protection_m,
        {},
        {}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) n.position_covariance[3 * i + j] = m.covariance[6 * i + j];
  for (int i = 0; i < 6; ++i) {
    const double variance = m.covariance[7 * i];
    n.sigma[i] = variance > 0.0 ? std::sqrt(variance) : NAN;
  }
  navs_.push_back(n);
}

void RunJudge::AddLandmarks(const swf_msgs::landmark_map_t& m) {
  Map map{m.frame_seq, m.utime, {}};
  map.landmarks.reserve(m.id.size());
  for (std::size_t i = 0; i < m.id.size(); ++i) {
    const double* p = m.position_world_m[i].data();
    Landmark l{m.id[i], {p[0], p[1], p[2]}, {}, 0};
    if (i < m.covariance_m2.size())
      std::copy(m.covariance_m2[i].begin(), m.covariance_m2[i].end(), l.covariance_m2);
    if (i < m.num_observations.size()) l.num_observations = m.num_observations[i];
    map.landmarks.push_back(l);
  }
  maps_.push_back(std::move(map));
}

void RunJudge::AddTruth(const swf_msgs::truth_state_t& m) {
  truth_[m.frame_seq] = Truth{{m.position_world_m[0], m.position_world_m[1], m.position_world_m[2]},
                              {m.orientation_world_q[0], m.orientation_world_q[1],
                               m.orientation_world_q[2], m.orientation_world_q[3]},
                              m.altitude_m};
}

void RunJudge::AddTruthLandmarks(const swf_msgs::landmark_map_t& m) {
  std::map<std::int64_t, Landmark>& truth = truth_maps_[m.frame_seq];
  for (std::size_t i = 0; i < m.id.size(); ++i) {
    const double* p = m.position_world_m[i].data();
    truth[m.id[i]] = Landmark{m.id[i], {p[0], p[1], p[2]}, {}, 0};
  }
}

void RunJudge::AddHazard(swf_msgs::hazard_map_t m) {
  const auto truth = hazard_truth_waiting_.find(m.frame_seq);
  if (truth == hazard_truth_waiting_.end()) {
    hazard_waiting_[m.frame_seq] = std::move(m);
    return;
  }
  JudgeHazard(m, truth->second);
  hazard_truth_waiting_.erase(truth);
}

void RunJudge::AddTruthHazard(swf_msgs::hazard_truth_t m) {
  const auto map = hazard_waiting_.find(m.frame_seq);
  if (map == hazard_waiting_.end()) {
    hazard_truth_waiting_[m.frame_seq] = std::move(m);
    return;
  }
  JudgeHazard(map->second, m);
  hazard_waiting_.erase(map);
}

void RunJudge::JudgeHazard(const swf_msgs::hazard_map_t& map,
                           const swf_msgs::hazard_truth_t& truth) {
  const HazardMapView view = ViewOf(map);
  if (!SameGrid(view, truth)) {
    ++hazard_truth_mismatched_;
    return;
  }
  hazard_judged_.push_back(JudgedHazard{map.frame_seq, JudgeHazardMap(view, truth, false)});
}

RunScore RunJudge::Score() const {
  RunScore score;
  score.undecodable = undecodable_;
  score.first_decode_error = first_decode_error_;
  std::vector<double> pose_errors;
  double nees_sum = 0.0;
  int nees_count = 0;
  for (const Nav& n : navs_) {
    const auto found = truth_.find(n.frame_seq);
    if (found == truth_.end()) {
      ++score.navs_without_truth;
      continue;
    }
    const Truth& truth = found->second;
    const Eigen::Vector3d estimate(n.p[0], n.p[1], n.p[2]);
    const Eigen::Vector3d t(truth.p[0], truth.p[1], truth.p[2]);
    OutputScore o;
    o.frame_seq = n.frame_seq;
    o.utime = n.utime;
    std::copy(n.p, n.p + 3, o.estimate_m);
    std::copy(truth.p, truth.p + 3, o.truth_m);
    o.error_m = (estimate - t).norm();
    o.altitude_m = truth.altitude_m;
    o.horizontal_error_m = std::hypot(n.p[0] - t.x(), n.p[1] - t.y());
    o.vertical_error_m = std::abs(n.p[2] - t.z());
    o.attitude_error_deg = AttitudeErrorDeg(n.q, truth.q, o.attitude_error_axes_deg);
    for (int i = 0; i < 3; ++i) {
      o.position_sigma_m[i] = n.sigma[i];
      o.attitude_sigma_deg[i] = n.sigma[3 + i] * 180.0 / M_PI;
    }
    o.status = n.status;
    o.hpl_m = n.hpl_m;
    o.vpl_m = n.vpl_m;
    o.position_nees = Nees(estimate - t, n.position_covariance);
    if (std::isfinite(o.position_nees)) {
      nees_sum += o.position_nees;
      ++nees_count;
    }
    if (n.status == swf_msgs::nav_state_t::STATUS_VALID) {
      const double ratio = std::max(n.hpl_m > 0.0 ? o.horizontal_error_m / n.hpl_m : 1e9,
                                    n.vpl_m > 0.0 ? o.vertical_error_m / n.vpl_m : 1e9);
      ++score.valid_navs;
      score.protection_violations += ratio > 1.0 ? 1 : 0;
      score.max_error_over_protection =
          std::max(score.max_error_over_protection, std::min(ratio, 1e9));
    }
    pose_errors.push_back(o.error_m);
    score.final_pose_error_m = o.error_m;
    score.final_attitude_error_deg = o.attitude_error_deg;
    score.outputs.push_back(o);
  }
  score.pose_rms_error_m = Rms(pose_errors);
  score.mean_position_nees = nees_count > 0 ? nees_sum / nees_count : NAN;

  std::vector<double> errors;
  for (const Map& m : maps_) {
    const auto found = truth_maps_.find(m.frame_seq);
    if (found == truth_maps_.end()) {
      ++score.maps_without_truth;
      continue;
    }
    errors.clear();
    score.last_map.clear();
    for (const Landmark& l : m.landmarks) {
      const auto truth = found->second.find(l.id);
      if (truth == found->second.end()) continue;
      LandmarkScore s;
      s.id = l.id;
      std::copy(l.p, l.p + 3, s.estimate_m);
      std::copy(truth->second.p, truth->second.p + 3, s.truth_m);
      const Eigen::Vector3d e = Eigen::Vector3d(l.p[0], l.p[1], l.p[2]) -
                                Eigen::Vector3d(s.truth_m[0], s.truth_m[1], s.truth_m[2]);
      s.error_m = e.norm();
      std::copy(l.covariance_m2, l.covariance_m2 + 6, s.covariance_m2);
      s.num_observations = l.num_observations;
      const double* c = l.covariance_m2;
      const double full[9] = {c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5]};
      s.nees = Nees(e, full);
      errors.push_back(s.error_m);
      score.last_map.push_back(s);
    }
    score.maps.push_back(MapScore{m.frame_seq, m.utime, static_cast<std::int64_t>(errors.size()),
                                  Rms(errors), Quantile(errors, 0.5)});
  }

  for (const JudgedHazard& h : hazard_judged_) {
    const auto truth = truth_.find(h.frame_seq);
    score.hazard_maps.push_back(
        HazardScore{h.frame_seq, truth == truth_.end() ? NAN : truth->second.altitude_m, h.map});
  }
  score.hazard_maps_without_truth = static_cast<std::int64_t>(hazard_waiting_.size());
  score.hazard_truth_mismatched = hazard_truth_mismatched_;
  return score;
}

}  // namespace swf::evaluation
