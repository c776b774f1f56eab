#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "swf/messages/checked_decode.hpp"
#include "swf/testing/encode.hpp"
#include "swf/testing/sample_messages.hpp"
#include "swf_msgs/feature_set_t.hpp"
#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/hazard_truth_t.hpp"
#include "swf_msgs/health_t.hpp"
#include "swf_msgs/imu_t.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

namespace {

using swf::testing::OneStageHealth;
using swf::testing::SafeAndRockCells;
using swf::testing::TwoLandmarks;

template <typename Msg>
Msg RoundTrip(const Msg& in, std::vector<std::uint8_t>* buffer) {
  buffer->assign(static_cast<std::size_t>(in.getEncodedSize()), 0);
  EXPECT_EQ(in.encode(buffer->data(), 0, static_cast<int>(buffer->size())),
            static_cast<int>(buffer->size()));
  Msg out;
  EXPECT_EQ(out.decode(buffer->data(), 0, static_cast<int>(buffer->size())),
            static_cast<int>(buffer->size()));
  return out;
}

// A 4 x 2 pair: left all 7, right all 9.
swf_msgs::stereo_frame_t SmallFrame() {
  swf_msgs::stereo_frame_t frame{};
  frame.seq = 3;
  frame.width = 4;
  frame.height = 2;
  frame.num_bytes = 8;
  frame.left.assign(8, 7);
  frame.right.assign(8, 9);
  return frame;
}

TEST(Messages, StereoFrameRoundTripsAndRejectsTruncation) {
  swf_msgs::stereo_frame_t frame = SmallFrame();
  frame.utime = 123456789;
  frame.seq = 42;
  frame.has_motion = true;
  frame.motion_translation_m[2] = -1.0;
  frame.motion_rotation_rad[0] = 1e-3;
  std::vector<std::uint8_t> buffer;
  const swf_msgs::stereo_frame_t out = RoundTrip(frame, &buffer);
  EXPECT_EQ(out.seq, 42);
  EXPECT_TRUE(out.has_motion);
  EXPECT_EQ(out.motion_translation_m[2], -1.0);
  EXPECT_EQ(out.motion_rotation_rad[0], 1e-3);
  EXPECT_EQ(out.right[7], 9);
  // A truncated record must fail to decode (negative), never read past the end.
  swf_msgs::stereo_frame_t broken;
  EXPECT_LT(broken.decode(buffer.data(), 0, static_cast<int>(buffer.size()) - 3), 0);
  // A wrong fingerprint (another type's bytes) is refused too.
  swf_msgs::nav_state_t nav;
  EXPECT_LT(nav.decode(buffer.data(), 0, static_cast<int>(buffer.size())), 0);
}

TEST(Messages, NavStateLandmarksHazardHealthRoundTrip) {
  std::vector<std::uint8_t> buffer;
  swf_msgs::nav_state_t nav{};
  nav.position_world_m[2] = 100.0;
  nav.covariance[35] = 1e-4;
  nav.mode = swf_msgs::nav_state_t::MODE_SWF;
  EXPECT_EQ(RoundTrip(nav, &buffer).covariance[35], 1e-4);

  swf_msgs::landmark_map_t map = TwoLandmarks();
  map.frame_seq = 17;
  EXPECT_EQ(RoundTrip(map, &buffer).position_world_m[1][2], 6.0);
  EXPECT_EQ(RoundTrip(map, &buffer).frame_seq, 17);

  swf_msgs::hazard_map_t hazard = SafeAndRockCells();
  EXPECT_EQ(RoundTrip(hazard, &buffer).hazard_class[1], swf_msgs::hazard_map_t::CLASS_ROCK);
  hazard.hazard_class[1] = swf_msgs::hazard_map_t::CLASS_UNCERTAIN;  // its own class, not safe
  EXPECT_EQ(RoundTrip(hazard, &buffer).hazard_class[1], swf_msgs::hazard_map_t::CLASS_UNCERTAIN);
  EXPECT_NE(swf_msgs::hazard_map_t::CLASS_UNCERTAIN, swf_msgs::hazard_map_t::CLASS_SAFE);

  EXPECT_EQ(RoundTrip(OneStageHealth(), &buffer).stage_name[0], "track");
}

// ---- checked decoding ------------------------------------------------------------------------
using swf::messages::CheckedDecode;
using swf::messages::DecodeError;
using swf::messages::DecodeResult;
using swf::testing::Encode;
using swf::testing::WithInt32;

template <typename Msg>
DecodeError Decode(const std::vector<std::uint8_t>& bytes) {
  Msg msg;
  return CheckedDecode(bytes.data(), bytes.size(), &msg);
}

// Every shorter prefix is refused and one byte more is refused: exactly one message fills a buffer.
template <typename Msg>
void ExpectEveryTruncationAndAnExtraByteRefused(const std::vector<std::uint8_t>& bytes) {
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    const std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<long>(n));
    EXPECT_EQ(Decode<Msg>(cut).result, DecodeResult::kTruncated) << n << " bytes";
  }
  std::vector<std::uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_EQ(Decode<Msg>(longer).result, DecodeResult::kTrailingBytes);
}

