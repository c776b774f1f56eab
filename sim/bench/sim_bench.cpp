// bench_sim: one full-size stereo pair (1024 x 768, the paper's EDL rig) rendered on one core
// over the default crater-field terrain (2048 x 2048 nodes) textured with the orbital imagery.
// The last case renders the same rig at half resolution (512 x 384, same field of view): the
// per-pixel cost, and what size fits the 100 ms budget.
#include <benchmark/benchmark.h>

#include <string>

#include "swf/ground_cli/shared_dir.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sim {
namespace {

struct World {
  Terrain terrain;
  Appearance appearance;
  bool ok = false;
  World() {
    const std::string shared = swf::ground_cli::SharedDir();
    ok = terrain.Configure(TerrainPresetOptions(TerrainPreset::kCraterField, 1)) ==
             core::Status::kOk &&
         appearance.Configure(terrain, DefaultImagery(shared)) == core::Status::kOk;
  }
};

const World& SharedWorld() {
  static const World kWorld;
  return kWorld;
}

void BmRenderPair(benchmark::State& state) {
  const World& world = SharedWorld();
  if (!world.ok) {
    state.SkipWithError("terrain or imagery failed (set SWF_SHARED_DIR)");
    return;
  }
  RenderOptions options;
  options.samples_per_pixel = static_cast<std::int32_t>(state.range(1));
  options.rig.width_px = static_cast<std::int32_t>(state.range(2));
  options.rig.height_px = options.rig.width_px * 3 / 4;
  Renderer renderer;
  if (renderer.Configure(options) != core::Status::kOk) {
    state.SkipWithError("configure failed");
    return;
  }
  estimator::Pose<double> pose;
  pose.R = NadirRotation(0.0);
  pose.t = {3.0, -2.0, static_cast<double>(state.range(0))};
  StereoImages images;
  std::uint64_t frame = 0;
  for (auto _ : state) {
    if (renderer.Render(world.terrain, world.appearance, pose, frame++, &images) !=
        core::Status::kOk) {
      state.SkipWithError("render failed");
      return;
    }
    benchmark::DoNotOptimize(images.left.data());
  }
  state.counters["altitude_m"] = static_cast<double>(state.range(0));
}
BENCHMARK(BmRenderPair)
    ->ArgNames({"altitude_m", "spp", "width_px"})
    ->Args({100, 1, 1024})
    ->Args({50, 1, 1024})
    ->Args({10, 1, 1024})
    ->Args({50, 4, 1024})
    ->Args({50, 1, 512})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace swf::sim

BENCHMARK_MAIN();
