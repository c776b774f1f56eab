// LiveModel: the checked decoders in front, the newest state behind one mutex, JSON per part.
#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>

#include "swf/messages/checked_decode.hpp"
#include "swf/view/live_view.hpp"

namespace swf::view {
namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

// Message kinds by the channel they come on (the flight process's prefix + suffix, the truth).
enum class Kind {
  kNav,
  kLandmarks,
  kHazard,
  kHealth,
  kStereo,
  kFeatures,
  kTruth,
  kTruthLandmarks,
  kOther
};

struct TrackPoint {
  std::int64_t frame_seq = 0;
  double estimate_m[3] = {0, 0, 0};
  bool has_truth = false;
  double truth_m[3] = {0, 0, 0};
};

const char* StatusName(int status) {
  switch (status) {
    case swf_msgs::nav_state_t::STATUS_VALID: return "VALID";
    case swf_msgs::nav_state_t::STATUS_DEGRADED: return "DEGRADED";
    case swf_msgs::nav_state_t::STATUS_INVALID: return "INVALID";
    default: return "UNKNOWN";
  }
}

const char* ModeName(int mode) {
  static const char* const kNames[] = {"SWF", "BATCH", "EKF", "VO", "VSDF"};
  return mode >= 0 && mode < 5 ? kNames[mode] : "UNKNOWN";
}

// The integrity checks that failed, by name (nav_state_t.INTEGRITY_*, in bit order).
Json IntegrityFlagNames(std::int32_t flags) {
  static const char* const kNames[] = {
      "solver failed",         "implausible state",   "diverged",
      "too few tracks",        "few tracks",          "residuals high",
      "residual jump",         "large step",          "covariance bad",
      "covariance large",      "degenerate geometry", "no parallax",
      "gate suspended",        "no motion input",     "recovering",
      "measurements rejected", "track loss",          "motion disagrees",
      "camera outage",         "motion rejected"};
  Json names = Json::array();
  for (int bit = 0; bit < 20; ++bit) {
    if ((flags >> bit) & 1) names.push_back(kNames[bit]);
  }
  return names;
}

// An enumerated field's values (0 .. N-1, as the decoder checked) as one digit each, for the
// page; counts[k] gets how many are k.
template <std::size_t N>
std::string DigitsAndCounts(const std::vector<std::int8_t>& values, std::int64_t (&counts)[N]) {
  std::string digits(values.size(), '0');
  for (std::size_t i = 0; i < values.size(); ++i) {
    const int k = std::clamp<int>(values[i], 0, static_cast<int>(N) - 1);
    digits[i] = static_cast<char>('0' + k);
    ++counts[k];
  }
  return digits;
}

std::string Base64(const std::vector<std::uint8_t>& bytes) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const std::uint32_t v = (bytes[i] << 16) | (two ? bytes[i + 1] << 8 : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += two ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// The left image reduced by an integer factor (box mean) so its width is at most max_width: the
// page needs a look at the scene, not every pixel of a 1024 px frame 20 times a second.
void Decimate(const swf_msgs::stereo_frame_t& frame, int max_width, std::vector<std::uint8_t>* out,
              int* width, int* height) {
  const int factor = std::max(1, (frame.width + max_width - 1) / std::max(1, max_width));
  *width = frame.width / factor;
  *height = frame.height / factor;
  out->assign(static_cast<std::size_t>(*width) * *height, 0);
  for (int r = 0; r < *height; ++r) {
    for (int c = 0; c < *width; ++c) {
      int sum = 0;
      for (int dr = 0; dr < factor; ++dr) {
        const std::uint8_t* row =
            frame.left.data() + static_cast<std::size_t>(r * factor + dr) * frame.width;
        for (int dc = 0; dc < factor; ++dc) sum += row[c * factor + dc];
      }
      (*out)[static_cast<std::size_t>(r) * *width + c] =
          static_cast<std::uint8_t>(sum / (factor * factor));
    }
  }
}

Json CountersJson(const ChannelCounters& c) {
  return Json{{"received", c.received},
              {"malformed", c.malformed},
              {"lost", c.lost},
              {"out_of_order", c.out_of_order},
              {"restarts", c.restarts}};
}

}  // namespace

struct LiveModel::State {
  ViewOptions options;
  std::string nav_channel, landmarks_channel, hazard_channel, health_channel, stereo_channel,
      features_channel;
  std::string truth_channel, truth_landmarks_channel;

