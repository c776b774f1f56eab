// SimLcmPublisher: puts a simulated run on LCM, as the cameras and a perfect navigator would.
//
// Channels (prefix + name, prefix empty by default):
//   STEREO           swf_msgs::stereo_frame_t, the rendered pair (rectified, 8-bit), exactly what
//                    the flight software receives from its cameras;
//   TRUTH            swf_msgs::truth_state_t, the true world_T_camera of that pair (position,
//                    quaternion w x y z), its velocity and its height above the terrain,
//                    frame_seq = the pair's seq;
//   TRUTH_LANDMARKS  swf_msgs::landmark_map_t, the true positions of the landmarks the
//                    measurement-level generator observes in that frame (id = landmark index,
//                    covariance zero, num_observations = frames that have observed it so far).
// Truth never passes for an estimate: the pose has its own type, and the landmarks' map is on a
// channel of its own (swf::evaluation::RunJudge and swf-judge read both). Messages are encoded into
// buffers owned by the publisher (grown on first use only) and published as bytes.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/sim/renderer.hpp"

namespace swf::sim {

inline constexpr const char* kSimStereoChannel = "STEREO";
inline constexpr const char* kSimTruthChannel = "TRUTH";
inline constexpr const char* kSimTruthLandmarksChannel = "TRUTH_LANDMARKS";

struct TruthLandmark {
  std::int64_t id = 0;
  Eigen::Vector3d position_world_m{0.0, 0.0, 0.0};
  std::int32_t num_observations = 0;
};

class SimLcmPublisher {
 public:
  SimLcmPublisher();
  ~SimLcmPublisher();
  SimLcmPublisher(const SimLcmPublisher&) = delete;
  SimLcmPublisher& operator=(const SimLcmPublisher&) = delete;

  // url: an LCM provider URL (udpm://239.255.76.67:7667?ttl=0, memq://, file:///x.lcmlog?mode=w).
  // kIoError when LCM cannot open it (udpm needs a multicast route: see RECIPES.md).
  core::Status Open(const std::string& url, const std::string& channel_prefix = "");

  // seq: the frame number; utime: its time stamp in microseconds. kNotConfigured before Open(),
  // kInvalidArgument for an empty or inconsistent image, kIoError when LCM refuses the message.
  core::Status PublishFrame(const StereoImages& images, std::int64_t seq, std::int64_t utime);
  core::Status PublishTruthPose(const estimator::Pose<double>& world_T_camera,
                                const Eigen::Vector3d& velocity_world_mps, double altitude_m,
                                std::int64_t seq, std::int64_t utime);
  core::Status PublishTruthLandmarks(const std::vector<TruthLandmark>& landmarks, std::int64_t seq,
                                     std::int64_t utime);

  std::int64_t Published() const { return published_; }

 private:
  struct Impl;
  core::Status Emit(const char* channel, std::int32_t size);

  std::unique_ptr<Impl> impl_;
  std::string prefix_;
  std::int64_t published_ = 0;
  std::int64_t landmarks_seq_ = 0;
};

}  // namespace swf::sim