// The count at `offset` of a message holding `count` records after it: negative, huge, one more
// and one fewer than the records are each refused, naming the count or the bytes that disagree.
template <typename Msg>
void ExpectCountChecked(const std::vector<std::uint8_t>& bytes, std::size_t offset,
                        const char* field, std::int32_t count) {
  DecodeError e = Decode<Msg>(WithInt32(bytes, offset, -1));
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  EXPECT_STREQ(e.field, field);
  e = Decode<Msg>(WithInt32(bytes, offset, 1 << 30));
  EXPECT_EQ(e.result, DecodeResult::kOverLimit);
  EXPECT_STREQ(e.field, field);
  EXPECT_EQ(Decode<Msg>(WithInt32(bytes, offset, count + 1)).result, DecodeResult::kTruncated);
  EXPECT_EQ(Decode<Msg>(WithInt32(bytes, offset, count - 1)).result, DecodeResult::kTrailingBytes);
}

// Field offsets in the encoded bytes (8-byte fingerprint first; messages/*.lcm in order).
constexpr std::size_t kStereoWidth = 8 + 86;
constexpr std::size_t kStereoHeight = kStereoWidth + 4;
constexpr std::size_t kStereoNumBytes = kStereoWidth + 8;
constexpr std::size_t kNumLandmarks = 8 + 24;
constexpr std::size_t kHazardNumCells = 8 + 72 + 8;
constexpr std::size_t kHealthNumFlags = 8 + 153;
constexpr std::size_t kImuFlags = 8 + 64;  // utime, seq (2 x 8), rate, force (6 x 8)

