#include "guidance_monitor.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include "swf/messages/checked_decode.hpp"

namespace swf::guidance {

GuidanceMonitor::GuidanceMonitor(lcm::LCM* lcm, const std::string& prefix, bool print)
    : print_(print) {
  lcm->subscribe(prefix + "NAV", &GuidanceMonitor::OnNav, this);
  lcm->subscribe(prefix + "LANDMARKS", &GuidanceMonitor::OnLandmarks, this);
  lcm->subscribe(prefix + "HEALTH", &GuidanceMonitor::OnHealth, this);
  lcm->subscribe(prefix + "HAZARD", &GuidanceMonitor::OnHazard, this);
}

template <typename Msg>
bool GuidanceMonitor::Receive(const lcm::ReceiveBuffer* buffer, Msg* msg, ChannelStats* stats) {
  // Checked: a hostile length field is counted here, never thrown or allocated.
  if (!messages::CheckedDecode(buffer->data, buffer->data_size, msg).Ok()) {
    ++stats->malformed;
    return false;
  }
  return Sequence(msg->seq, stats);
}

bool GuidanceMonitor::Sequence(std::int64_t seq, ChannelStats* stats) {
  // Sequence numbers count up from 0: a negative one is not a number the publisher sends.
  if (seq < 0) {
    ++stats->malformed;
    return false;
  }
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  if (stats->received > 0 && seq < stats->next_seq) {
    ++stats->out_of_order;
  } else {
    // Both are non-negative, so the gap cannot overflow; the running total saturates.
    const std::int64_t gap = seq - stats->next_seq;
    stats->lost = gap > kMax - stats->lost ? kMax : stats->lost + gap;
    stats->next_seq = seq == kMax ? kMax : seq + 1;
  }
  ++stats->received;
  return true;
}

void GuidanceMonitor::OnNav(const lcm::ReceiveBuffer* buffer, const std::string& /*channel*/) {
  swf_msgs::nav_state_t msg;
  if (!Receive(buffer, &msg, &nav_)) return;
  last_nav_ = msg;
  if (print_) {
    std::printf(
        "nav %lld frame %lld  position %.2f %.2f %.2f m  velocity %.2f %.2f %.2f m/s  "
        "sigma_z %.3f m  status %d faults %d\n",
        static_cast<long long>(msg.seq), static_cast<long long>(msg.frame_seq),
        msg.position_world_m[0], msg.position_world_m[1], msg.position_world_m[2],
        msg.velocity_world_mps[0], msg.velocity_world_mps[1], msg.velocity_world_mps[2],
        msg.covariance[14] > 0 ? std::sqrt(msg.covariance[14]) : 0.0, msg.status, msg.fault_bits);
  }
}

void GuidanceMonitor::OnLandmarks(const lcm::ReceiveBuffer* buffer,
                                  const std::string& /*channel*/) {
  swf_msgs::landmark_map_t msg;
  if (!Receive(buffer, &msg, &landmarks_)) return;
  last_map_ = msg;
  if (print_) {
    std::printf("landmarks %lld frame %lld: %d landmarks\n", static_cast<long long>(msg.seq),
                static_cast<long long>(msg.frame_seq), msg.num_landmarks);
  }
}

void GuidanceMonitor::OnHealth(const lcm::ReceiveBuffer* buffer, const std::string& /*channel*/) {
  swf_msgs::health_t msg;
  if (!Receive(buffer, &msg, &health_)) return;
  last_health_ = msg;
  if (print_) {
    std::printf("health %lld: %lld frames, %lld overruns, %lld allocations, faults %d\n",
                static_cast<long long>(msg.seq), static_cast<long long>(msg.frames),
                static_cast<long long>(msg.overruns),
                static_cast<long long>(msg.allocations_after_start), msg.fault_bits);
  }
}

void GuidanceMonitor::OnHazard(const lcm::ReceiveBuffer* buffer, const std::string& /*channel*/) {
  swf_msgs::hazard_map_t msg;
  if (!Receive(buffer, &msg, &hazard_)) return;
  int safe = 0;
  int hazards = 0;
  for (std::int8_t c : msg.hazard_class) {
    safe += c == swf_msgs::hazard_map_t::CLASS_SAFE;
    hazards += c == swf_msgs::hazard_map_t::CLASS_ROCK || c == swf_msgs::hazard_map_t::CLASS_SLOPE;
  }
  if (print_) {
    std::printf("hazard %lld frame %lld: %dx%d cells of %.3f m, %d safe, %d hazard, site %s",
                static_cast<long long>(msg.seq), static_cast<long long>(msg.frame_seq), msg.cols,
                msg.rows, msg.cell_size_m, safe, hazards, msg.safe_site_valid ? "" : "none\n");
    if (msg.safe_site_valid) {
      std::printf("%.2f %.2f m score %.3f\n", msg.safe_site_world_m[0], msg.safe_site_world_m[1],
                  msg.safe_site_score);
    }
  }
  last_hazard_ = std::move(msg);
}

}  // namespace swf::guidance
