// lcmlog_dump LOG: every record of an LCM log as one JSON object per line, read by LCM's own log
// reader (lcm::LogFile) and decoded by the lcm-gen C++ types, the independent side that
// lcmlog_test.py holds swf_lcmlog (Python) against. The fields of each type are listed by hand,
// in schema order, so that a field the Python side reads and this one does not (or the reverse)
// shows as a difference. JSON conventions shared with swf_lcmlog.to_json: non-finite floats are
// the strings "NaN", "Infinity", "-Infinity"; byte arrays are arrays of integers; booleans are
// true/false. Exit 1 on a record that does not decode (naming it), 2 on usage.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

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

// Keys in schema order, as the Python side lists them.
using json = nlohmann::ordered_json;

json V(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  return v;
}
json V(float v) { return V(static_cast<double>(v)); }
json V(std::int8_t v) { return static_cast<int>(v); }
json V(std::uint8_t v) { return static_cast<int>(v); }
json V(std::int32_t v) { return v; }
json V(std::int64_t v) { return v; }
json V(const std::string& v) { return v; }
template <typename T>
json V(const std::vector<T>& values) {
  json out = json::array();
  for (const T& v : values) out.push_back(V(v));
  return out;
}
template <typename T, std::size_t N>
json V(const T (&values)[N]) {
  json out = json::array();
  for (const T& v : values) out.push_back(V(v));
  return out;
}
// LCM's C++ booleans are int8_t: said explicitly, as Python decodes them to bool.
json Bool(std::int8_t v) { return v != 0; }

json Fields(const swf_msgs::stereo_frame_t& m) {
  return {{"utime", V(m.utime)},
          {"seq", V(m.seq)},
          {"left_exposure_utime", V(m.left_exposure_utime)},
          {"right_exposure_utime", V(m.right_exposure_utime)},
          {"dropped_before", V(m.dropped_before)},
          {"rectified", Bool(m.rectified)},
          {"has_motion", Bool(m.has_motion)},
          {"motion_translation_m", V(m.motion_translation_m)},
          {"motion_rotation_rad", V(m.motion_rotation_rad)},
          {"width", V(m.width)},
          {"height", V(m.height)},
          {"num_bytes", V(m.num_bytes)},
          {"left", V(m.left)},
          {"right", V(m.right)}};
}

json Fields(const swf_msgs::nav_state_t& m) {
  return {{"utime", V(m.utime)},
          {"seq", V(m.seq)},
          {"frame_seq", V(m.frame_seq)},
          {"position_world_m", V(m.position_world_m)},
          {"orientation_world_q", V(m.orientation_world_q)},
          {"velocity_world_mps", V(m.velocity_world_mps)},
          {"covariance", V(m.covariance)},
          {"mode", V(m.mode)},
          {"status", V(m.status)},
          {"integrity_flags", V(m.integrity_flags)},
          {"horizontal_protection_m", V(m.horizontal_protection_m)},
          {"vertical_protection_m", V(m.vertical_protection_m)},
          {"integrity_risk", V(m.integrity_risk)},
          {"update_status", V(m.update_status)},
          {"fault_bits", V(m.fault_bits)},
          {"iterations", V(m.iterations)},
          {"num_measurements", V(m.num_measurements)}};
}

json Fields(const swf_msgs::landmark_map_t& m) {
  return {{"utime", V(m.utime)},
          {"seq", V(m.seq)},
          {"frame_seq", V(m.frame_seq)},
          {"num_landmarks", V(m.num_landmarks)},
          {"id", V(m.id)},
          {"position_world_m", V(m.position_world_m)},
          {"covariance_m2", V(m.covariance_m2)},
          {"num_observations", V(m.num_observations)}};
}