TEST(CheckedDecode, StereoFrameLengthsAreCheckedBeforeAnyAllocation) {
  const std::vector<std::uint8_t> bytes = Encode(SmallFrame());
  swf_msgs::stereo_frame_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.right[7], 9);
  // GIVEN the length fields a flipped bit or a hostile sender makes WHEN decoded THEN each is
  // refused, naming the field (lcm-gen's decode() throws std::length_error or allocates 2 GB).
  DecodeError e = Decode<swf_msgs::stereo_frame_t>(WithInt32(bytes, kStereoNumBytes, -1));
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  EXPECT_STREQ(e.field, "num_bytes");
  EXPECT_EQ(e.value, -1);
  e = Decode<swf_msgs::stereo_frame_t>(WithInt32(bytes, kStereoNumBytes, 2147483647));
  EXPECT_EQ(e.result, DecodeResult::kOverLimit);
  EXPECT_STREQ(e.field, "num_bytes");
  e = Decode<swf_msgs::stereo_frame_t>(
      WithInt32(WithInt32(bytes, kStereoWidth, 65537), kStereoHeight, 65537));
  EXPECT_EQ(e.result, DecodeResult::kOverLimit);
  EXPECT_STREQ(e.field, "width");
  e = Decode<swf_msgs::stereo_frame_t>(WithInt32(bytes, kStereoHeight, 3));  // 4 x 3 != 8
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  EXPECT_STREQ(e.field, "num_bytes");
  // Consistent and within limits, but more bytes than the record holds.
  e = Decode<swf_msgs::stereo_frame_t>(
      WithInt32(WithInt32(bytes, kStereoHeight, 4), kStereoNumBytes, 16));
  EXPECT_EQ(e.result, DecodeResult::kTruncated);
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::stereo_frame_t>(bytes);
  char text[96];
  swf::messages::Describe(Decode<swf_msgs::stereo_frame_t>(WithInt32(bytes, kStereoNumBytes, -1)),
                          text, sizeof text);
  EXPECT_STREQ(text, "num_bytes -1: bad length");
}

TEST(CheckedDecode, StereoFrameWithinTheReceiversLimitsFitsItsReservedBuffers) {
  const std::vector<std::uint8_t> bytes = Encode(SmallFrame());  // 4 x 2
  swf_msgs::stereo_frame_t out;
  // GIVEN a receiver whose buffers hold 4 x 2 px WHEN a 4 x 2 frame arrives THEN it decodes into
  // them without reallocating.
  out.left.reserve(8);
  out.right.reserve(8);
  const std::uint8_t* left = out.left.data();
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), 4, 2, &out).Ok());
  EXPECT_EQ(out.left.data(), left);
  EXPECT_EQ(out.right[7], 9);
  // A frame wider or taller than the receiver's limits is refused before anything is filled.
  DecodeError e = CheckedDecode(bytes.data(), bytes.size(), 3, 2, &out);
  EXPECT_EQ(e.result, DecodeResult::kOverLimit);
  EXPECT_STREQ(e.field, "width");
  EXPECT_EQ(e.value, 4);
  e = CheckedDecode(bytes.data(), bytes.size(), 4, 1, &out);
  EXPECT_EQ(e.result, DecodeResult::kOverLimit);
  EXPECT_STREQ(e.field, "height");
  // Limits beyond the type's own are the type's own.
  const std::vector<std::uint8_t> huge =
      WithInt32(WithInt32(bytes, kStereoWidth, 65537), kStereoHeight, 65537);
  EXPECT_EQ(CheckedDecode(huge.data(), huge.size(), 1 << 30, 1 << 30, &out).result,
            DecodeResult::kOverLimit);
}

TEST(CheckedDecode, LandmarkMapCountIsCheckedAgainstTheBytesAndTheLimit) {
  swf_msgs::landmark_map_t map = TwoLandmarks();
  const std::vector<std::uint8_t> bytes = Encode(map);
  swf_msgs::landmark_map_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.position_world_m[1][2], 6.0);
  ExpectCountChecked<swf_msgs::landmark_map_t>(bytes, kNumLandmarks, "num_landmarks", 2);
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::landmark_map_t>(bytes);
}

TEST(CheckedDecode, FeatureSetCountAndStatusesAreChecked) {
  swf_msgs::feature_set_t set{};
  set.num_features = 2;
  set.id = {5, 6};
  set.u_px = {10.5f, 20.0f};
  set.v_px = {3.0f, 4.0f};
  set.status = {swf_msgs::feature_set_t::STATUS_TRACKED, swf_msgs::feature_set_t::STATUS_GATED};
  const std::vector<std::uint8_t> bytes = Encode(set);
  swf_msgs::feature_set_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.u_px[0], 10.5f);
  constexpr std::size_t kNumFeatures = 8 + 24;
  ExpectCountChecked<swf_msgs::feature_set_t>(bytes, kNumFeatures, "num_features", 2);
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::feature_set_t>(bytes);
  set.status[1] = 4;  // no such status
  const std::vector<std::uint8_t> unknown = Encode(set);
  const DecodeError e = CheckedDecode(unknown.data(), unknown.size(), &out);
  EXPECT_EQ(e.result, DecodeResult::kBadValue);
  EXPECT_STREQ(e.field, "status");
}

