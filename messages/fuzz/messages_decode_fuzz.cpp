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

// When the bytes decode as Msg: the message holds what `holds` expects of it and re-encodes to
// the very bytes it came from.
template <typename Msg, typename Holds>
void IfDecoded(const std::uint8_t* data, std::size_t size, Holds holds) {
  Msg msg;
  if (!CheckedDecode(data, size, &msg).Ok()) return;
  holds(msg);
  ExpectSameBytes(msg, data, size);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  IfDecoded<swf_msgs::stereo_frame_t>(data, size, [](const swf_msgs::stereo_frame_t& m) {
    Expect(m.num_bytes == m.width * m.height);
    Expect(m.left.size() == static_cast<std::size_t>(m.num_bytes));
    Expect(m.right.size() == static_cast<std::size_t>(m.num_bytes));
  });
  // A live receiver's bounded decode (drivers' LcmStereoSource): never beyond its limits.
  swf_msgs::stereo_frame_t bounded;
  if (CheckedDecode(data, size, 64, 48, &bounded).Ok()) {
    Expect(bounded.width <= 64 && bounded.height <= 48);
    Expect(bounded.left.size() == static_cast<std::size_t>(bounded.num_bytes));
  }
  IfDecoded<swf_msgs::nav_state_t>(data, size, [](const swf_msgs::nav_state_t&) {});
  IfDecoded<swf_msgs::landmark_map_t>(data, size, [](const swf_msgs::landmark_map_t& m) {
    Expect(m.num_landmarks <= swf::messages::kMaxMapLandmarks);
    Expect(m.id.size() == static_cast<std::size_t>(m.num_landmarks));
    Expect(m.num_observations.size() == m.id.size());
  });
  IfDecoded<swf_msgs::feature_set_t>(data, size, [](const swf_msgs::feature_set_t& m) {
    Expect(m.num_features <= swf::messages::kMaxFeatures);
    Expect(m.status.size() == static_cast<std::size_t>(m.num_features));
    ExpectEachWithin(m.status, swf_msgs::feature_set_t::STATUS_TRACKED,
                     swf_msgs::feature_set_t::STATUS_GATED);
  });
  IfDecoded<swf_msgs::hazard_map_t>(data, size, [](const swf_msgs::hazard_map_t& m) {
    Expect(m.num_cells == m.rows * m.cols);
    Expect(m.hazard_class.size() == static_cast<std::size_t>(m.num_cells));
    ExpectEachWithin(m.hazard_class, swf_msgs::hazard_map_t::CLASS_UNKNOWN,
                     swf_msgs::hazard_map_t::CLASS_UNCERTAIN);
  });
  IfDecoded<swf_msgs::hazard_truth_t>(data, size, [](const swf_msgs::hazard_truth_t& m) {
    Expect(m.num_cells == m.rows * m.cols);
    Expect(m.rock_free.size() == static_cast<std::size_t>(m.num_cells));
    Expect(m.num_rocks <= swf::messages::kMaxTruthRocks);
    Expect(m.rock_height_m.size() == static_cast<std::size_t>(m.num_rocks));
    ExpectEachWithin<std::int8_t>(m.rock_free, 0, 1);
  });
  // health_t is not re-encoded: its strings are cut at a NUL.
  swf_msgs::health_t health;
  if (CheckedDecode(data, size, &health).Ok()) {
    Expect(health.stage_name.size() == static_cast<std::size_t>(health.num_stages));
    Expect(health.stage_max_ms.size() == health.stage_name.size());
    Expect(health.integrity_flag_counts.size() ==
           static_cast<std::size_t>(health.num_integrity_flags));
  }
  IfDecoded<swf_msgs::truth_state_t>(data, size, [](const swf_msgs::truth_state_t&) {});
  IfDecoded<swf_msgs::imu_t>(data, size, [](const swf_msgs::imu_t& m) {
    Expect((m.flags & ~swf::messages::kImuKnownFlags) == 0);
  });
  return 0;
}
