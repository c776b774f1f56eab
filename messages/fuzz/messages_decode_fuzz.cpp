// Fuzz entry point for the checked decoder (swf/messages/checked_decode.hpp): the same bytes go to
// every message type (each checks its fingerprint first). No input may crash, throw or allocate
// past a stated limit; a message that decodes has the sizes its length fields state, and
// re-encodes to the very bytes it came from (health_t excepted: its strings are cut at a NUL).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "swf/messages/checked_decode.hpp"

namespace {

using swf::messages::CheckedDecode;

void Expect(bool condition) {
  if (!condition) __builtin_trap();
}

template <typename Msg>
void ExpectSameBytes(const Msg& msg, const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> again(static_cast<std::size_t>(msg.getEncodedSize()));
  Expect(again.size() == size);
  Expect(msg.encode(again.data(), 0, static_cast<int>(again.size())) == static_cast<int>(size));
  Expect(std::memcmp(again.data(), data, size) == 0);
}

// Every value within [lo, hi] (an enumeration's range).
template <typename T>
void ExpectEachWithin(const std::vector<T>& values, T lo, T hi) {
  for (const T v : values) Expect(v >= lo && v <= hi);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  swf_msgs::stereo_frame_t frame;
  if (CheckedDecode(data, size, &frame).Ok()) {
    Expect(frame.num_bytes == frame.width * frame.height);
    Expect(frame.left.size() == static_cast<std::size_t>(frame.num_bytes));
    Expect(frame.right.size() == static_cast<std::size_t>(frame.num_bytes));
    ExpectSameBytes(frame, data, size);
  }
  // A live receiver's bounded decode (drivers' LcmStereoSource): never beyond its limits.
  swf_msgs::stereo_frame_t bounded;
  if (CheckedDecode(data, size, 64, 48, &bounded).Ok()) {
    Expect(bounded.width <= 64 && bounded.height <= 48);
    Expect(bounded.left.size() == static_cast<std::size_t>(bounded.num_bytes));
  }
  swf_msgs::nav_state_t nav;
  if (CheckedDecode(data, size, &nav).Ok()) ExpectSameBytes(nav, data, size);
  swf_msgs::landmark_map_t map;
  if (CheckedDecode(data, size, &map).Ok()) {
    Expect(map.num_landmarks <= swf::messages::kMaxMapLandmarks);
    Expect(map.id.size() == static_cast<std::size_t>(map.num_landmarks));
    Expect(map.num_observations.size() == map.id.size());
    ExpectSameBytes(map, data, size);
  }
  swf_msgs::feature_set_t features;
  if (CheckedDecode(data, size, &features).Ok()) {
    Expect(features.num_features <= swf::messages::kMaxFeatures);
    Expect(features.status.size() == static_cast<std::size_t>(features.num_features));
    ExpectEachWithin(features.status, swf_msgs::feature_set_t::STATUS_TRACKED,
                     swf_msgs::feature_set_t::STATUS_GATED);
    ExpectSameBytes(features, data, size);
  }
  swf_msgs::hazard_map_t hazard;
  if (CheckedDecode(data, size, &hazard).Ok()) {
    Expect(hazard.num_cells == hazard.rows * hazard.cols);
    Expect(hazard.hazard_class.size() == static_cast<std::size_t>(hazard.num_cells));
    ExpectEachWithin(hazard.hazard_class, swf_msgs::hazard_map_t::CLASS_UNKNOWN,
                     swf_msgs::hazard_map_t::CLASS_UNCERTAIN);
    ExpectSameBytes(hazard, data, size);
  }
  swf_msgs::hazard_truth_t hazard_truth;
  if (CheckedDecode(data, size, &hazard_truth).Ok()) {
    Expect(hazard_truth.num_cells == hazard_truth.rows * hazard_truth.cols);
    Expect(hazard_truth.rock_free.size() == static_cast<std::size_t>(hazard_truth.num_cells));
    Expect(hazard_truth.num_rocks <= swf::messages::kMaxTruthRocks);
    Expect(hazard_truth.rock_height_m.size() == static_cast<std::size_t>(hazard_truth.num_rocks));
    ExpectEachWithin<std::int8_t>(hazard_truth.rock_free, 0, 1);
    ExpectSameBytes(hazard_truth, data, size);
  }
  swf_msgs::health_t health;
  if (CheckedDecode(data, size, &health).Ok()) {
    Expect(health.stage_name.size() == static_cast<std::size_t>(health.num_stages));
    Expect(health.stage_max_ms.size() == health.stage_name.size());
    Expect(health.integrity_flag_counts.size() ==
           static_cast<std::size_t>(health.num_integrity_flags));
  }
  swf_msgs::truth_state_t truth;
  if (CheckedDecode(data, size, &truth).Ok()) ExpectSameBytes(truth, data, size);
  swf_msgs::imu_t imu;
  if (CheckedDecode(data, size, &imu).Ok()) {
    Expect((imu.flags & ~swf::messages::kImuKnownFlags) == 0);
    ExpectSameBytes(imu, data, size);
  }
  return 0;
}