TEST(CheckedDecode, HazardMapCellsAndClassesAreChecked) {
  swf_msgs::hazard_map_t hazard = SafeAndRockCells();
  hazard.safe_site_score = 0.5;
  const std::vector<std::uint8_t> bytes = Encode(hazard);
  swf_msgs::hazard_map_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.safe_site_score, 0.5);  // the fields after the cells are where they should be
  DecodeError e = Decode<swf_msgs::hazard_map_t>(WithInt32(bytes, kHazardNumCells, -2));
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  EXPECT_STREQ(e.field, "num_cells");
  e = Decode<swf_msgs::hazard_map_t>(WithInt32(bytes, kHazardNumCells, 3));  // != 1 x 2
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  e = Decode<swf_msgs::hazard_map_t>(WithInt32(bytes, kHazardNumCells - 8, -1));
  EXPECT_STREQ(e.field, "rows");
  hazard.hazard_class[1] = 42;
  e = Decode<swf_msgs::hazard_map_t>(Encode(hazard));
  EXPECT_EQ(e.result, DecodeResult::kBadValue);
  EXPECT_EQ(e.value, 42);
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::hazard_map_t>(bytes);
}

// The fuzz corpus's health_t seed is a whole message of the current schema (regenerated with the
// schema: a seed the decoder refuses at its first check explores nothing beyond it).
TEST(CheckedDecode, TheCorpusHealthSeedIsACurrentMessage) {
  const std::string here = __FILE__;  // .../messages/test/messages_test.cpp
  const std::string corpus = here[0] == '/' ? here.substr(0, here.rfind("/test/")) + "/fuzz/corpus"
                                            : std::string("messages/fuzz/corpus");
  std::ifstream in(corpus + "/health", std::ios::binary);
  ASSERT_TRUE(in) << corpus;
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  swf_msgs::health_t health;
  const DecodeError e = CheckedDecode(bytes.data(), bytes.size(), &health);
  EXPECT_TRUE(e.Ok()) << e.field;
  EXPECT_EQ(health.camera_pairing_failures, 2);
}

TEST(CheckedDecode, HealthCountsAndStringLengthsAreChecked) {
  swf_msgs::health_t health{};
  health.frames_rejected = 4;
  health.camera_missing_packets = 3;
  health.camera_pairing_failures = 2;
  health.camera_timeouts = 1;
  health.num_integrity_flags = 2;
  health.integrity_flag_counts = {1, 2};
  health.num_stages = 2;
  health.stage_name = {"track", "estimate"};
  health.stage_p50_ms = {1.5f, 2.0f};
  health.stage_p99_ms = {2.5f, 3.0f};
  health.stage_max_ms = {3.5f, 4.0f};
  const std::vector<std::uint8_t> bytes = Encode(health);
  swf_msgs::health_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.frames_rejected, 4);
  EXPECT_EQ(out.camera_missing_packets, 3);
  EXPECT_EQ(out.camera_pairing_failures, 2);
  EXPECT_EQ(out.camera_timeouts, 1);
  EXPECT_EQ(out.stage_name[1], "estimate");
  EXPECT_EQ(out.stage_max_ms[1], 4.0f);
  EXPECT_EQ(Decode<swf_msgs::health_t>(WithInt32(bytes, kHealthNumFlags, -1)).result,
            DecodeResult::kBadLength);
  EXPECT_EQ(Decode<swf_msgs::health_t>(WithInt32(bytes, kHealthNumFlags, 33)).result,
            DecodeResult::kOverLimit);
  const std::size_t num_stages = kHealthNumFlags + 4 + 2 * 8;
  EXPECT_EQ(Decode<swf_msgs::health_t>(WithInt32(bytes, num_stages, -7)).result,
            DecodeResult::kBadLength);
  // The first name's length: 0 (lcm-gen would take -1 characters) and negative.
  DecodeError e = Decode<swf_msgs::health_t>(WithInt32(bytes, num_stages + 4, 0));
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  EXPECT_STREQ(e.field, "stage_name");
  EXPECT_EQ(Decode<swf_msgs::health_t>(WithInt32(bytes, num_stages + 4, -100)).result,
            DecodeResult::kBadLength);
  EXPECT_EQ(Decode<swf_msgs::health_t>(WithInt32(bytes, num_stages + 4, 1000)).result,
            DecodeResult::kOverLimit);
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::health_t>(bytes);
}

