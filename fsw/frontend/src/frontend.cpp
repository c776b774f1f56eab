#include "swf/frontend/frontend.hpp"

#include <algorithm>
#include <cmath>

namespace swf::frontend {

using core::Status;

Status Frontend::Configure(const FrontendOptions& options) {
  configured_ = false;
  if (!options.camera.Valid() || options.max_tracks == 0 || options.max_tracks > kMaxTracks ||
      options.detection_level < 0 || options.detection_level >= options.tracker.pyramid_levels) {
    return Status::kInvalidArgument;
  }
  if (Status s = harris_.Configure(options.harris); s != Status::kOk) return s;
  if (Status s = stereo_.Configure(options.stereo); s != Status::kOk) return s;
  if (Status s = tracker_.Configure(options.tracker); s != Status::kOk) return s;
  ConsistencyOptions consistency = options.consistency;
  if (!(consistency.focal_baseline_px_m > 0.0)) {
    consistency.focal_baseline_px_m = options.camera.fx * options.camera.baseline_m;
  }
  if (Status s = consistency_.Configure(consistency); s != Status::kOk) return s;
  options_ = options;
  tracks_.clear();
  num_free_ = kMaxTracks;
  for (std::size_t i = 0; i < kMaxTracks; ++i) {
    free_slots_[i] = static_cast<int>(kMaxTracks - 1 - i);
  }
  next_id_ = 1;
  has_previous_ = false;
  frame_count_ = 0;
  current_ = 0;
  width_ = 0;
  height_ = 0;
  configured_ = true;
  return Status::kOk;
}

TrackView Frontend::TrackAt(std::size_t i) const {
  const Track& t = tracks_[i];
  return TrackView{t.id, t.x, t.y, t.disparity, t.length};
}

void Frontend::ReleaseTemplate(int slot) {
  SWF_ASSERT(slot >= 0 && num_free_ < kMaxTracks);
  if (slot < 0 || num_free_ >= kMaxTracks) return;
  free_slots_[num_free_++] = slot;
}

std::size_t Frontend::FindTrack(std::uint32_t id) const {
  std::size_t lo = 0;
  std::size_t hi = tracks_.size();
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (tracks_[mid].id < id) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return (lo < tracks_.size() && tracks_[lo].id == id) ? lo : tracks_.size();
}

void Frontend::AttachEstimates(const FramePrediction& prediction) {
  for (Track& t : tracks_) t.has_estimate = false;
  if (!prediction.has_pose || prediction.landmarks == nullptr) return;
  for (std::size_t i = 0; i < prediction.num_landmarks; ++i) {
    const std::size_t k = FindTrack(prediction.landmarks[i].id);
    if (k == tracks_.size()) continue;
    tracks_[k].has_estimate = prediction.landmarks[i].p_world.allFinite();
    tracks_[k].p_world = prediction.landmarks[i].p_world;
  }
}

Eigen::Vector3d Frontend::Triangulate(float x, float y, float disparity) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  const estimator::Vec3<double> z(x, static_cast<double>(x) - disparity, y);
  (void)options_.camera.Triangulate(z, &p);
  return p;
}

float Frontend::Magnification(const Track& track, const estimator::Pose<double>& world_T_camera) {
  if (!track.has_estimate || !track.has_ref_pose) return 1.0f;
  const double depth_ref = track.world_T_ref.ApplyInverse(track.p_world).z();
  const double depth_now = world_T_camera.ApplyInverse(track.p_world).z();
  if (!(depth_ref > 1e-3 && depth_now > 1e-3)) return 1.0f;
  return static_cast<float>(depth_ref / depth_now);
}

