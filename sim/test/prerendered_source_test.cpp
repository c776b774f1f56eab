// The simulated camera: a rendered descent served in order with its timing faults (lost frames as
// gaps before the next pair, trailing losses in the source's count), then kEmpty.
#include "swf/sim/prerendered_source.hpp"

#include <gtest/gtest.h>

#include "small_scene.hpp"

namespace swf::sim {
namespace {

TEST(PrerenderedStereoSourceTest, RendersADescentAndServesItWithItsTimingFaults) {
  testing::SmallScene scene;
  ASSERT_NO_FATAL_FAILURE(BuildSmallScene(TerrainPreset::kSmoothPlains, 1, 64, 48, &scene));
  const Terrain& terrain = scene.terrain;
  const Appearance& appearance = scene.appearance;
  const Renderer& renderer = scene.renderer;
  Trajectory trajectory;
  ASSERT_EQ(trajectory.Configure(HoverTrajectory(10.0, 6)), core::Status::kOk);

  // Frames 2 and 3 lost on the way, frame 5 lost at the end; frame 4 stamped 1 ms late.
  RenderedDescent descent;
  descent.width_px = 64;
  descent.height_px = 48;
  descent.delivered = {1, 1, 0, 0, 1, 0};
  for (int k = 0; k < 6; ++k) descent.exposure_ns.push_back(trajectory.FrameTimeNs(k));
  descent.exposure_ns[4] += 1'000'000;
  ASSERT_EQ(RenderDescent(terrain, appearance, renderer, trajectory, 2, nullptr, &descent),
            core::Status::kOk);
  ASSERT_EQ(descent.left.size(), 6u);
  ASSERT_EQ(descent.left[0].size(), 64u * 48u);
  StereoImages truth;
  ASSERT_EQ(renderer.Render(terrain, appearance, trajectory.WorldTCamera(4), 4, &truth),
            core::Status::kOk);
  EXPECT_EQ(descent.left[4], truth.left);  // the same pixels as rendering that frame alone
  EXPECT_EQ(descent.right[4], truth.right);

  PrerenderedStereoSource source(&descent);
  drivers::StereoPair pair;
  EXPECT_EQ(source.Next(0, &pair), core::Status::kNotConfigured);
  ASSERT_EQ(source.Start(), core::Status::kOk);
  EXPECT_STREQ(source.Name(), "sim");
  ASSERT_EQ(source.Next(0, &pair), core::Status::kOk);
  EXPECT_EQ(pair.seq, 0u);
  EXPECT_EQ(pair.dropped_before, 0u);
  EXPECT_EQ(pair.left.width, 64);
  EXPECT_EQ(pair.left.data, descent.left[0].data());
  ASSERT_EQ(source.Next(0, &pair), core::Status::kOk);
  EXPECT_EQ(pair.seq, 1u);
  ASSERT_EQ(source.Next(0, &pair), core::Status::kOk);
  EXPECT_EQ(pair.seq, 4u);  // the trajectory's frame number, over the gap
  EXPECT_EQ(pair.dropped_before, 2u);
  EXPECT_EQ(pair.left_exposure_ns, trajectory.FrameTimeNs(4) + 1'000'000);
  EXPECT_EQ(pair.right.data, descent.right[4].data());
  EXPECT_EQ(source.Next(0, &pair), core::Status::kEmpty);
  EXPECT_EQ(source.Stats().pairs_served, 3u);
  EXPECT_EQ(source.Stats().frames_dropped, 1u);  // frame 5: no pair left to carry it
  source.Stop();
  EXPECT_EQ(source.Next(0, &pair), core::Status::kNotConfigured);
}

}  // namespace
}  // namespace swf::sim