  // Decode targets, touched by the ingesting thread only (decoding happens outside the lock).
  swf_msgs::nav_state_t scratch_nav;
  swf_msgs::landmark_map_t scratch_map;
  swf_msgs::hazard_map_t scratch_hazard;
  swf_msgs::health_t scratch_health;
  swf_msgs::stereo_frame_t scratch_frame;
  swf_msgs::feature_set_t scratch_features;
  swf_msgs::truth_state_t scratch_truth;
  std::vector<std::uint8_t> scratch_image;

  mutable std::mutex mutex;
  std::condition_variable changed;
  std::uint64_t versions[kNumParts] = {};
  std::map<std::string, ChannelCounters> channels;  // by channel name
  std::int64_t ignored = 0;
  std::string last_error;
  bool any_message = false;
  Clock::time_point last_message;
  Clock::time_point started = Clock::now();

  bool has_nav = false;
  swf_msgs::nav_state_t nav;
  bool has_health = false;
  swf_msgs::health_t health;
  bool has_map = false;
  swf_msgs::landmark_map_t map;
  bool has_truth_map = false;
  swf_msgs::landmark_map_t truth_map;
  bool has_hazard = false;
  swf_msgs::hazard_map_t hazard;
  bool has_truth = false;
  swf_msgs::truth_state_t truth;
  bool has_features = false;
  swf_msgs::feature_set_t features;
  std::deque<TrackPoint> track;
  std::map<std::int64_t, TrackPoint> truth_by_frame;  // truth that came before its estimate

  bool has_image = false;
  std::vector<std::uint8_t> image;
  int image_width = 0, image_height = 0, source_width = 0, source_height = 0;
  std::int64_t image_seq = -1;
  bool image_rectified = false;
  std::uint64_t image_served_version = 0;
  std::int64_t images_superseded = 0;

  int clients = 0;
  std::int64_t clients_refused = 0;
  std::int64_t event_bytes = 0;

  std::mutex cache_mutex;
  std::shared_ptr<const std::string> cache[kNumParts];
  std::uint64_t cache_version[kNumParts] = {};

  Kind KindOf(const std::string& channel) const {
    if (channel == nav_channel) return Kind::kNav;
    if (channel == landmarks_channel) return Kind::kLandmarks;
    if (channel == hazard_channel) return Kind::kHazard;
    if (channel == health_channel) return Kind::kHealth;
    if (channel == stereo_channel) return Kind::kStereo;
    if (channel == features_channel) return Kind::kFeatures;
    if (channel == truth_channel) return Kind::kTruth;
    if (channel == truth_landmarks_channel) return Kind::kTruthLandmarks;
    return Kind::kOther;
  }

  // Counts a sequence number (under the lock). False when the message is not to be used.
  bool Sequence(ChannelCounters* c, std::int64_t seq) {
    if (seq < 0) {
      ++c->malformed;
      return false;
    }
    if (c->next_seq > 0 && seq == 0) {
      ++c->restarts;  // a new flight: its numbers start again
    } else if (c->next_seq >= 0 && seq < c->next_seq) {
      ++c->out_of_order;
      return false;
    } else if (c->next_seq >= 0) {
      c->lost = std::min(std::numeric_limits<std::int64_t>::max() / 2,
                         c->lost + std::min(seq - c->next_seq, std::int64_t{1} << 40));
    }
    c->next_seq = seq == std::numeric_limits<std::int64_t>::max() ? seq : seq + 1;
    ++c->received;
    return true;
  }

