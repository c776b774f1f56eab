// The measurement pipeline of the paper (section 4.1) for one rectified stereo frame:
//   track the known landmarks (patch warped by the landmark's plane homography when the
//   estimator supplies a predicted pose and landmark estimates; pyramidal LK otherwise)
//   -> stereo LK refinement of their disparity -> Moravec rigid-consistency between the previous
//   and current stereo points -> Harris detection in uncovered buckets -> SAD stereo + LK for new
//   landmarks. Output: (landmark id, uL, uR, v, quality) per tracked landmark and stereo
//   initialisations of new landmarks, in the rectified left camera of estimator::StereoCamera.
//
// Usage by the estimator, once per frame:
//   frontend.ProcessFrame(frame, prediction, &output);   // measurements for the SWF
//   ... SWF Gauss-Newton update ...
//   frontend.SetReferencePose(updated_pose);             // templates of this frame: estimated pose
//   frontend.Refine(updated_prediction, &output, &n);     // re-refinement (paper 4.1.2); the
//                                                        // caller replaces what the SWF holds
// Capacities: config.hpp. The object is large (images, remap-free); create it once at start.
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "swf/core/static_vector.hpp"
#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/frontend/config.hpp"
#include "swf/frontend/consistency.hpp"
#include "swf/frontend/harris.hpp"
#include "swf/frontend/image.hpp"
#include "swf/frontend/stereo_matcher.hpp"
#include "swf/frontend/tracker.hpp"

namespace swf::frontend {

// A rectified stereo pair (views stay valid for the duration of the call only).
struct StereoFrame {
  GrayView left;
  GrayView right;
};

// The estimator's current estimate of a tracked landmark.
struct LandmarkEstimate {
  std::uint32_t id = 0;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
};

// What the estimator predicts for the frame being processed. Without a pose the front end
// tracks with pyramidal LK from the previous frame.
struct FramePrediction {
  bool has_pose = false;
  estimator::Pose<double> world_T_camera;  // rectified left camera
  const LandmarkEstimate* landmarks = nullptr;
  std::size_t num_landmarks = 0;
};

struct StereoMeasurement {
  std::uint32_t landmark_id = 0;
  double u_left = 0.0;  // pixels, rectified
  double u_right = 0.0;
  double v = 0.0;
  float quality = 0.0f;  // min of tracking and stereo ZNCC, in [-1, 1]
  // How much larger the landmark's neighbourhood appears here than in the frame its template was
  // taken in: the landmark's depth there over its depth here, from the estimator's landmark and
  // poses (the scale of the template's warp; 1 without an estimate). The tracking error grows
  // with it (docs/imu.md, "Consistency along the descent").
  float magnification = 1.0f;
};

struct NewLandmark {
  std::uint32_t landmark_id = 0;
  double u_left = 0.0;
  double u_right = 0.0;
  double v = 0.0;
  Eigen::Vector3d p_camera = Eigen::Vector3d::Zero();  // stereo triangulation, metres
  float quality = 0.0f;
};

struct FrameStats {
  std::size_t tracks_in = 0;             // tracks at the start of the frame
  std::size_t lost_tracking = 0;         // temporal LK failed
  std::size_t lost_stereo = 0;           // stereo refinement failed
  std::size_t rejected_consistency = 0;  // removed by Moravec's check
  std::size_t corners = 0;               // Harris corners offered for new landmarks
  std::size_t new_landmarks = 0;
  std::size_t warped = 0;  // tracks aligned with the plane homography
  // Tracks LK lost that the search around the prediction found again (and stereo kept), and
  // how many of those Moravec's check then rejected.
  std::size_t searched = 0;
  std::size_t recovered = 0;
  std::size_t recovered_inconsistent = 0;
};

struct FrameOutput {
  core::StaticVector<StereoMeasurement, kMaxTracks> measurements;
  core::StaticVector<NewLandmark, kMaxNewLandmarks> new_landmarks;
  core::StaticVector<std::uint32_t, kMaxTracks> dropped;  // ids lost this frame
  FrameStats stats;
  void Clear() {
    measurements.clear();
    new_landmarks.clear();
    dropped.clear();
    stats = FrameStats{};
  }
};

struct FrontendOptions {
  estimator::StereoCamera<double> camera;  // the rectified rig
  HarrisOptions harris;
  StereoMatcherOptions stereo;
  TrackerOptions tracker;
  ConsistencyOptions consistency;  // focal_baseline_px_m 0: taken from `camera`
  bool consistency_check = true;
  std::size_t min_consistency_points = 8;  // fewer tracks: skip the check (nothing to vote)
  std::size_t max_tracks = 300;            // detection tops up to this many
  // Pyramid level Harris runs on (0 = full resolution). Level 1 costs a quarter (the corners only
  // seed landmarks; stereo and LK refine them at full resolution) but finds fewer corners in weak
  // texture: on EuRoC 213 instead of 297 tracks per frame (docs/benchmarks.md).
  int detection_level = 0;
  // Paper 4.1.2 warps every feature patch from the frame it was first tracked in. The reference
  // pose of a template is the estimator's updated pose of that frame (SetReferencePose), so
  // tracks started without a prediction (the first frame, a restart) are warped too once the
  // estimator has their landmark. Off: the pose predicted at first sighting, and tracks started
  // without one follow frame-to-frame LK for life.
  bool reference_from_estimate = true;
  // A track whose warped LK fails is searched for around its predicted projection
  // (PatchTracker::SearchWarped, tracker.search_radius_px) before it is given up; what the
  // search finds passes stereo and Moravec's check like any track. At most max_recoveries
  // searches per frame bound the cost.
  bool recover_lost_tracks = true;
  std::size_t max_recoveries = 64;
};

// A tracked landmark as seen by tools and tests.
struct TrackView {
  std::uint32_t id = 0;
  float x = 0.0f;
  float y = 0.0f;
  float disparity = 0.0f;
  int length = 0;  // frames observed
};

class Frontend {
 public:
  core::Status Configure(const FrontendOptions& options);