json Fields(const swf_msgs::hazard_map_t& m) {
  return {{"utime", V(m.utime)},
          {"seq", V(m.seq)},
          {"frame_seq", V(m.frame_seq)},
          {"origin_world_m", V(m.origin_world_m)},
          {"up_world", V(m.up_world)},
          {"cell_size_m", V(m.cell_size_m)},
          {"rows", V(m.rows)},
          {"cols", V(m.cols)},
          {"num_cells", V(m.num_cells)},
          {"elevation_m", V(m.elevation_m)},
          {"sigma_m", V(m.sigma_m)},
          {"relief_sigma_m", V(m.relief_sigma_m)},
          {"slope_deg", V(m.slope_deg)},
          {"roughness_m", V(m.roughness_m)},
          {"hazard_class", V(m.hazard_class)},
          {"safe_site_valid", Bool(m.safe_site_valid)},
          {"safe_site_world_m", V(m.safe_site_world_m)},
          {"safe_site_score", V(m.safe_site_score)},
          {"outliers_rejected", V(m.outliers_rejected)},
          {"cells_replaced", V(m.cells_replaced)}};
}

json Fields(const swf_msgs::hazard_truth_t& m) {
  return {{"utime", V(m.utime)},
          {"frame_seq", V(m.frame_seq)},
          {"origin_world_m", V(m.origin_world_m)},
          {"cell_size_m", V(m.cell_size_m)},
          {"rows", V(m.rows)},
          {"cols", V(m.cols)},
          {"num_cells", V(m.num_cells)},
          {"elevation_m", V(m.elevation_m)},
          {"slope_deg", V(m.slope_deg)},
          {"rock_free", V(m.rock_free)},
          {"max_rock_height_m", V(m.max_rock_height_m)},
          {"footprint_radius_m", V(m.footprint_radius_m)},
          {"num_rocks", V(m.num_rocks)},
          {"rock_center_world_m", V(m.rock_center_world_m)},
          {"rock_diameter_m", V(m.rock_diameter_m)},
          {"rock_height_m", V(m.rock_height_m)},
          {"site_valid", Bool(m.site_valid)},
          {"site_world_m", V(m.site_world_m)},
          {"site_clearance_m", V(m.site_clearance_m)},
          {"site_search_m", V(m.site_search_m)}};
}

json Fields(const swf_msgs::health_t& m) {
  return {{"utime", V(m.utime)},
          {"seq", V(m.seq)},
          {"frames", V(m.frames)},
          {"frames_dropped", V(m.frames_dropped)},
          {"frames_rejected", V(m.frames_rejected)},
          {"overruns", V(m.overruns)},
          {"outputs_dropped", V(m.outputs_dropped)},
          {"allocations_after_start", V(m.allocations_after_start)},
          {"fault_bits", V(m.fault_bits)},
          {"estimator_status", V(m.estimator_status)},
          {"num_features", V(m.num_features)},
          {"num_landmarks", V(m.num_landmarks)},
          {"frames_valid", V(m.frames_valid)},
          {"frames_degraded", V(m.frames_degraded)},
          {"frames_invalid", V(m.frames_invalid)},
          {"restarts", V(m.restarts)},
          {"last_recovery_frames", V(m.last_recovery_frames)},
          {"measurements_gated", V(m.measurements_gated)},
          {"measurements_rejected", V(m.measurements_rejected)},
          {"landmarks_rejected", V(m.landmarks_rejected)},
          {"new_landmarks_refused", V(m.new_landmarks_refused)},
          {"gate_suspensions", V(m.gate_suspensions)},
          {"num_integrity_flags", V(m.num_integrity_flags)},
          {"integrity_flag_counts", V(m.integrity_flag_counts)},
          {"num_stages", V(m.num_stages)},
          {"stage_name", V(m.stage_name)},
          {"stage_p50_ms", V(m.stage_p50_ms)},
          {"stage_p99_ms", V(m.stage_p99_ms)},
          {"stage_max_ms", V(m.stage_max_ms)},
          {"imu_accepted", V(m.imu_accepted)},
          {"imu_out_of_order", V(m.imu_out_of_order)},
          {"imu_duplicated", V(m.imu_duplicated)},
          {"imu_invalid", V(m.imu_invalid)},
          {"imu_saturated", V(m.imu_saturated)},
          {"imu_missing", V(m.imu_missing)},
          {"imu_intervals_bridged", V(m.imu_intervals_bridged)},
          {"camera_missing_packets", V(m.camera_missing_packets)},
          {"camera_pairing_failures", V(m.camera_pairing_failures)},
          {"camera_timeouts", V(m.camera_timeouts)}};
}

