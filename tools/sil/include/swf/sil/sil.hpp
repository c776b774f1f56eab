// tools/sil: the flight process on the ground, in the loop with the simulator. It adds to the
// flight process (fsw/app) what the flight binary must not carry: the simulated descent as a
// source (terrain, renderer, trajectory, IMU unit; sim/), its configuration keys (sim.*,
// inject.black_*), the truth-derived start, and the evaluation of every published output against
// the simulator's truth. swf-sil flies it; swf-replay replays any recorded log (a log of a
// simulated descent starts from the same truth).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "swf/app/app.hpp"
#include "swf/sil/evaluation.hpp"
#include "swf/sil/sim_world.hpp"

namespace swf::sil {

// The simulator's configuration keys and checks (app::ConfigExtension).
const app::ConfigExtension* SimConfigExtension();

// The simulated descent as the flight process's extension: `source: sim` renders the descent
// before start and serves it in order; after the run the outputs are judged against its truth.
class SimulatedDescent final : public app::ProcessExtension {
 public:
  const app::ConfigExtension* Config() const override;
  bool OpenSource(const app::FswConfig& config, bool progress, app::PipelineOptions* po,
                  std::unique_ptr<drivers::StereoSource>* source, std::int64_t* total_frames,
                  std::string* error) override;
  bool Start(const app::FswConfig& config, app::PipelineOptions* po, std::string* error) override;
  estimator::StereoCamera<double> RectifiedRig(const app::FswConfig& config, int width_px,
                                               int height_px) override;
  drivers::MotionProvider* Motion() override;
  drivers::ImuProvider* Imu() override;
  void Observe(app::FlightParts* parts) override;
  void Evaluate(const app::FswConfig& config, const app::FlightParts& parts,
                const app::PipelineOptions& po, std::int64_t imu_samples_taken,
                app::Verdict* verdict, app::ImuReport* imu) override;
  std::string RunLine() const override;
  void WriteSummaryHead(std::FILE* f) const override;
  void WriteIntegrityTruth(std::FILE* f) const override;
  bool WriteHazardTruth(std::FILE* f) const override;

  // The world after OpenSource (nullptr before).
  const SimWorld* World() const { return world_.get(); }

 private:
  std::int64_t LandmarksEvaluated() const;  // in the last published map
  // The run's plots into summary.plot_dir (swf::plot); a plot that fails fails the run.
  void DrawPlots(const std::string& dir, const app::MapperHazardStage& hazard,
                 app::Verdict* verdict) const;

  const app::FswConfig* config_ = nullptr;
  std::unique_ptr<SimWorld> world_;
  Evaluation evaluation_;
  evaluation::RunScore score_;
  app::FrontendCounters frontend_{};  // the pipeline's, after the run
};

}  // namespace swf::sil