  // Swaps the decoded message in as the latest of its channel when its sequence number says to
  // use it. False when it was not taken.
  template <typename Msg>
  bool TakeInSequence(ChannelCounters* c, Msg* scratch, Msg* latest, bool* has) {
    if (!Sequence(c, scratch->seq)) return false;
    std::swap(*latest, *scratch);
    *has = true;
    return true;
  }

  void Bump(Part part) { ++versions[part]; }
};

LiveModel::LiveModel(ViewOptions options) : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.options = std::move(options);
  s.options.max_image_width_px = std::max(16, s.options.max_image_width_px);
  s.options.trajectory_points = std::max(2, s.options.trajectory_points);
  const std::string& p = s.options.prefix;
  s.nav_channel = p + "NAV";
  s.landmarks_channel = p + "LANDMARKS";
  s.hazard_channel = p + "HAZARD";
  s.health_channel = p + "HEALTH";
  s.stereo_channel = p + "STEREO";
  s.features_channel = p + "FEATURES";
  s.truth_channel = s.options.truth_prefix;
  s.truth_landmarks_channel = s.options.truth_prefix + "_LANDMARKS";
}

LiveModel::~LiveModel() = default;

const char* LiveModel::PartName(Part part) {
  static const char* const kNames[] = {"status", "trajectory", "landmarks",
                                       "hazard", "image",      "features"};
  return part >= 0 && part < kNumParts ? kNames[part] : "unknown";
}

