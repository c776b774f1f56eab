// The simulated worlds the frame-group tests fly (small rigs, 256 x 192 px), and the pipeline
// options they fly them with: the world's rectified rig, 100 tracks in 40-px buckets, disparities
// up to 64 px, a window of 5. Each test adds its own process noise and start.
#pragma once

#include <string>

#include "swf/app/config.hpp"
#include "swf/app/pipeline.hpp"
#include "swf/sil/sil.hpp"
#include "swf/sil/sim_world.hpp"

namespace swf::testing {

// The simulated run `text` configures, into *config, its world built and rendered (2 threads).
// False with *error when a step fails.
inline bool BuildSimWorld(const std::string& text, app::FswConfig* config, sil::SimWorld* world,
                          std::string* error) {
  return app::ParseConfig(text, "test", config, error, sil::SimConfigExtension()) &&
         world->Build(*config, error) && world->RenderAll(2, nullptr, error);
}

inline app::PipelineOptions SmallRigOptions(const sil::SimWorld& world) {
  app::PipelineOptions po;
  po.camera = world.Camera();
  po.width_px = world.Width();
  po.height_px = world.Height();
  po.frontend.harris.bucket_cols = po.width_px / 40;
  po.frontend.harris.bucket_rows = po.height_px / 40;
  po.frontend.max_tracks = 100;
  po.frontend.stereo.max_disparity = 64;
  po.swf.window_size = 5;
  return po;
}

}  // namespace swf::testing