  // Processes one rectified pair (same size every frame). kInvalidArgument for bad images,
  // kNotConfigured before Configure. Never allocates.
  core::Status ProcessFrame(const StereoFrame& frame, const FramePrediction& prediction,
                            FrameOutput* output);

  // The estimator's updated pose of the frame just processed: the reference pose of the templates
  // this frame started (FrontendOptions::reference_from_estimate; a no-op when off).
  void SetReferencePose(const estimator::Pose<double>& world_T_camera);

  // Re-aligns this frame's measurements with an updated pose and landmark estimates (paper
  // 4.1.2: refine after each Gauss-Newton step): each track's template warped at the updated
  // pose and landmark, LK from its measurement, then stereo LK. Measurements whose refinement
  // fails keep their previous value. *num_refined: how many were updated.
  core::Status Refine(const FramePrediction& updated, FrameOutput* output,
                      std::size_t* num_refined);

  std::size_t NumTracks() const { return tracks_.size(); }
  TrackView TrackAt(std::size_t i) const;
  const estimator::StereoCamera<double>& Camera() const { return options_.camera; }

 private:
  struct Track {
    std::uint32_t id = 0;
    float x = 0.0f;
    float y = 0.0f;
    float disparity = 0.0f;
    float quality = 0.0f;
    int length = 0;
    int template_slot = -1;
    float magnification = 1.0f;  // of this frame's measurement (StereoMeasurement)
    bool has_ref_pose = false;
    estimator::Pose<double> world_T_ref;
    std::int64_t ref_frame = 0;  // the frame the template was taken in (frame_count_)
    Eigen::Vector3d p_camera = Eigen::Vector3d::Zero();  // last stereo triangulation
    // Per-frame scratch.
    bool has_estimate = false;
    Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  };

  // ProcessFrame's steps, in order.
  core::Status LoadImages(const StereoFrame& frame);  // checks the pair, builds the left pyramid
  // Tracks and re-triangulates every known landmark; returns how many survived (keep_, p0_, p1_).
  std::size_t TrackAndTriangulate(const GrayView& left, const GrayView& right,
                                  const FramePrediction& prediction, FrameStats* stats);
  core::Status MarkConsistent(std::size_t n);  // inlier_ of the n survivors
  void EmitMeasurements(FrameOutput* output);
  core::Status AddNewLandmarks(const GrayView& left, const GrayView& right,
                               const FramePrediction& prediction, FrameOutput* output);
  void AttachEstimates(const FramePrediction& prediction);
  // Warped tracking of one track under `prediction`; (x, y, d) in: fallback start, out: result.
  // When warped LK fails and `may_search`, the search around the prediction comes before
  // frame-to-frame LK (*searched: it ran; *recovered: it found the track).
  bool TrackOne(const Track& track, const FramePrediction& prediction, bool may_search, float* x,
                float* y, float* disparity_guess, float* quality, bool* warped, bool* searched,
                bool* recovered) const;
  bool StereoOne(const GrayView& left, const GrayView& right, float x, float y, float* disparity,
                 float* quality) const;
  Eigen::Vector3d Triangulate(float x, float y, float disparity) const;
  // StereoMeasurement::magnification of a track seen from world_T_camera.
  static float Magnification(const Track& track, const estimator::Pose<double>& world_T_camera);
  void ReleaseTemplate(int slot);
  std::size_t FindTrack(std::uint32_t id) const;  // tracks_.size() when absent

  FrontendOptions options_{};
  bool configured_ = false;
  HarrisDetector harris_;
  StereoMatcher stereo_;
  PatchTracker tracker_;
  RigidConsistency<kMaxTracks> consistency_;

  Pyramid pyramids_[2];
  Image<std::uint8_t> right_;
  int current_ = 0;
  bool has_previous_ = false;
  std::int64_t frame_count_ = 0;  // frames processed
  int width_ = 0;
  int height_ = 0;

  core::StaticVector<Track, kMaxTracks> tracks_;  // sorted by id (ids only grow)
  PatchTemplate templates_[kMaxTracks];
  int free_slots_[kMaxTracks] = {};
  std::size_t num_free_ = 0;
  std::uint32_t next_id_ = 1;

  // Per-frame scratch.
  CornerList corners_;
  Point2f occupied_[kMaxTracks];  // track positions at the detection level
  Eigen::Vector3d p0_[kMaxTracks];
  Eigen::Vector3d p1_[kMaxTracks];
  bool inlier_[kMaxTracks] = {};
  bool keep_[kMaxTracks] = {};
  bool recovered_[kMaxTracks] = {};
};

}  // namespace swf::frontend