bool Frontend::TrackOne(const Track& track, const FramePrediction& prediction, bool may_search,
                        float* x, float* y, float* disparity_guess, float* quality, bool* warped,
                        bool* searched, bool* recovered) const {
  *warped = false;
  *searched = false;
  *recovered = false;
  const GrayView left = pyramids_[current_].Level(0);
  bool has_warp = false;
  Eigen::Matrix3d h;
  float predicted_x = 0.0f;
  float predicted_y = 0.0f;
  float predicted_d = 0.0f;
  if (prediction.has_pose && track.has_estimate && track.has_ref_pose) {
    const Eigen::Vector3d p_cam = prediction.world_T_camera.ApplyInverse(track.p_world);
    const Eigen::Vector3d p_ref = track.world_T_ref.ApplyInverse(track.p_world);
    if (p_cam.z() > 1e-3 && p_ref.z() > 1e-3) {
      const Eigen::Vector3d z = options_.camera.Project(p_cam);
      const estimator::Pose<double> cur_T_ref =
          prediction.world_T_camera.Inverse() * track.world_T_ref;
      h = PlaneHomography(options_.camera, cur_T_ref, p_ref.z());
      has_warp = true;
      predicted_x = static_cast<float>(z.x());
      predicted_y = static_cast<float>(z.z());
      predicted_d = static_cast<float>(z.x() - z.y());
      float px = predicted_x;
      float py = predicted_y;
      float q = 0.0f;
      if (tracker_.TrackWarped(left, templates_[track.template_slot], h, &px, &py, &q)) {
        *x = px;
        *y = py;
        *disparity_guess = predicted_d;
        *quality = q;
        *warped = true;
        return true;
      }
    }
  }
  if (has_warp && may_search) {
    // Warped LK lost it: look for the same template around the prediction before falling back
    // to frame-to-frame LK, which re-anchors the track on the previous frame (and drifts).
    *searched = true;
    float px = predicted_x;
    float py = predicted_y;
    if (tracker_.SearchWarped(left, templates_[track.template_slot], h, &px, &py, quality)) {
      *x = px;
      *y = py;
      *disparity_guess = predicted_d;
      *warped = true;
      *recovered = true;
      return true;
    }
  }
  if (!has_previous_) return false;
  float px = track.x;
  float py = track.y;
  if (!tracker_.TrackFlow(pyramids_[1 - current_], pyramids_[current_], track.x, track.y, &px, &py,
                          quality)) {
    return false;
  }
  *x = px;
  *y = py;
  *disparity_guess = track.disparity;
  return true;
}

bool Frontend::StereoOne(const GrayView& left, const GrayView& right, float x, float y,
                         float* disparity, float* quality) const {
  const float min_zncc = options_.stereo.min_zncc;
  float d = *disparity;
  float q = 0.0f;
  if (stereo_.RefineDisparity(left, right, x, y, &d, &q) && q >= min_zncc && d > 0.0f) {
    *disparity = d;
    *quality = q;
    return true;
  }
  // The guess was too far off: search the row again from the nearest pixel.
  StereoMatch m;
  if (!stereo_.Match(left, right, static_cast<int>(std::lround(x)),
                     static_cast<int>(std::lround(y)), &m)) {
    return false;
  }
  d = m.disparity;
  if (!stereo_.RefineDisparity(left, right, x, y, &d, &q) || q < min_zncc || !(d > 0.0f)) {
    return false;
  }
  *disparity = d;
  *quality = q;
  return true;
}

Status Frontend::ProcessFrame(const StereoFrame& frame, const FramePrediction& prediction,
                              FrameOutput* output) {
  output->Clear();
  if (!configured_) return Status::kNotConfigured;
  if (Status s = LoadImages(frame); s != Status::kOk) return s;
  const GrayView left = pyramids_[current_].Level(0);
  const GrayView right = right_.View();

  FrameStats& stats = output->stats;
  stats.tracks_in = tracks_.size();
  AttachEstimates(prediction);
  // 1. Temporal tracking and stereo of every known landmark.
  const std::size_t n = TrackAndTriangulate(left, right, prediction, &stats);
  // 2. Moravec's rigid-consistency check on the previous and current stereo points.
  if (Status s = MarkConsistent(n); s != Status::kOk) return s;
  // 3. Emit measurements, drop the lost and the inconsistent.
  EmitMeasurements(output);
  // 4. New landmarks where the image is not covered.
  if (Status s = AddNewLandmarks(left, right, prediction, output); s != Status::kOk) return s;
  has_previous_ = true;
  ++frame_count_;
  return Status::kOk;
}

