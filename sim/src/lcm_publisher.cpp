#include "swf/sim/lcm_publisher.hpp"

#include <cmath>

#include <Eigen/Geometry>
#include <algorithm>
#include <lcm/lcm-cpp.hpp>

#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

namespace swf::sim {

struct SimLcmPublisher::Impl {
  std::unique_ptr<lcm::LCM> lcm;
  std::vector<std::uint8_t> buffer;
  std::string channel;
  swf_msgs::stereo_frame_t frame;
  swf_msgs::truth_state_t truth;
  swf_msgs::landmark_map_t map;
};

SimLcmPublisher::SimLcmPublisher() : impl_(std::make_unique<Impl>()) {}
SimLcmPublisher::~SimLcmPublisher() = default;

core::Status SimLcmPublisher::Open(const std::string& url, const std::string& channel_prefix) {
  impl_->lcm = std::make_unique<lcm::LCM>(url);
  if (!impl_->lcm->good()) {
    impl_->lcm.reset();
    return core::Status::kIoError;
  }
  prefix_ = channel_prefix;
  return core::Status::kOk;
}

core::Status SimLcmPublisher::Emit(const char* channel, std::int32_t size) {
  impl_->channel.assign(prefix_);
  impl_->channel.append(channel);
  if (impl_->lcm->publish(impl_->channel, impl_->buffer.data(), static_cast<unsigned>(size)) != 0) {
    return core::Status::kIoError;
  }
  ++published_;
  return core::Status::kOk;
}

core::Status SimLcmPublisher::PublishFrame(const StereoImages& images, std::int64_t seq,
                                           std::int64_t utime) {
  if (!impl_->lcm) return core::Status::kNotConfigured;
  const std::int64_t n = static_cast<std::int64_t>(images.width) * images.height;
  if (images.width <= 0 || images.height <= 0 ||
      static_cast<std::int64_t>(images.left.size()) != n ||
      static_cast<std::int64_t>(images.right.size()) != n || n > (1 << 28)) {
    return core::Status::kInvalidArgument;
  }
  swf_msgs::stereo_frame_t& m = impl_->frame;
  m.utime = utime;
  m.seq = seq;
  m.left_exposure_utime = utime;  // the simulated pair is exposed simultaneously
  m.right_exposure_utime = utime;
  m.dropped_before = 0;
  m.rectified = true;
  m.width = images.width;
  m.height = images.height;
  m.num_bytes = static_cast<std::int32_t>(n);
  m.left.assign(images.left.begin(), images.left.end());
  m.right.assign(images.right.begin(), images.right.end());
  const std::int32_t size = m.getEncodedSize();
  if (static_cast<std::int32_t>(impl_->buffer.size()) < size) impl_->buffer.resize(size);
  if (m.encode(impl_->buffer.data(), 0, size) != size) return core::Status::kInvalidArgument;
  return Emit(kSimStereoChannel, size);
}

core::Status SimLcmPublisher::PublishTruthPose(const estimator::Pose<double>& world_T_camera,
                                               const Eigen::Vector3d& velocity_world_mps,
                                               double altitude_m, std::int64_t seq,
                                               std::int64_t utime) {
  if (!impl_->lcm) return core::Status::kNotConfigured;
  if (!world_T_camera.t.allFinite() || !world_T_camera.R.allFinite() ||
      !velocity_world_mps.allFinite() || !std::isfinite(altitude_m)) {
    return core::Status::kInvalidArgument;
  }
  swf_msgs::truth_state_t& m = impl_->truth;
  m = swf_msgs::truth_state_t{};
  m.utime = utime;
  m.frame_seq = seq;
  m.altitude_m = altitude_m;
  const Eigen::Quaterniond q(world_T_camera.R);
  for (int i = 0; i < 3; ++i) {
    m.position_world_m[i] = world_T_camera.t[i];
    m.velocity_world_mps[i] = velocity_world_mps[i];
  }
  m.orientation_world_q[0] = q.w();
  m.orientation_world_q[1] = q.x();
  m.orientation_world_q[2] = q.y();
  m.orientation_world_q[3] = q.z();
  const std::int32_t size = m.getEncodedSize();
  if (static_cast<std::int32_t>(impl_->buffer.size()) < size) impl_->buffer.resize(size);
  if (m.encode(impl_->buffer.data(), 0, size) != size) return core::Status::kInvalidArgument;
  return Emit(kSimTruthChannel, size);
}

core::Status SimLcmPublisher::PublishTruthLandmarks(const std::vector<TruthLandmark>& landmarks,
                                                    std::int64_t seq, std::int64_t utime) {
  if (!impl_->lcm) return core::Status::kNotConfigured;
  swf_msgs::landmark_map_t& m = impl_->map;
  m.utime = utime;
  m.seq = landmarks_seq_++;
  m.frame_seq = seq;
  m.num_landmarks = static_cast<std::int32_t>(landmarks.size());
  m.id.resize(landmarks.size());
  m.position_world_m.resize(landmarks.size());
  m.covariance_m2.resize(landmarks.size());
  m.num_observations.resize(landmarks.size());
  for (size_t i = 0; i < landmarks.size(); ++i) {
    const TruthLandmark& l = landmarks[i];
    if (!l.position_world_m.allFinite()) return core::Status::kInvalidArgument;
    m.id[i] = l.id;
    m.position_world_m[i].assign(l.position_world_m.data(), l.position_world_m.data() + 3);
    m.covariance_m2[i].assign(6, 0.0);
    m.num_observations[i] = l.num_observations;
  }
  const std::int32_t size = m.getEncodedSize();
  if (static_cast<std::int32_t>(impl_->buffer.size()) < size) impl_->buffer.resize(size);
  if (m.encode(impl_->buffer.data(), 0, size) != size) return core::Status::kInvalidArgument;
  return Emit(kSimTruthLandmarksChannel, size);
}

}  // namespace swf::sim
