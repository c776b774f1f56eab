#include "swf/sim/prerendered_source.hpp"

#include <atomic>
#include <thread>

namespace swf::sim {

using core::Status;

Status RenderDescent(const Terrain& terrain, const Appearance& appearance, const Renderer& renderer,
                     const Trajectory& trajectory, int threads,
                     void (*progress)(int done, int total), RenderedDescent* descent) {
  const int frames = descent->NumFrames();
  const std::size_t n = static_cast<std::size_t>(descent->width_px) * descent->height_px;
  descent->left.assign(frames, std::vector<std::uint8_t>(n));
  descent->right.assign(frames, std::vector<std::uint8_t>(n));
  std::atomic<int> next{0};
  std::atomic<int> done{0};
  std::atomic<bool> failed{false};
  // Renders frame k into the descent; false (and `failed`) when the renderer refuses it.
  auto render_frame = [&](int k, StereoImages* images) {
    if (renderer.Render(terrain, appearance, trajectory.WorldTCamera(k),
                        static_cast<std::uint64_t>(k), images) != Status::kOk ||
        images->left.size() != n) {
      failed = true;
      return false;
    }
    descent->left[k] = images->left;
    descent->right[k] = images->right;
    ++done;
    return true;
  };
  auto worker = [&] {
    StereoImages images;
    for (int k = next++; k < frames; k = next++) {
      if (!render_frame(k, &images)) return;
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
  {
    StereoImages images;
    for (int k = next++; k < frames; k = next++) {
      if (!render_frame(k, &images)) break;
      if (progress != nullptr) progress(done.load(), frames);
    }
  }
  for (std::thread& t : pool) t.join();
  if (progress != nullptr) progress(done.load(), frames);
  return failed ? Status::kInvalidArgument : Status::kOk;
}

Status PrerenderedStereoSource::Start() {
  next_ = 0;
  stats_ = drivers::SourceStats{};
  running_ = true;
  return Status::kOk;
}

Status PrerenderedStereoSource::Next(core::TimeNs /*timeout_ns*/, drivers::StereoPair* pair) {
  if (!running_ || pair == nullptr) return Status::kNotConfigured;
  // Frames the camera lost reach the loop as a gap before the next pair, as a camera's do.
  const RenderedDescent& d = *descent_;
  std::uint32_t dropped = 0;
  while (next_ < d.NumFrames() && d.delivered[next_] == 0) {
    ++next_;
    ++dropped;
  }
  if (next_ >= d.NumFrames()) {
    // Lost at the very end, with no pair left to carry them: the source's own count.
    stats_.frames_dropped += dropped;
    return Status::kEmpty;
  }
  const std::int32_t w = d.width_px;
  const std::int32_t h = d.height_px;
  pair->left = core::ImageView<const std::uint8_t>{d.left[next_].data(), w, h, w};
  pair->right = core::ImageView<const std::uint8_t>{d.right[next_].data(), w, h, w};
  pair->left_exposure_ns = d.exposure_ns[next_];
  pair->right_exposure_ns = pair->left_exposure_ns;
  // The trajectory's frame number, gaps included: the outputs are matched to the truth of the
  // frame actually taken (a camera numbering only the pairs it served would shift them).
  pair->seq = static_cast<std::uint64_t>(next_);
  pair->dropped_before = dropped;
  pair->handle = next_;
  ++next_;
  ++stats_.pairs_served;
  return Status::kOk;
}

}  // namespace swf::sim