Status Frontend::LoadImages(const StereoFrame& frame) {
  if (!frame.left.Valid() || !frame.right.Valid() || frame.left.width != frame.right.width ||
      frame.left.height != frame.right.height || frame.left.width > kMaxImageWidth ||
      frame.left.height > kMaxImageHeight) {
    return Status::kInvalidArgument;
  }
  if (has_previous_ && (frame.left.width != width_ || frame.left.height != height_)) {
    return Status::kInvalidArgument;
  }
  width_ = frame.left.width;
  height_ = frame.left.height;
  current_ = has_previous_ ? 1 - current_ : current_;
  if (Status s = pyramids_[current_].Build(frame.left, options_.tracker.pyramid_levels);
      s != Status::kOk) {
    return s;
  }
  if (Status s = right_.Resize(width_, height_); s != Status::kOk) return s;
  right_.CopyFrom(frame.right);
  return Status::kOk;
}

std::size_t Frontend::TrackAndTriangulate(const GrayView& left, const GrayView& right,
                                          const FramePrediction& prediction, FrameStats* stats) {
  std::size_t n = 0;
  std::size_t searches = 0;
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    keep_[i] = false;
    float x = t.x;
    float y = t.y;
    float d = t.disparity;
    float q_track = 0.0f;
    bool warped = false;
    bool searched = false;
    bool recovered = false;
    const bool may_search = options_.recover_lost_tracks && searches < options_.max_recoveries;
    const bool tracked =
        TrackOne(t, prediction, may_search, &x, &y, &d, &q_track, &warped, &searched, &recovered);
    if (searched) ++searches;
    if (searched) ++stats->searched;
    if (!tracked) {
      ++stats->lost_tracking;
      continue;
    }
    float q_stereo = 0.0f;
    if (!StereoOne(left, right, x, y, &d, &q_stereo)) {
      ++stats->lost_stereo;
      continue;
    }
    if (warped) ++stats->warped;
    if (recovered) ++stats->recovered;
    recovered_[n] = recovered;
    keep_[i] = true;
    p0_[n] = t.p_camera;
    p1_[n] = Triangulate(x, y, d);
    t.x = x;
    t.y = y;
    t.disparity = d;
    t.quality = std::fmin(q_track, q_stereo);
    t.magnification = prediction.has_pose ? Magnification(t, prediction.world_T_camera) : 1.0f;
    ++n;
  }
  return n;
}

Status Frontend::MarkConsistent(std::size_t n) {
  if (options_.consistency_check && n >= options_.min_consistency_points) {
    std::size_t num_inliers = 0;
    return consistency_.Run(p0_, p1_, n, inlier_, &num_inliers);
  }
  for (std::size_t k = 0; k < n; ++k) inlier_[k] = true;
  return Status::kOk;
}

void Frontend::EmitMeasurements(FrameOutput* output) {
  FrameStats& stats = output->stats;
  // Order kept: tracks stay sorted.
  std::size_t write = 0;
  for (std::size_t i = 0, k = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    bool keep = keep_[i];
    if (keep) {
      const bool consistent = inlier_[k];
      t.p_camera = p1_[k];
      ++k;
      if (!consistent) {
        ++stats.rejected_consistency;
        if (recovered_[k - 1]) ++stats.recovered_inconsistent;
        keep = false;
      }
    }
    if (!keep) {
      (void)output->dropped.push_back(t.id);
      ReleaseTemplate(t.template_slot);
      continue;
    }
    ++t.length;
    (void)output->measurements.push_back(StereoMeasurement{
        t.id, t.x, static_cast<double>(t.x) - t.disparity, t.y, t.quality, t.magnification});
    if (write != i) tracks_[write] = t;
    ++write;
  }
  while (tracks_.size() > write) tracks_.pop_back();
}

