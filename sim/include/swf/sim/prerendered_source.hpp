// The simulated camera behind the drivers' StereoSource interface. Rendering takes ~0.1-0.5 s a
// pair, far slower than a camera's rate, so a descent is rendered before start
// (RenderDescent) and served in order at the flight loop's pace, with the camera's timing faults
// drawn on it: frames lost before they reach the loop, jittered exposure stamps.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/core/time.hpp"
#include "swf/drivers/stereo_source.hpp"
#include "swf/sim/appearance.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/terrain.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sim {

// A descent's frames as the camera delivers them.
struct RenderedDescent {
  std::int32_t width_px = 0;
  std::int32_t height_px = 0;
  std::vector<std::vector<std::uint8_t>> left;  // per frame, width_px x height_px, row-major
  std::vector<std::vector<std::uint8_t>> right;
  std::vector<std::uint8_t> delivered;    // 1: frame k reaches the flight loop, 0: lost
  std::vector<core::TimeNs> exposure_ns;  // frame k's exposure stamp

  std::int32_t NumFrames() const { return static_cast<std::int32_t>(delivered.size()); }
};

// Renders frames [0, descent->NumFrames()) of `trajectory` into descent->left/right with
// `threads` threads (the calling thread is one of them and calls progress(done, total) between
// its frames). kInvalidArgument when the renderer refuses a frame.
core::Status RenderDescent(const Terrain& terrain, const Appearance& appearance,
                           const Renderer& renderer, const Trajectory& trajectory, int threads,
                           void (*progress)(int done, int total), RenderedDescent* descent);

// Serves a rendered descent's delivered frames in order; finite (kEmpty after the last). Never
// allocates. Frames not delivered are skipped and counted in the next pair's dropped_before
// (pair.seq stays the trajectory's frame number, so it jumps over them), or in Stats().
// frames_dropped when no pair follows; stamps are the descent's exposure times.
class PrerenderedStereoSource final : public drivers::StereoSource {
 public:
  explicit PrerenderedStereoSource(const RenderedDescent* descent) : descent_(descent) {}
  core::Status Start() override;
  core::Status Next(core::TimeNs timeout_ns, drivers::StereoPair* pair) override;
  void Release(const drivers::StereoPair& /*pair*/) override {}
  void Stop() override { running_ = false; }
  drivers::SourceStats Stats() const override { return stats_; }
  const char* Name() const override { return "sim"; }

 private:
  const RenderedDescent* descent_;
  std::int32_t next_ = 0;
  bool running_ = false;
  drivers::SourceStats stats_;
};

}  // namespace swf::sim
