// SimLcmPublisher over real UDP multicast: before anything else the process enters its own network
// namespace with only loopback and a multicast route on it (RECIPES.md), so nothing can leave the
// machine; a subscriber in this process receives what the publisher sends (ttl=0).
#include "swf/sim/lcm_publisher.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <limits>

#include "small_scene.hpp"
#include "swf/sim/trajectory.hpp"
#include "swf/testing/private_network.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

namespace swf::sim {
namespace {

// Before main(), while the process has a single thread.
const bool kIsolated = swf::testing::EnterPrivateNetwork("ip route add 239.0.0.0/8 dev lo");
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

class Inbox {
 public:
  void OnFrame(const lcm::ReceiveBuffer*, const std::string& channel,
               const swf_msgs::stereo_frame_t* m) {
    frame = *m;
    frame_channel = channel;
    ++received;
  }
  void OnTruth(const lcm::ReceiveBuffer*, const std::string&, const swf_msgs::truth_state_t* m) {
    truth = *m;
    ++received;
  }
  void OnLandmarks(const lcm::ReceiveBuffer*, const std::string&,
                   const swf_msgs::landmark_map_t* m) {
    landmarks = *m;
    ++received;
  }
  swf_msgs::stereo_frame_t frame;
  std::string frame_channel;
  swf_msgs::truth_state_t truth;
  swf_msgs::landmark_map_t landmarks;
  int received = 0;
};

TEST(SimLcmPublisherTest, SubscriberReceivesTheRenderedPairAndItsTruth) {
  ASSERT_TRUE(kIsolated) << "cannot create a private network namespace (needs root or userns)";
  // GIVEN a rendered pair of a small scene and its true pose.
  testing::SmallScene scene;
  ASSERT_NO_FATAL_FAILURE(BuildSmallScene(TerrainPreset::kCraterField, 7, 96, 72, &scene));
  estimator::Pose<double> pose;
  pose.R = NadirRotation(0.3);
  pose.t = {1.0, -2.0, 20.0};
  StereoImages images;
  ASSERT_EQ(scene.renderer.Render(scene.terrain, scene.appearance, pose, 3, &images),
            core::Status::kOk);
  const std::vector<TruthLandmark> truth_landmarks = {{5, {1.0, 2.0, -0.5}, 3},
                                                      {9, {-4.0, 0.5, 0.25}, 1}};

  // AND a subscriber on the same multicast group.
  lcm::LCM subscriber(kUrl);
  ASSERT_TRUE(subscriber.good());
  Inbox inbox;
  subscriber.subscribe("SIM_STEREO", &Inbox::OnFrame, &inbox);
  subscriber.subscribe("SIM_TRUTH", &Inbox::OnTruth, &inbox);
  subscriber.subscribe("SIM_TRUTH_LANDMARKS", &Inbox::OnLandmarks, &inbox);

  // WHEN the publisher sends frame 3 with its truth.
  SimLcmPublisher publisher;
  ASSERT_EQ(publisher.Open(kUrl, "SIM_"), core::Status::kOk);
  ASSERT_EQ(publisher.PublishFrame(images, 3, 200000), core::Status::kOk);
  ASSERT_EQ(publisher.PublishTruthPose(pose, Eigen::Vector3d(0.0, 0.0, -10.0), 19.5, 3, 200000),
            core::Status::kOk);
  ASSERT_EQ(publisher.PublishTruthLandmarks(truth_landmarks, 3, 200000), core::Status::kOk);
  EXPECT_EQ(publisher.Published(), 3);
  for (int i = 0; i < 50 && inbox.received < 3; ++i) subscriber.handleTimeout(100);

  // THEN all three arrive intact.
  ASSERT_EQ(inbox.received, 3);
  EXPECT_EQ(inbox.frame_channel, "SIM_STEREO");
  EXPECT_EQ(inbox.frame.seq, 3);
  EXPECT_EQ(inbox.frame.utime, 200000);
  EXPECT_EQ(inbox.frame.width, 96);
  EXPECT_EQ(inbox.frame.height, 72);
  EXPECT_TRUE(inbox.frame.rectified);
  EXPECT_EQ(inbox.frame.left, images.left);
  EXPECT_EQ(inbox.frame.right, images.right);
  EXPECT_EQ(inbox.truth.frame_seq, 3);
  EXPECT_EQ(inbox.truth.altitude_m, 19.5);
  const Eigen::Quaterniond q(inbox.truth.orientation_world_q[0], inbox.truth.orientation_world_q[1],
                             inbox.truth.orientation_world_q[2],
                             inbox.truth.orientation_world_q[3]);
  EXPECT_LT((q.toRotationMatrix() - pose.R).norm(), 1e-12);
  EXPECT_EQ(inbox.truth.position_world_m[2], 20.0);
  EXPECT_EQ(inbox.truth.velocity_world_mps[2], -10.0);
  ASSERT_EQ(inbox.landmarks.num_landmarks, 2);
  EXPECT_EQ(inbox.landmarks.id[1], 9);
  EXPECT_EQ(inbox.landmarks.position_world_m[0][2], -0.5);
  EXPECT_EQ(inbox.landmarks.num_observations[0], 3);
}

TEST(SimLcmPublisherTest, RefusesToPublishBeforeOpenAndBadInput) {
  SimLcmPublisher publisher;
  StereoImages images;
  EXPECT_EQ(publisher.PublishFrame(images, 0, 0), core::Status::kNotConfigured);
  ASSERT_EQ(publisher.Open("memq://"), core::Status::kOk);
  EXPECT_EQ(publisher.PublishFrame(images, 0, 0), core::Status::kInvalidArgument);
  images.width = 4;
  images.height = 2;
  images.left.assign(8, 1);
  images.right.assign(7, 1);  // inconsistent
  EXPECT_EQ(publisher.PublishFrame(images, 0, 0), core::Status::kInvalidArgument);
  estimator::Pose<double> pose;
  pose.t.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(publisher.PublishTruthPose(pose, Eigen::Vector3d::Zero(), 0.0, 0, 0),
            core::Status::kInvalidArgument);
  EXPECT_EQ(publisher.Published(), 0);
  SimLcmPublisher bad;
  EXPECT_EQ(bad.Open("nosuchprovider://x"), core::Status::kIoError);
}

}  // namespace
}  // namespace swf::sim