Status Frontend::AddNewLandmarks(const GrayView& left, const GrayView& right,
                                 const FramePrediction& prediction, FrameOutput* output) {
  const int level = std::min(options_.detection_level, pyramids_[current_].NumLevels() - 1);
  const float to_level = 1.0f / static_cast<float>(1 << level);
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    occupied_[i] = Point2f{tracks_[i].x * to_level, tracks_[i].y * to_level};
  }
  if (tracks_.size() >= options_.max_tracks) return Status::kOk;
  if (Status s =
          harris_.Detect(pyramids_[current_].Level(level), occupied_, tracks_.size(), &corners_);
      s != Status::kOk && s != Status::kFull) {
    return s;
  }
  output->stats.corners = corners_.size();
  for (const Corner& c : corners_) {
    if (tracks_.size() >= options_.max_tracks || num_free_ == 0 || output->new_landmarks.full()) {
      break;
    }
    // Level-l pixel x samples full-resolution pixel (x << l) (Downsample2x is centred there).
    const int x0 = static_cast<int>(c.x) << level;
    const int y0 = static_cast<int>(c.y) << level;
    StereoMatch m;
    if (!stereo_.Match(left, right, x0, y0, &m)) continue;
    if (!(m.disparity > 0.0f)) continue;
    const int slot = free_slots_[num_free_ - 1];
    if (!tracker_.ExtractTemplate(left, m.x, m.y, &templates_[slot])) continue;
    --num_free_;
    Track t;
    t.id = next_id_++;
    t.x = m.x;
    t.y = m.y;
    t.disparity = m.disparity;
    t.quality = m.quality;
    t.length = 1;
    t.template_slot = slot;
    t.has_ref_pose = prediction.has_pose;
    t.world_T_ref = prediction.world_T_camera;
    t.ref_frame = frame_count_;
    t.p_camera = Triangulate(m.x, m.y, m.disparity);
    (void)tracks_.push_back(t);
    (void)output->new_landmarks.push_back(
        NewLandmark{t.id, m.x, static_cast<double>(m.x) - m.disparity, m.y, t.p_camera, m.quality});
    ++output->stats.new_landmarks;
  }
  return Status::kOk;
}

void Frontend::SetReferencePose(const estimator::Pose<double>& world_T_camera) {
  if (!configured_ || !options_.reference_from_estimate || !has_previous_) return;
  // New tracks are appended: those of the frame just processed are the tail.
  for (std::size_t i = tracks_.size(); i-- > 0;) {
    Track& t = tracks_[i];
    if (t.ref_frame != frame_count_ - 1) break;
    t.has_ref_pose = true;
    t.world_T_ref = world_T_camera;
  }
}

Status Frontend::Refine(const FramePrediction& updated, FrameOutput* output,
                        std::size_t* num_refined) {
  *num_refined = 0;
  if (!configured_) return Status::kNotConfigured;
  if (!has_previous_ || !updated.has_pose) return Status::kInvalidArgument;
  AttachEstimates(updated);
  const GrayView left = pyramids_[current_].Level(0);
  const GrayView right = right_.View();
  for (StereoMeasurement& m : output->measurements) {
    const std::size_t k = FindTrack(m.landmark_id);
    if (k == tracks_.size()) continue;
    Track& t = tracks_[k];
    if (!t.has_estimate || !t.has_ref_pose) continue;
    const Eigen::Vector3d p_ref = t.world_T_ref.ApplyInverse(t.p_world);
    const Eigen::Vector3d p_cam = updated.world_T_camera.ApplyInverse(t.p_world);
    if (!(p_ref.z() > 1e-3 && p_cam.z() > 1e-3)) continue;
    const Eigen::Matrix3d h = PlaneHomography(
        options_.camera, updated.world_T_camera.Inverse() * t.world_T_ref, p_ref.z());
    // Start from the current measurement: the update changes the warp, not the neighbourhood.
    float x = t.x;
    float y = t.y;
    float q_track = 0.0f;
    if (!tracker_.TrackWarped(left, templates_[t.template_slot], h, &x, &y, &q_track)) continue;
    float d = t.disparity;
    float q_stereo = 0.0f;
    if (!stereo_.RefineDisparity(left, right, x, y, &d, &q_stereo) ||
        q_stereo < options_.stereo.min_zncc || !(d > 0.0f)) {
      continue;
    }
    t.x = x;
    t.y = y;
    t.disparity = d;
    t.quality = std::fmin(q_track, q_stereo);
    t.p_camera = Triangulate(x, y, d);
    t.magnification = Magnification(t, updated.world_T_camera);
    m = StereoMeasurement{t.id, x, static_cast<double>(x) - d, y, t.quality, t.magnification};
    ++*num_refined;
  }
  return Status::kOk;
}

}  // namespace swf::frontend
