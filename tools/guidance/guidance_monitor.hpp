// GuidanceMonitor: the guidance side of the LCM interface. Subscribes to the flight process's
// outputs, decodes them, checks their sequence numbers (a gap = lost outputs, a repeat or step
// back = out of order) and counts, without stopping, anything on a subscribed channel that does
// not decode as that channel's type (swf/messages/checked_decode.hpp: lengths and ranges are
// checked before anything is allocated, so no message can abort or exhaust the consumer).
#pragma once

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>

#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/health_t.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"

namespace swf::guidance {

struct ChannelStats {
  std::int64_t received = 0;
  std::int64_t lost = 0;          // missing sequence numbers
  std::int64_t out_of_order = 0;  // a sequence number at or below the previous one
  std::int64_t malformed = 0;     // refused by the checked decoder: counted and ignored
  std::int64_t next_seq = 0;
};

class GuidanceMonitor {
 public:
  GuidanceMonitor(lcm::LCM* lcm, const std::string& prefix, bool print);

  const ChannelStats& Nav() const { return nav_; }
  const ChannelStats& Landmarks() const { return landmarks_; }
  const ChannelStats& Health() const { return health_; }
  const ChannelStats& Hazard() const { return hazard_; }
  const swf_msgs::nav_state_t& LastNav() const { return last_nav_; }
  const swf_msgs::landmark_map_t& LastMap() const { return last_map_; }
  const swf_msgs::health_t& LastHealth() const { return last_health_; }
  // The last hazard map that decoded (num_cells = rows * cols, classes known: the decoder checks).
  const swf_msgs::hazard_map_t& LastHazard() const { return last_hazard_; }
  std::int64_t Malformed() const {
    return nav_.malformed + landmarks_.malformed + health_.malformed + hazard_.malformed;
  }
  std::int64_t Lost() const { return nav_.lost + landmarks_.lost + health_.lost + hazard_.lost; }
  std::int64_t Received() const {
    return nav_.received + landmarks_.received + health_.received + hazard_.received;
  }

  // Raw handlers (this LCM version does not take lambdas).
  void OnNav(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void OnLandmarks(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void OnHealth(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void OnHazard(const lcm::ReceiveBuffer* buffer, const std::string& channel);

 private:
  // Decodes a message and counts its sequence number in `stats`; false (counted as malformed)
  // when it does not decode or carries a negative sequence number.
  template <typename Msg>
  static bool Receive(const lcm::ReceiveBuffer* buffer, Msg* msg, ChannelStats* stats);
  static bool Sequence(std::int64_t seq, ChannelStats* stats);

  bool print_;
  ChannelStats nav_;
  ChannelStats landmarks_;
  ChannelStats health_;
  ChannelStats hazard_;
  swf_msgs::nav_state_t last_nav_{};
  swf_msgs::landmark_map_t last_map_{};
  swf_msgs::health_t last_health_{};
  swf_msgs::hazard_map_t last_hazard_{};
};

}  // namespace swf::guidance