void LiveModel::Ingest(const std::string& channel, const void* data, std::size_t size) {
  State& s = *state_;
  const Kind kind = s.KindOf(channel);
  messages::DecodeError error;
  switch (kind) {
    case Kind::kNav: error = messages::CheckedDecode(data, size, &s.scratch_nav); break;
    case Kind::kLandmarks:
    case Kind::kTruthLandmarks: error = messages::CheckedDecode(data, size, &s.scratch_map); break;
    case Kind::kHazard: error = messages::CheckedDecode(data, size, &s.scratch_hazard); break;
    case Kind::kHealth: error = messages::CheckedDecode(data, size, &s.scratch_health); break;
    case Kind::kStereo: error = messages::CheckedDecode(data, size, &s.scratch_frame); break;
    case Kind::kFeatures: error = messages::CheckedDecode(data, size, &s.scratch_features); break;
    case Kind::kTruth: error = messages::CheckedDecode(data, size, &s.scratch_truth); break;
    case Kind::kOther: break;
  }
  int image_width = 0, image_height = 0;
  if (kind == Kind::kStereo && error.Ok()) {
    Decimate(s.scratch_frame, s.options.max_image_width_px, &s.scratch_image, &image_width,
             &image_height);
  }

  std::lock_guard<std::mutex> lock(s.mutex);
  s.any_message = true;
  s.last_message = Clock::now();
  if (kind == Kind::kOther) {
    ++s.ignored;
    return;
  }
  ChannelCounters& c = s.channels[channel];
  if (!error.Ok()) {
    ++c.malformed;
    char text[160];
    messages::Describe(error, text, sizeof text);
    s.last_error = channel + ": " + text;
    s.Bump(kStatus);
    s.changed.notify_all();
    return;
  }
  switch (kind) {
    case Kind::kNav: {
      const bool restart = c.next_seq > 0 && s.scratch_nav.seq == 0;
      if (!s.TakeInSequence(&c, &s.scratch_nav, &s.nav, &s.has_nav)) break;
      if (restart) {
        s.track.clear();
        s.truth_by_frame.clear();
      }
      TrackPoint point;
      point.frame_seq = s.nav.frame_seq;
      std::copy(s.nav.position_world_m, s.nav.position_world_m + 3, point.estimate_m);
      const auto truth = s.truth_by_frame.find(point.frame_seq);
      if (truth != s.truth_by_frame.end()) {
        point.has_truth = true;
        std::copy(truth->second.truth_m, truth->second.truth_m + 3, point.truth_m);
      }
      // Truth older than this estimate will find no estimate any more.
      s.truth_by_frame.erase(s.truth_by_frame.begin(),
                             s.truth_by_frame.upper_bound(point.frame_seq));
      s.track.push_back(point);
      while (static_cast<int>(s.track.size()) > s.options.trajectory_points) s.track.pop_front();
      s.Bump(kStatus);
      s.Bump(kTrajectory);
      break;
    }
    case Kind::kTruth: {
      ++c.received;  // truth carries no sequence number of its own
      std::swap(s.truth, s.scratch_truth);
      s.has_truth = true;
      // The simulator sends the truth after the estimate of the same frame; either order works.
      bool matched = false;
      for (auto it = s.track.rbegin(); it != s.track.rend() && !matched; ++it) {
        if (it->frame_seq != s.truth.frame_seq) continue;
        it->has_truth = true;
        std::copy(s.truth.position_world_m, s.truth.position_world_m + 3, it->truth_m);
        matched = true;
      }
      if (!matched && s.truth_by_frame.size() < 1024) {
        TrackPoint& p = s.truth_by_frame[s.truth.frame_seq];
        p.has_truth = true;
        std::copy(s.truth.position_world_m, s.truth.position_world_m + 3, p.truth_m);
      }
      s.Bump(kStatus);
      s.Bump(kTrajectory);
      break;
    }
    case Kind::kLandmarks:
      if (s.TakeInSequence(&c, &s.scratch_map, &s.map, &s.has_map)) s.Bump(kLandmarks);
      break;
    case Kind::kTruthLandmarks:
      ++c.received;
      std::swap(s.truth_map, s.scratch_map);
      s.has_truth_map = true;
      s.Bump(kLandmarks);
      break;
    case Kind::kHazard:
      if (!s.TakeInSequence(&c, &s.scratch_hazard, &s.hazard, &s.has_hazard)) break;
      s.Bump(kHazard);
      s.Bump(kStatus);
      break;
    case Kind::kHealth:
      if (s.TakeInSequence(&c, &s.scratch_health, &s.health, &s.has_health)) s.Bump(kStatus);
      break;
    case Kind::kFeatures:
      if (s.TakeInSequence(&c, &s.scratch_features, &s.features, &s.has_features)) {
        s.Bump(kFeatures);
      }
      break;
    case Kind::kStereo:
      if (!s.Sequence(&c, s.scratch_frame.seq)) break;
      // Latest wins: an image no client took before this one replaces it is superseded.
      if (s.has_image && s.image_served_version < s.versions[kImage]) ++s.images_superseded;
      std::swap(s.image, s.scratch_image);
      s.image_width = image_width;
      s.image_height = image_height;
      s.source_width = s.scratch_frame.width;
      s.source_height = s.scratch_frame.height;
      s.image_seq = s.scratch_frame.seq;
      s.image_rectified = s.scratch_frame.rectified;
      s.has_image = true;
      s.Bump(kImage);
      break;
    case Kind::kOther: break;
  }
  s.Bump(kStatus);
  s.changed.notify_all();
}

std::uint64_t LiveModel::Version(Part part) const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->versions[part];
}

std::uint64_t LiveModel::VersionSum() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  std::uint64_t sum = 0;
  for (std::uint64_t v : state_->versions) sum += v;
  return sum;
}

std::uint64_t LiveModel::WaitForChange(std::uint64_t seen, std::chrono::milliseconds timeout) {
  State& s = *state_;
  std::unique_lock<std::mutex> lock(s.mutex);
  const auto sum = [&s] {
    std::uint64_t total = 0;
    for (std::uint64_t v : s.versions) total += v;
    return total;
  };
  s.changed.wait_for(lock, timeout, [&] { return sum() != seen; });
  return sum();
}

void LiveModel::MarkImageServed(std::uint64_t version) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->image_served_version = std::max(state_->image_served_version, version);
}