TEST(CheckedDecode, NavStateAndForeignBytes) {
  swf_msgs::nav_state_t nav{};
  nav.seq = 9;
  const std::vector<std::uint8_t> bytes = Encode(nav);
  swf_msgs::nav_state_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.seq, 9);
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::nav_state_t>(bytes);
  // Another type's bytes, and bytes that are no message at all.
  EXPECT_EQ(Decode<swf_msgs::nav_state_t>(Encode(SmallFrame())).result, DecodeResult::kWrongType);
  EXPECT_EQ(Decode<swf_msgs::health_t>(bytes).result, DecodeResult::kWrongType);
  const std::vector<std::uint8_t> garbage(100, 0xff);
  EXPECT_EQ(Decode<swf_msgs::landmark_map_t>(garbage).result, DecodeResult::kWrongType);
}

TEST(CheckedDecode, ImuRoundTripsAndUnknownFlagsAreRefused) {
  swf_msgs::imu_t imu{};
  imu.utime = 1403715273262142;
  imu.seq = -3;  // any counter value: the stream checker judges sequence, not the decoder
  imu.angular_rate_radps[2] = 0.25;
  imu.specific_force_mps2[0] = -9.81;
  imu.flags = std::int32_t{swf_msgs::imu_t::FLAG_VALID} |
              std::int32_t{swf_msgs::imu_t::FLAG_ACCEL_SATURATED};
  const std::vector<std::uint8_t> bytes = Encode(imu);
  EXPECT_EQ(bytes.size(), kImuFlags + 4);  // the offsets above match the schema
  swf_msgs::imu_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.utime, imu.utime);
  EXPECT_EQ(out.seq, -3);
  EXPECT_EQ(out.angular_rate_radps[2], 0.25);
  EXPECT_EQ(out.specific_force_mps2[0], -9.81);
  EXPECT_EQ(out.flags, imu.flags);
  // GIVEN a bit the schema does not define WHEN decoded THEN refused, naming the field.
  DecodeError e = Decode<swf_msgs::imu_t>(WithInt32(bytes, kImuFlags, 8));
  EXPECT_EQ(e.result, DecodeResult::kBadValue);
  EXPECT_STREQ(e.field, "flags");
  EXPECT_EQ(e.value, 8);
  EXPECT_EQ(Decode<swf_msgs::imu_t>(WithInt32(bytes, kImuFlags, -1)).result,
            DecodeResult::kBadValue);
  EXPECT_TRUE(Decode<swf_msgs::imu_t>(WithInt32(bytes, kImuFlags, 0)).Ok());  // invalid, known
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::imu_t>(bytes);
  EXPECT_EQ(Decode<swf_msgs::imu_t>(Encode(SmallFrame())).result, DecodeResult::kWrongType);
  EXPECT_EQ(Decode<swf_msgs::nav_state_t>(bytes).result, DecodeResult::kWrongType);
}

