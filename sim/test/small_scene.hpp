// A small rendered world for sim's tests: a 256-node terrain of a preset, its appearance and a
// renderer of the given image size.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>

#include "swf/sim/appearance.hpp"
#include "swf/sim/renderer.hpp"
#include "swf/sim/terrain.hpp"

namespace swf::sim::testing {

struct SmallScene {
  Terrain terrain;
  Appearance appearance;
  Renderer renderer;
};

// Fails the calling test (ASSERT) when a part is refused.
inline void BuildSmallScene(TerrainPreset preset, std::uint64_t seed, std::int32_t width_px,
                            std::int32_t height_px, SmallScene* scene) {
  TerrainOptions t = TerrainPresetOptions(preset, seed);
  t.size = 256;
  ASSERT_EQ(scene->terrain.Configure(t), core::Status::kOk);
  ASSERT_EQ(scene->appearance.Configure(scene->terrain, AppearanceOptions{}), core::Status::kOk);
  RenderOptions r;
  r.rig.width_px = width_px;
  r.rig.height_px = height_px;
  ASSERT_EQ(scene->renderer.Configure(r), core::Status::kOk);
}

}  // namespace swf::sim::testing
