// SimStereoSource: the simulator behind the drivers' StereoSource interface, so the flight loop
// runs on rendered pairs exactly as it runs on cameras. Each Next() renders the next trajectory
// frame into a free buffer of a fixed pool (allocated in Start()); exposure stamps are the
// trajectory's frame times; the source is finite (kEmpty after the last frame). The truth of a
// served pair (pose, depth, disparity) stays readable until the pair is released.
#pragma once

#include <cstdint>
#include <vector>

#include "swf/drivers/stereo_source.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sim {

struct SimSourceOptions {
  std::int32_t pool_size = 4;  // pairs the consumer may hold at once
};

class SimStereoSource final : public drivers::StereoSource {
 public:
  // The pointed-to objects are borrowed and must outlive the source. kInvalidArgument for a null
  // pointer or pool_size outside [1, 64].
  core::Status Configure(const Terrain* terrain, const Appearance* appearance,
                         const Renderer* renderer, const Trajectory* trajectory,
                         const SimSourceOptions& options);

  core::Status Start() override;
  // kOk with the next pair; kEmpty after the last frame; kFull when every buffer is held;
  // kNotConfigured before Configure() + Start(). Rendering is synchronous (timeout unused).
  core::Status Next(core::TimeNs timeout_ns, drivers::StereoPair* pair) override;
  void Release(const drivers::StereoPair& pair) override;
  void Stop() override;
  drivers::SourceStats Stats() const override { return stats_; }
  const char* Name() const override { return "sim"; }

  // Truth of a pair that has been served and not yet released (nullptr for a bad handle).
  const StereoImages* TruthImages(std::int32_t handle) const;
  const estimator::Pose<double>& TruePose(std::uint64_t seq) const {
    return trajectory_->WorldTCamera(static_cast<std::int32_t>(seq));
  }

 private:
  const Terrain* terrain_ = nullptr;
  const Appearance* appearance_ = nullptr;
  const Renderer* renderer_ = nullptr;
  const Trajectory* trajectory_ = nullptr;
  SimSourceOptions options_;
  std::vector<StereoImages> buffers_;
  std::vector<std::uint8_t> in_use_;
  std::int32_t next_frame_ = 0;
  bool running_ = false;
  drivers::SourceStats stats_;
};

}  // namespace swf::sim
