#include "swf/sim/sim_stereo_source.hpp"

#include <gtest/gtest.h>

namespace swf::sim {
namespace {

TEST(SimStereoSourceTest, ServesEveryFrameWithTimestampsThenEnds) {
  TerrainOptions t = TerrainPresetOptions(TerrainPreset::kSmoothPlains, 1);
  t.size = 256;
  Terrain terrain;
  ASSERT_EQ(terrain.Configure(t), core::Status::kOk);
  Appearance appearance;
  ASSERT_EQ(appearance.Configure(terrain, AppearanceOptions{}), core::Status::kOk);
  RenderOptions r;
  r.rig.width_px = 64;
  r.rig.height_px = 48;
  Renderer renderer;
  ASSERT_EQ(renderer.Configure(r), core::Status::kOk);
  Trajectory trajectory;
  ASSERT_EQ(trajectory.Configure(HoverTrajectory(10.0, 5)), core::Status::kOk);

  SimStereoSource source;
  drivers::StereoPair pair;
  EXPECT_EQ(source.Next(0, &pair), core::Status::kNotConfigured);
  SimSourceOptions o;
  o.pool_size = 2;
  ASSERT_EQ(source.Configure(&terrain, &appearance, &renderer, &trajectory, o), core::Status::kOk);
  ASSERT_EQ(source.Start(), core::Status::kOk);
  EXPECT_STREQ(source.Name(), "sim");

  drivers::StereoPair a;
  drivers::StereoPair b;
  ASSERT_EQ(source.Next(0, &a), core::Status::kOk);
  ASSERT_EQ(source.Next(0, &b), core::Status::kOk);
  EXPECT_EQ(source.Next(0, &pair), core::Status::kFull);  // both buffers held
  EXPECT_EQ(a.seq, 0u);
  EXPECT_EQ(b.seq, 1u);
  EXPECT_EQ(b.left_exposure_ns - a.left_exposure_ns, trajectory.FrameTimeNs(1));
  EXPECT_EQ(a.left.width, 64);
  EXPECT_NE(a.handle, b.handle);
  ASSERT_NE(source.TruthImages(a.handle), nullptr);
  EXPECT_NEAR(source.TruthImages(a.handle)->depth_m[24 * 64 + 32], 10.0, 0.5);
  source.Release(a);
  EXPECT_EQ(source.TruthImages(a.handle), nullptr);
  source.Release(b);
  int served = 2;
  while (source.Next(0, &pair) == core::Status::kOk) {
    EXPECT_EQ(pair.seq, static_cast<std::uint64_t>(served));
    source.Release(pair);
    ++served;
  }
  EXPECT_EQ(served, 5);
  EXPECT_EQ(source.Next(0, &pair), core::Status::kEmpty);
  EXPECT_EQ(source.Stats().pairs_served, 5u);
  source.Stop();
}

}  // namespace
}  // namespace swf::sim
