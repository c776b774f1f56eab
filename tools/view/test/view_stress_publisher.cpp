// view_stress_publisher: what swf-view must survive, as a flight process would send it and worse.
// Two flights separated by a silence (a publisher that stops and restarts: sequence numbers start
// again at 0), each a 20 Hz stream of 1024 x 768 stereo frames with a navigation output and a
// feature set per frame and a hazard map every fifth, and malformed messages mixed in (junk
// bytes, truncated frames, a hazard map with an unknown class, a feature with an unknown status,
// a negative sequence number). Prints what it sent and how long
// its publish calls took as one JSON object.
//   view_stress_publisher [--url URL] [--frames N] [--rate HZ] [--pause S] [--width W] [--height H]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "swf_msgs/feature_set_t.hpp"
#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Settings {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  int frames = 40;  // per flight
  double rate_hz = 20.0;
  double pause_s = 2.5;
  int width = 1024;
  int height = 768;
};

struct Sent {
  int frames = 0;
  int navs = 0;
  int hazards = 0;
  int malformed = 0;
  std::vector<double> publish_ms;
};

class Publisher {
 public:
  Publisher(lcm::LCM* lcm, Sent* sent) : lcm_(lcm), sent_(sent) {}

  void Bytes(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    const auto start = Clock::now();
    lcm_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    sent_->publish_ms.push_back(
        std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }

  template <typename Msg>
  std::vector<std::uint8_t> Encode(const Msg& msg) {
    std::vector<std::uint8_t> bytes(msg.getEncodedSize());
    msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    return bytes;
  }

 private:
  lcm::LCM* lcm_;
  Sent* sent_;
};

swf_msgs::stereo_frame_t Frame(const Settings& s, std::int64_t seq) {
  swf_msgs::stereo_frame_t f{};
  f.utime = seq * 50000;
  f.seq = seq;
  f.rectified = true;
  f.width = s.width;
  f.height = s.height;
  f.num_bytes = s.width * s.height;
  f.left.resize(f.num_bytes);
  f.right.resize(f.num_bytes);
  for (int i = 0; i < f.num_bytes; ++i) {
    f.left[i] = static_cast<std::uint8_t>((i % s.width + seq * 7) & 255);
    f.right[i] = f.left[i];
  }
  return f;
}

swf_msgs::nav_state_t Nav(std::int64_t seq) {
  swf_msgs::nav_state_t n{};
  n.utime = seq * 50000;
  n.seq = seq;
  n.frame_seq = seq;
  n.position_world_m[2] = 100.0 - 0.5 * static_cast<double>(seq);
  n.orientation_world_q[0] = 1.0;
  n.velocity_world_mps[2] = -10.0;
  for (int i = 0; i < 6; ++i) n.covariance[i * 7] = 1e-4;
  n.status = swf_msgs::nav_state_t::STATUS_VALID;
  n.horizontal_protection_m = 0.2;
  n.vertical_protection_m = 0.3;
  return n;
}

swf_msgs::feature_set_t Features(const Settings& s, std::int64_t seq) {
  swf_msgs::feature_set_t f{};
  f.seq = seq;
  f.frame_seq = seq;
  f.num_features = 150;
  for (int i = 0; i < f.num_features; ++i) {
    f.id.push_back(i);
    f.u_px.push_back(static_cast<float>((i * 37) % s.width));
    f.v_px.push_back(static_cast<float>((i * 53) % s.height));
    f.status.push_back(static_cast<std::int8_t>(i % 4));
  }
  return f;
}

swf_msgs::hazard_map_t Hazard(std::int64_t seq, std::int64_t frame_seq) {
  swf_msgs::hazard_map_t h{};
  h.seq = seq;
  h.frame_seq = frame_seq;
  h.cell_size_m = 0.25;
  h.up_world[2] = 1.0;
  h.rows = h.cols = 64;
  h.num_cells = 64 * 64;
  h.elevation_m.assign(h.num_cells, 0.0f);
  h.sigma_m.assign(h.num_cells, 0.05f);
  h.relief_sigma_m.assign(h.num_cells, 0.02f);
  h.slope_deg.assign(h.num_cells, 2.0f);
  h.roughness_m.assign(h.num_cells, 0.01f);
  h.hazard_class.resize(h.num_cells);
  for (int i = 0; i < h.num_cells; ++i) h.hazard_class[i] = static_cast<std::int8_t>(1 + i % 4);
  h.safe_site_valid = true;
  h.safe_site_world_m[0] = 8.0;
  h.safe_site_world_m[1] = 8.0;
  h.safe_site_score = 0.9;
  return h;
}

// One flight: frames at the rate, with the malformed messages mixed in every tenth frame.
void Fly(const Settings& s, Publisher* pub, Sent* sent) {
  const auto period = std::chrono::duration<double>(1.0 / s.rate_hz);
  const auto start = Clock::now();
  std::int64_t hazard_seq = 0;
  for (int i = 0; i < s.frames; ++i) {
    std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(period * i));
    pub->Bytes("SWF_STEREO", pub->Encode(Frame(s, i)));
    ++sent->frames;
    pub->Bytes("SWF_NAV", pub->Encode(Nav(i)));
    ++sent->navs;
    pub->Bytes("SWF_FEATURES", pub->Encode(Features(s, i)));
    if (i % 5 == 4) {
      pub->Bytes("SWF_HAZARD", pub->Encode(Hazard(hazard_seq++, i)));
      ++sent->hazards;
    }
    if (i % 10 != 9) continue;
    // Junk on the navigation channel.
    pub->Bytes("SWF_NAV", std::vector<std::uint8_t>(37, 0xA5));
    // A frame cut short (as a lost fragment would leave it, had LCM passed it on).
    std::vector<std::uint8_t> frame = pub->Encode(Frame(s, 1000 + i));
    frame.resize(frame.size() / 2);
    pub->Bytes("SWF_STEREO", frame);
    // A hazard map with a class the schema does not have.
    swf_msgs::hazard_map_t bad = Hazard(999, i);
    bad.hazard_class[17] = 42;
    pub->Bytes("SWF_HAZARD", pub->Encode(bad));
    // A navigation output with a negative sequence number.
    pub->Bytes("SWF_NAV", pub->Encode(Nav(-5)));
    // A feature set with a status the schema does not have.
    swf_msgs::feature_set_t features = Features(s, 999);
    features.status[3] = 9;
    pub->Bytes("SWF_FEATURES", pub->Encode(features));
    sent->malformed += 5;
  }
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1)))];
}

}  // namespace