json Fields(const swf_msgs::imu_t& m) {
  return {{"utime", V(m.utime)},
          {"seq", V(m.seq)},
          {"angular_rate_radps", V(m.angular_rate_radps)},
          {"specific_force_mps2", V(m.specific_force_mps2)},
          {"flags", V(m.flags)}};
}

json Fields(const swf_msgs::truth_state_t& m) {
  return {{"utime", V(m.utime)},
          {"frame_seq", V(m.frame_seq)},
          {"position_world_m", V(m.position_world_m)},
          {"orientation_world_q", V(m.orientation_world_q)},
          {"velocity_world_mps", V(m.velocity_world_mps)},
          {"altitude_m", V(m.altitude_m)}};
}

json Fields(const swf_msgs::feature_set_t& m) {
  return {{"utime", V(m.utime)},
          {"seq", V(m.seq)},
          {"frame_seq", V(m.frame_seq)},
          {"num_features", V(m.num_features)},
          {"id", V(m.id)},
          {"u_px", V(m.u_px)},
          {"v_px", V(m.v_px)},
          {"status", V(m.status)}};
}

// Decodes the payload as T when its fingerprint is T's: true and `out` filled, or false when
// the fingerprint is another type's. `error` is set when it is T's but does not decode whole.
template <typename T>
bool TryDecode(const lcm::LogEvent& event, std::int64_t fingerprint, json* out,
               std::string* error) {
  if (fingerprint != T::getHash()) return false;
  T message;
  const int used = message.decode(event.data, 0, event.datalen);
  if (used != event.datalen) {
    *error = std::string("does not decode as ") + T::getTypeName() + " (" + std::to_string(used) +
             " of " + std::to_string(event.datalen) + " bytes)";
    return true;
  }
  (*out)["type"] = T::getTypeName();
  (*out)["fields"] = Fields(message);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s LOG\n", argv[0]);
    return 2;
  }
  lcm::LogFile log(argv[1], "r");
  if (!log.good()) {
    std::fprintf(stderr, "%s: cannot open\n", argv[1]);
    return 1;
  }
  long index = 0;
  for (const lcm::LogEvent* event = log.readNextEvent(); event != nullptr;
       event = log.readNextEvent(), ++index) {
    json line = {{"index", index},
                 {"eventnum", event->eventnum},
                 {"utime", event->timestamp},
                 {"channel", event->channel},
                 {"type", nullptr},
                 {"fields", nullptr}};
    std::string error;
    if (event->datalen >= 8) {
      const auto* b = static_cast<const std::uint8_t*>(event->data);
      std::uint64_t hash = 0;
      for (int i = 0; i < 8; ++i) hash = (hash << 8) | b[i];
      const auto fingerprint = static_cast<std::int64_t>(hash);
      TryDecode<swf_msgs::stereo_frame_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::nav_state_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::landmark_map_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::hazard_map_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::hazard_truth_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::health_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::imu_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::truth_state_t>(*event, fingerprint, &line, &error) ||
          TryDecode<swf_msgs::feature_set_t>(*event, fingerprint, &line, &error);
    }
    if (!error.empty()) {
      std::fprintf(stderr, "%s: record %ld (channel %s): %s\n", argv[1], index,
                   event->channel.c_str(), error.c_str());
      return 1;
    }
    std::printf("%s\n", line.dump().c_str());
  }
  return 0;
}