void LiveModel::CountClient(int delta) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->clients += delta;
}

void LiveModel::CountClientRefused() {
  std::lock_guard<std::mutex> lock(state_->mutex);
  ++state_->clients_refused;
}

void LiveModel::CountEventsSent(std::int64_t bytes) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->event_bytes += bytes;
}

ChannelCounters LiveModel::Counters(const std::string& channel_suffix) const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  for (const auto& [name, counters] : state_->channels) {
    if (name.size() >= channel_suffix.size() &&
        name.compare(name.size() - channel_suffix.size(), channel_suffix.size(), channel_suffix) ==
            0 &&
        name.find("TRUTH") == std::string::npos) {
      return counters;
    }
  }
  return {};
}

std::int64_t LiveModel::MalformedTotal() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  std::int64_t total = 0;
  for (const auto& entry : state_->channels) total += entry.second.malformed;
  return total;
}

std::int64_t LiveModel::LostTotal() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  std::int64_t total = 0;
  for (const auto& entry : state_->channels) total += entry.second.lost;
  return total;
}

std::int64_t LiveModel::ImagesSuperseded() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->images_superseded;
}

namespace {

Json NavJson(const swf_msgs::nav_state_t& nav) {
  const double* p = nav.position_world_m;
  const double* v = nav.velocity_world_mps;
  return Json{
      {"frame_seq", nav.frame_seq},
      {"seq", nav.seq},
      {"utime", nav.utime},
      {"position_m", {p[0], p[1], p[2]}},
      {"velocity_mps", {v[0], v[1], v[2]}},
      {"sigma_m",
       {std::sqrt(std::max(0.0, nav.covariance[0])), std::sqrt(std::max(0.0, nav.covariance[7])),
        std::sqrt(std::max(0.0, nav.covariance[14]))}},
      {"status", StatusName(nav.status)},
      {"mode", ModeName(nav.mode)},
      {"integrity_flags", IntegrityFlagNames(nav.integrity_flags)},
      {"horizontal_protection_m", nav.horizontal_protection_m},
      {"vertical_protection_m", nav.vertical_protection_m},
      {"integrity_risk", nav.integrity_risk},
      {"iterations", nav.iterations},
      {"num_measurements", nav.num_measurements}};
}

Json HealthJson(const swf_msgs::health_t& h) {
  Json stages = Json::array();
  for (int i = 0; i < h.num_stages; ++i) {
    stages.push_back(Json{{"name", h.stage_name[i]},
                          {"p50_ms", h.stage_p50_ms[i]},
                          {"p99_ms", h.stage_p99_ms[i]},
                          {"max_ms", h.stage_max_ms[i]}});
  }
  return Json{{"frames", h.frames},
              {"frames_dropped", h.frames_dropped},
              {"frames_rejected", h.frames_rejected},
              {"overruns", h.overruns},
              {"outputs_dropped", h.outputs_dropped},
              {"allocations_after_start", h.allocations_after_start},
              {"fault_bits", h.fault_bits},
              {"num_features", h.num_features},
              {"num_landmarks", h.num_landmarks},
              {"frames_valid", h.frames_valid},
              {"frames_degraded", h.frames_degraded},
              {"frames_invalid", h.frames_invalid},
              {"restarts", h.restarts},
              {"measurements_gated", h.measurements_gated},
              {"measurements_rejected", h.measurements_rejected},
              {"landmarks_rejected", h.landmarks_rejected},
              {"new_landmarks_refused", h.new_landmarks_refused},
              {"imu_accepted", h.imu_accepted},
              {"stages", stages}};
}

// One digit a cell for the page to draw, and how many cells hold each value (by the names of
// the message's enumeration, in its order).
template <std::size_t N>
Json DigitsWithCounts(const std::vector<std::int8_t>& values, const char* const (&names)[N],
                      const char* digits_key) {
  std::int64_t counts[N] = {};
  const std::string digits = DigitsAndCounts(values, counts);
  Json named = Json::object();
  for (std::size_t k = 0; k < N; ++k) named[names[k]] = counts[k];
  return Json{{digits_key, digits}, {"counts", named}};
}

Json HazardJson(const swf_msgs::hazard_map_t& h) {
  static constexpr const char* kClasses[] = {"unknown", "safe",  "slope",
                                             "rock",    "rough", "uncertain"};
  Json j = DigitsWithCounts(h.hazard_class, kClasses, "classes");
  j["frame_seq"] = h.frame_seq;
  j["rows"] = h.rows;
  j["cols"] = h.cols;
  j["cell_size_m"] = h.cell_size_m;
  j["origin_m"] = {h.origin_world_m[0], h.origin_world_m[1]};
  j["known_cells"] = static_cast<std::int64_t>(std::count_if(
      h.hazard_class.begin(), h.hazard_class.end(), [](std::int8_t c) { return c > 0; }));
  j["safe_site"] = {{"valid", h.safe_site_valid},
                    {"position_m", {h.safe_site_world_m[0], h.safe_site_world_m[1]}},
                    {"score", h.safe_site_score}};
  return j;
}

Json FeaturesJson(const swf_msgs::feature_set_t& f) {
  static constexpr const char* kStatus[] = {"tracked", "new", "rejected", "gated"};
  Json j = DigitsWithCounts(f.status, kStatus, "status");
  j["frame_seq"] = f.frame_seq;
  j["u_px"] = f.u_px;
  j["v_px"] = f.v_px;
  return j;
}

}  // namespace

