#include "swf/sim/sim_stereo_source.hpp"

namespace swf::sim {

core::Status SimStereoSource::Configure(const Terrain* terrain, const Appearance* appearance,
                                        const Renderer* renderer, const Trajectory* trajectory,
                                        const SimSourceOptions& options) {
  if (terrain == nullptr || appearance == nullptr || renderer == nullptr || trajectory == nullptr ||
      options.pool_size < 1 || options.pool_size > 64) {
    return core::Status::kInvalidArgument;
  }
  terrain_ = terrain;
  appearance_ = appearance;
  renderer_ = renderer;
  trajectory_ = trajectory;
  options_ = options;
  return core::Status::kOk;
}

core::Status SimStereoSource::Start() {
  if (renderer_ == nullptr) return core::Status::kNotConfigured;
  // Size every buffer now: Renderer::Render does not allocate into a buffer of the right size.
  const estimator::StereoCamera<double>& cam = renderer_->Camera();
  const auto w = static_cast<std::int32_t>(2.0 * cam.cx + 1.0 + 0.5);
  const auto h = static_cast<std::int32_t>(2.0 * cam.cy + 1.0 + 0.5);
  const size_t n = static_cast<size_t>(w) * h;
  buffers_.resize(options_.pool_size);
  for (StereoImages& b : buffers_) {
    b.width = w;
    b.height = h;
    b.left.assign(n, 0);
    b.right.assign(n, 0);
    b.depth_m.assign(n, 0.0f);
    b.disparity_px.assign(n, 0.0f);
  }
  in_use_.assign(options_.pool_size, 0);
  next_frame_ = 0;
  stats_ = drivers::SourceStats{};
  running_ = true;
  return core::Status::kOk;
}

core::Status SimStereoSource::Next(core::TimeNs /*timeout_ns*/, drivers::StereoPair* pair) {
  if (!running_ || pair == nullptr) return core::Status::kNotConfigured;
  if (next_frame_ >= trajectory_->NumFrames()) return core::Status::kEmpty;
  std::int32_t handle = -1;
  for (std::int32_t i = 0; i < static_cast<std::int32_t>(in_use_.size()); ++i) {
    if (in_use_[i] == 0) {
      handle = i;
      break;
    }
  }
  if (handle < 0) return core::Status::kFull;
  StereoImages& images = buffers_[handle];
  const core::Status s =
      renderer_->Render(*terrain_, *appearance_, trajectory_->WorldTCamera(next_frame_),
                        static_cast<std::uint64_t>(next_frame_), &images);
  if (s != core::Status::kOk) return s;
  in_use_[handle] = 1;
  const drivers::ImageView left{images.left.data(), images.width, images.height, images.width};
  const drivers::ImageView right{images.right.data(), images.width, images.height, images.width};
  pair->left = left;
  pair->right = right;
  pair->left_exposure_ns = trajectory_->FrameTimeNs(next_frame_);
  pair->right_exposure_ns = pair->left_exposure_ns;
  pair->seq = static_cast<std::uint64_t>(next_frame_);
  pair->dropped_before = 0;
  pair->handle = handle;
  ++next_frame_;
  ++stats_.pairs_served;
  return core::Status::kOk;
}

void SimStereoSource::Release(const drivers::StereoPair& pair) {
  if (pair.handle >= 0 && pair.handle < static_cast<std::int32_t>(in_use_.size())) {
    in_use_[pair.handle] = 0;
  }
}

void SimStereoSource::Stop() { running_ = false; }

const StereoImages* SimStereoSource::TruthImages(std::int32_t handle) const {
  if (handle < 0 || handle >= static_cast<std::int32_t>(in_use_.size()) || in_use_[handle] == 0) {
    return nullptr;
  }
  return &buffers_[handle];
}

}  // namespace swf::sim