int main(int argc, char** argv) {
  Settings s;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a];
    const char* value = argv[a + 1];
    if (key == "--url") {
      s.url = value;
    } else if (key == "--frames") {
      s.frames = std::atoi(value);
    } else if (key == "--rate") {
      s.rate_hz = std::atof(value);
    } else if (key == "--pause") {
      s.pause_s = std::atof(value);
    } else if (key == "--width") {
      s.width = std::atoi(value);
    } else if (key == "--height") {
      s.height = std::atoi(value);
    } else {
      std::fprintf(stderr, "view_stress_publisher: unknown option %s\n", key.c_str());
      return 2;
    }
  }
  lcm::LCM lcm(s.url);
  if (!lcm.good()) {
    std::fprintf(stderr, "view_stress_publisher: cannot open LCM at %s\n", s.url.c_str());
    return 1;
  }
  Sent sent;
  Publisher pub(&lcm, &sent);
  const auto start = Clock::now();
  Fly(s, &pub, &sent);
  std::this_thread::sleep_for(std::chrono::duration<double>(s.pause_s));  // the publisher stops
  Fly(s, &pub, &sent);                                                    // ... and restarts
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf(
      "{\"frames\": %d, \"navs\": %d, \"hazards\": %d, \"malformed\": %d, \"seconds\": %.3f, "
      "\"publish_ms_p50\": %.3f, \"publish_ms_max\": %.3f}\n",
      sent.frames, sent.navs, sent.hazards, sent.malformed, elapsed,
      Percentile(sent.publish_ms, 0.5), Percentile(sent.publish_ms, 1.0));
  return 0;
}