std::shared_ptr<const std::string> LiveModel::Json(Part part) {
  State& s = *state_;
  std::lock_guard<std::mutex> cache_lock(s.cache_mutex);
  // The status carries the time since the last message: always fresh. The others are built once
  // per version and shared between clients.
  if (part != kStatus && s.cache[part] && s.cache_version[part] == Version(part)) {
    return s.cache[part];
  }
  nlohmann::json j;
  std::uint64_t version = 0;
  {
    std::lock_guard<std::mutex> lock(s.mutex);
    version = s.versions[part];
    switch (part) {
      case kStatus: {
        j["nav"] = s.has_nav ? NavJson(s.nav) : nlohmann::json(nullptr);
        j["frames"] = s.channels.count(s.nav_channel) ? s.channels[s.nav_channel].received : 0;
        j["health"] = s.has_health ? HealthJson(s.health) : nlohmann::json(nullptr);
        if (s.has_truth) {
          const double* t = s.truth.position_world_m;
          j["truth"] = {{"frame_seq", s.truth.frame_seq},
                        {"position_m", {t[0], t[1], t[2]}},
                        {"altitude_m", s.truth.altitude_m}};
          if (s.has_nav && s.nav.frame_seq == s.truth.frame_seq) {
            const double* e = s.nav.position_world_m;
            j["truth"]["error_m"] =
                std::sqrt((e[0] - t[0]) * (e[0] - t[0]) + (e[1] - t[1]) * (e[1] - t[1]) +
                          (e[2] - t[2]) * (e[2] - t[2]));
          }
        } else {
          j["truth"] = nullptr;
        }
        nlohmann::json channels = nlohmann::json::object();
        std::int64_t malformed = 0, lost = 0;
        for (const auto& [name, counters] : s.channels) {
          channels[name] = CountersJson(counters);
          malformed += counters.malformed;
          lost += counters.lost;
        }
        const double since_last =
            s.any_message ? std::chrono::duration<double>(Clock::now() - s.last_message).count()
                          : -1.0;
        j["bus"] = {{"channels", channels},
                    {"malformed_total", malformed},
                    {"lost_total", lost},
                    {"ignored", s.ignored},
                    {"images_superseded", s.images_superseded},
                    {"last_error", s.last_error},
                    {"seconds_since_last_message", since_last},
                    {"publisher", !s.any_message     ? "waiting"
                                  : since_last > 2.0 ? "silent"
                                                     : "live"}};
        j["http"] = {{"clients", s.clients},
                     {"clients_refused", s.clients_refused},
                     {"event_bytes", s.event_bytes}};
        j["uptime_s"] = std::chrono::duration<double>(Clock::now() - s.started).count();
        break;
      }
      case kTrajectory: {
        nlohmann::json frames = nlohmann::json::array(), estimate = nlohmann::json::array(),
                       truth = nlohmann::json::array();
        for (const TrackPoint& p : s.track) {
          frames.push_back(p.frame_seq);
          estimate.push_back({p.estimate_m[0], p.estimate_m[1], p.estimate_m[2]});
          truth.push_back(p.has_truth ? nlohmann::json{p.truth_m[0], p.truth_m[1], p.truth_m[2]}
                                      : nlohmann::json(nullptr));
        }
        j = {{"frame_seq", frames}, {"estimate_m", estimate}, {"truth_m", truth}};
        if (s.has_nav) {
          const double* c = s.nav.covariance;  // rho block: world x, y, z rows/columns 0..2
          j["covariance_xy_m2"] = {c[0], c[1], c[7]};
          j["sigma_z_m"] = std::sqrt(std::max(0.0, c[14]));
        }
        break;
      }
      case kLandmarks: {
        nlohmann::json points = nlohmann::json::array(), sigma = nlohmann::json::array(),
                       truth = nlohmann::json::array();
        if (s.has_map) {
          std::map<std::int64_t, int> truth_index;
          if (s.has_truth_map && s.truth_map.frame_seq == s.map.frame_seq) {
            for (int i = 0; i < s.truth_map.num_landmarks; ++i) truth_index[s.truth_map.id[i]] = i;
          }
          for (int i = 0; i < s.map.num_landmarks; ++i) {
            const auto& p = s.map.position_world_m[i];
            const auto& c = s.map.covariance_m2[i];
            points.push_back({p[0], p[1], p[2]});
            sigma.push_back(std::sqrt(std::max(0.0, c[0] + c[3] + c[5])));
            const auto t = truth_index.find(s.map.id[i]);
            if (t != truth_index.end()) {
              const auto& q = s.truth_map.position_world_m[t->second];
              truth.push_back({q[0], q[1], q[2]});
            } else {
              truth.push_back(nullptr);
            }
          }
          j["frame_seq"] = s.map.frame_seq;
        } else {
          j["frame_seq"] = nullptr;
        }
        j["position_m"] = points;
        j["sigma_m"] = sigma;
        j["truth_m"] = truth;
        break;
      }
      case kHazard:
        j = s.has_hazard ? HazardJson(s.hazard) : nlohmann::json{{"frame_seq", nullptr}};
        break;
      case kImage: {
        if (!s.has_image) {
          j = {{"seq", nullptr}};
          break;
        }
        j = {{"seq", s.image_seq},
             {"width", s.image_width},
             {"height", s.image_height},
             {"source_width", s.source_width},
             {"source_height", s.source_height},
             {"rectified", s.image_rectified},
             {"gray_base64", Base64(s.image)}};
        break;
      }
      case kFeatures:
        j = s.has_features ? FeaturesJson(s.features) : nlohmann::json{{"frame_seq", nullptr}};
        break;
      case kNumParts: break;
    }
  }
  // nlohmann writes null for a non-finite number: the text is always valid JSON.
  auto text = std::make_shared<const std::string>(j.dump());
  if (part != kStatus) {
    s.cache[part] = text;
    s.cache_version[part] = version;
  }
  return text;
}

std::string LiveModel::StateJson() {
  std::string out = "{";
  for (int p = 0; p < kNumParts; ++p) {
    if (p > 0) out += ",";
    out += "\"";
    out += PartName(static_cast<Part>(p));
    out += "\":";
    out += *Json(static_cast<Part>(p));
  }
  out += "}";
  return out;
}

}  // namespace swf::view