TEST(CheckedDecode, TruthStateRoundTripsAndIsNoEstimate) {
  swf_msgs::truth_state_t truth{};
  truth.utime = 200000;
  truth.frame_seq = 3;
  truth.position_world_m[2] = 100.0;
  truth.orientation_world_q[0] = 1.0;
  truth.altitude_m = 98.5;
  const std::vector<std::uint8_t> bytes = Encode(truth);
  EXPECT_EQ(bytes.size(), 8u + 2 * 8 + 11 * 8);  // fingerprint, two int64, eleven doubles
  swf_msgs::truth_state_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.frame_seq, 3);
  EXPECT_EQ(out.altitude_m, 98.5);
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::truth_state_t>(bytes);
  // Truth and estimates never pass for each other.
  EXPECT_EQ(Decode<swf_msgs::nav_state_t>(bytes).result, DecodeResult::kWrongType);
  EXPECT_EQ(Decode<swf_msgs::truth_state_t>(Encode(swf_msgs::nav_state_t{})).result,
            DecodeResult::kWrongType);
}

TEST(CheckedDecode, HazardTruthCellsRocksAndFlagsAreChecked) {
  swf_msgs::hazard_truth_t truth{};
  truth.frame_seq = 40;
  truth.rows = 2;
  truth.cols = 1;
  truth.num_cells = 2;
  truth.elevation_m = {0.5, 0.25};
  truth.slope_deg = {1.0f, 2.0f};
  truth.rock_free = {1, 0};
  truth.max_rock_height_m = 0.3;
  truth.num_rocks = 1;
  truth.rock_center_world_m = {{1.0, 2.0}};
  truth.rock_diameter_m = {0.8};
  truth.rock_height_m = {0.4};
  truth.site_valid = true;
  truth.site_clearance_m = 3.5;
  const std::vector<std::uint8_t> bytes = Encode(truth);
  swf_msgs::hazard_truth_t out;
  ASSERT_TRUE(CheckedDecode(bytes.data(), bytes.size(), &out).Ok());
  EXPECT_EQ(out.rock_center_world_m[0][1], 2.0);
  EXPECT_EQ(out.site_clearance_m, 3.5);  // the fields after the rocks are where they should be
  // utime, frame_seq (2 x 8), origin (2 x 8), cell size (8): then rows, cols, num_cells.
  constexpr std::size_t kNumCells = 8 + 40 + 8;
  // After two cells of 13 bytes and the two criteria: num_rocks.
  constexpr std::size_t kNumRocks = kNumCells + 4 + 2 * 13 + 16;
  DecodeError e = Decode<swf_msgs::hazard_truth_t>(WithInt32(bytes, kNumCells, 3));  // != 2 x 1
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  EXPECT_STREQ(e.field, "num_cells");
  e = Decode<swf_msgs::hazard_truth_t>(WithInt32(bytes, kNumRocks, -1));
  EXPECT_EQ(e.result, DecodeResult::kBadLength);
  EXPECT_STREQ(e.field, "num_rocks");
  e = Decode<swf_msgs::hazard_truth_t>(WithInt32(bytes, kNumRocks, 1 << 30));
  EXPECT_EQ(e.result, DecodeResult::kOverLimit);
  e = Decode<swf_msgs::hazard_truth_t>(WithInt32(bytes, kNumRocks, 2));
  EXPECT_EQ(e.result, DecodeResult::kTruncated);
  truth.rock_free[1] = 2;
  e = Decode<swf_msgs::hazard_truth_t>(Encode(truth));
  EXPECT_EQ(e.result, DecodeResult::kBadValue);
  EXPECT_STREQ(e.field, "rock_free");
  ExpectEveryTruncationAndAnExtraByteRefused<swf_msgs::hazard_truth_t>(bytes);
  // Truth and the estimate it judges never pass for each other.
  EXPECT_EQ(Decode<swf_msgs::hazard_map_t>(bytes).result, DecodeResult::kWrongType);
}

}  // namespace
