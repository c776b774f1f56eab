#include "swf/app/config.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>

#include "swf/app/config_fields.hpp"
#include "swf/app/lcm_io.hpp"
#include "swf/cli/cli.hpp"
#include "swf/drivers/lcm_stereo_source.hpp"

namespace swf::app {

namespace {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

}  // namespace

// At most this many bytes of anything read are quoted back in an error: a 10 MB value must not
// become 10 MB on stderr, and bytes outside printable ASCII are shown as \xNN so that an error
// never writes terminal control sequences or invalid text.
constexpr std::size_t kMaxExcerpt = 48;

std::string Excerpt(const std::string& s) {
  std::string out;
  const std::size_t n = std::min(s.size(), kMaxExcerpt);
  for (std::size_t i = 0; i < n; ++i) {
    const auto ch = static_cast<unsigned char>(s[i]);
    if (ch >= 0x20 && ch < 0x7f) {
      out += static_cast<char>(ch);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", ch);
      out += hex;
    }
  }
  if (s.size() > kMaxExcerpt) out += std::string("... (") + std::to_string(s.size()) + " bytes)";
  return out;
}

// The value in quotes, excerpted. (Built by appending: GCC 12 reports a false -Wrestrict for "'" +
// std::string when this is inlined.)
std::string Quoted(const std::string& v) {
  std::string out(1, '\'');
  out += Excerpt(v);
  out += '\'';
  return out;
}

bool ParseDouble(const std::string& v, double* out, std::string* why) {
  char* end = nullptr;
  errno = 0;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || end == v.c_str() || *end != '\0' || errno != 0 || !std::isfinite(d)) {
    *why = Quoted(v) + " is not a finite number";
    return false;
  }
  *out = d;
  return true;
}

bool ParseInt(const std::string& v, std::int64_t* out, std::string* why) {
  char* end = nullptr;
  errno = 0;
  const long long i = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || end == v.c_str() || *end != '\0' || errno != 0) {
    *why = Quoted(v) + " is not an integer";
    return false;
  }
  *out = i;
  return true;
}

namespace {

// A finite number into the member `field`, inside [lo, hi].
ConfigSetter Double(double FswConfig::*field, double lo, double hi) {
  return Number([field](FswConfig* c) { return &(c->*field); }, lo, hi);
}

// Three finite numbers ("x y z" or "x, y, z") into field[3].
template <typename Get>
ConfigSetter Vector3(Get get) {
  return Numbers<3>(get, std::numeric_limits<double>::lowest(), std::numeric_limits<double>::max(),
                    "x y z");
}

}  // namespace

// "[lo, hi]", with "(" when the low end is excluded.
std::string Interval(double lo, double hi, bool lo_open) {
  std::ostringstream o;
  o << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
  return o.str();
}

bool InInterval(double d, double lo, double hi, bool lo_open) {
  return (lo_open ? d > lo : d >= lo) && d <= hi;
}

namespace {

// A non-negative finite number into a member of ImuConfig, at most hi.
ConfigSetter ImuNumber(double ImuConfig::*field, double hi, double lo = 0.0) {
  return Number([field](FswConfig* c) { return &(c->imu.*field); }, lo, hi);
}

// Where the stereo pairs come from: the source and its log or LCM input.
void AddSourceFields(std::map<std::string, ConfigSetter>* fields) {
  std::map<std::string, ConfigSetter>& f = *fields;
  f["source"] =
      OneOf<SourceKind>([](FswConfig* c) { return &c->source; }, {{"sim", SourceKind::kSim},
                                                                  {"v4l2", SourceKind::kV4l2},
                                                                  {"aravis", SourceKind::kAravis},
                                                                  {"log", SourceKind::kLog},
                                                                  {"lcm", SourceKind::kLcm}});
  f["log.path"] = Text([](FswConfig* c) { return &c->log_path; });
  f["lcm_source.url"] = Text([](FswConfig* c) { return &c->lcm_source.url; });
  f["lcm_source.channel"] = Text([](FswConfig* c) { return &c->lcm_source.channel; });
  // The frame group holds one pair; the receiver needs a free buffer to keep receiving.
  f["lcm_source.buffers"] =
      Int<std::int32_t>([](FswConfig* c) { return &c->lcm_source.buffers; }, 2,
                        drivers::kMaxLcmBuffers, " (drivers::kMaxLcmBuffers)");
}

// The IMU input and its model.
void AddImuFields(std::map<std::string, ConfigSetter>* fields) {
  std::map<std::string, ConfigSetter>& f = *fields;
  f["imu.enabled"] = Bool([](FswConfig* c) { return &c->imu.enabled; });
  f["imu.static_start"] = Bool([](FswConfig* c) { return &c->imu.static_start; });
  f["imu.channel"] = Text([](FswConfig* c) { return &c->imu.channel; });
  f["imu.rate_hz"] = ImuNumber(&ImuConfig::rate_hz, 10000.0);
  f["imu.max_latency_ms"] = ImuNumber(&ImuConfig::max_latency_ms, 1000.0);
  f["imu.gyro_noise_density"] = ImuNumber(&ImuConfig::gyro_noise_density, 1.0);
  f["imu.gyro_random_walk"] = ImuNumber(&ImuConfig::gyro_random_walk, 1.0);
  f["imu.accel_noise_density"] = ImuNumber(&ImuConfig::accel_noise_density, 10.0);
  f["imu.accel_random_walk"] = ImuNumber(&ImuConfig::accel_random_walk, 10.0);
  f["imu.gyro_range_radps"] = ImuNumber(&ImuConfig::gyro_range_radps, 1000.0);
  f["imu.accel_range_mps2"] = ImuNumber(&ImuConfig::accel_range_mps2, 10000.0);
  f["imu.gravity_mps2"] = ImuNumber(&ImuConfig::gravity_mps2, 100.0);
  f["imu.gyro_bias_sigma_radps"] = ImuNumber(&ImuConfig::gyro_bias_sigma_radps, 10.0);
  f["imu.accel_bias_sigma_mps2"] = ImuNumber(&ImuConfig::accel_bias_sigma_mps2, 100.0);
  f["imu.velocity_sigma_mps"] = ImuNumber(&ImuConfig::velocity_sigma_mps, 1000.0);
  f["imu.time_offset_ms"] = ImuNumber(&ImuConfig::time_offset_ms, 1000.0, -1000.0);
  f["imu.estimate_time_offset"] = Bool([](FswConfig* c) { return &c->imu.estimate_time_offset; });
  f["imu.max_time_offset_ms"] = ImuNumber(&ImuConfig::max_time_offset_ms, 1000.0);
  f["imu.camera_t_imu_m"] = Vector3([](FswConfig* c) { return c->imu.camera_t_imu_m; });
  f["imu.camera_r_imu_rad"] = Vector3([](FswConfig* c) { return c->imu.camera_r_imu_rad; });
  f["imu.initial_velocity_mps"] = Vector3([](FswConfig* c) { return c->imu.initial_velocity_mps; });
}

// The cameras (V4L2, Aravis) and their calibrations.
void AddCameraFields(std::map<std::string, ConfigSetter>* fields) {
  std::map<std::string, ConfigSetter>& f = *fields;
  f["camera.left"] = Text([](FswConfig* c) { return &c->camera.left; });
  f["camera.right"] = Text([](FswConfig* c) { return &c->camera.right; });
  f["camera.left_calibration"] = Text([](FswConfig* c) { return &c->camera.left_calibration; });
  f["camera.right_calibration"] = Text([](FswConfig* c) { return &c->camera.right_calibration; });
  f["camera.fake"] = Bool([](FswConfig* c) { return &c->camera.fake; });
  f["camera.format"] =
      OneOf([](FswConfig* c) { return &c->camera.format; }, {"grey", "y16", "yuyv"});
  // The V4L2 source holds up to 2 pairs and the kernel needs 2 more buffers to keep streaming.
  f["camera.buffers"] = Int<std::int32_t>([](FswConfig* c) { return &c->camera.buffers; }, 4, 16);
  f["camera.pair_tolerance_ms"] =
      Number([](FswConfig* c) { return &c->camera.pair_tolerance_ms; }, 0.0, 1000.0);
  f["camera.exposure_us"] =
      Number([](FswConfig* c) { return &c->camera.exposure_us; }, 0.0, 1e8, true);
  f["camera.gain"] = Number([](FswConfig* c) { return &c->camera.gain; }, 0.0, 1e4);
  f["camera.roi_offset_px"] = [](const std::string& v, FswConfig* c, std::string* why) {
    std::istringstream in(v);
    std::int64_t x = -1;
    std::int64_t y = -1;
    std::string rest;
    if (!(in >> x >> y) || (in >> rest) || x < 0 || y < 0 || x > 65535 || y > 65535) {
      *why = Quoted(v) + ": expected two whole numbers of pixels in [0, 65535]: x y";
      return false;
    }
    c->camera.roi_offset_px[0] = static_cast<std::int32_t>(x);
    c->camera.roi_offset_px[1] = static_cast<std::int32_t>(y);
    return true;
  };
  f["camera.packet_size"] =
      Int<std::int32_t>([](FswConfig* c) { return &c->camera.packet_size; }, 0, 65535);
  f["camera.trigger"] =
      OneOf([](FswConfig* c) { return &c->camera.trigger; }, {"free", "software", "hardware"});
  f["camera.trigger_source"] = Text([](FswConfig* c) { return &c->camera.trigger_source; });
}

// The estimator and the front end.
void AddEstimatorFields(std::map<std::string, ConfigSetter>* fields) {
  std::map<std::string, ConfigSetter>& f = *fields;
  f["mode"] = OneOf([](FswConfig* c) { return &c->mode; }, {"swf", "ekf", "vo", "vsdf"});
  f["window"] = Int<std::int32_t>([](FswConfig* c) { return &c->window; }, 1, kMaxWindow,
                                  " (kMaxWindow, the filter's compiled window capacity)");
  f["max_iterations"] = Int<std::int32_t>([](FswConfig* c) { return &c->max_iterations; }, 1, 100);
  f["measurement_sigma_px"] = Double(&FswConfig::measurement_sigma_px, 1e-3, 100.0);
  f["measurement_sigma_per_magnification_px"] =
      Double(&FswConfig::measurement_sigma_per_magnification_px, 0.0, 100.0);
  f["measurement_sigma_per_magnification_rad"] =
      Double(&FswConfig::measurement_sigma_per_magnification_rad, 0.0, 0.1);
  f["measurement_track_error"] =
      OneOf<bool>([](FswConfig* c) { return &c->measurement_track_error_shared; },
                  {{"independent", false}, {"shared", true}});
  f["measurement_disparity_sigma_px"] =
      Double(&FswConfig::measurement_disparity_sigma_px, 0.0, 100.0);
  f["measurement_disparity_sigma_per_parallax_px"] =
      Double(&FswConfig::measurement_disparity_sigma_per_parallax_px, 0.0, 1e4);
  f["min_quality"] = Double(&FswConfig::min_quality, -1.0, 1.0);
  f["process_sigma_m"] = Double(&FswConfig::process_sigma_m, 1e-6, 1e3);
  f["process_sigma_rad"] = Double(&FswConfig::process_sigma_rad, 1e-8, 3.0);
  f["calibration.baseline_sigma_m"] = Double(&FswConfig::calibration_baseline_sigma_m, 0.0, 1.0);
  f["calibration.disparity_sigma_px"] =
      Double(&FswConfig::calibration_disparity_sigma_px, 0.0, 10.0);
  f["max_tracks"] = Int<std::int32_t>([](FswConfig* c) { return &c->max_tracks; }, 8,
                                      static_cast<std::int64_t>(frontend::kMaxTracks),
                                      " (frontend::kMaxTracks, the compiled track capacity)");
  f["hold_depth_precision"] = Double(&FswConfig::hold_depth_precision, 0.0, 0.5);
  f["vsdf.schur"] = OneOf<bool>([](FswConfig* c) { return &c->vsdf_scalar_diagonal; },
                                {{"block", false}, {"diagonal", true}});
  f["max_disparity_px"] = Int<std::int32_t>([](FswConfig* c) { return &c->max_disparity_px; }, 8,
                                            frontend::kMaxDisparity);
  f["frontend.refine_in_loop"] = Bool([](FswConfig* c) { return &c->frontend_refine_in_loop; });
  f["frontend.reference_from_estimate"] =
      Bool([](FswConfig* c) { return &c->frontend_reference_from_estimate; });
  f["frontend.recover_lost_tracks"] =
      Bool([](FswConfig* c) { return &c->frontend_recover_lost_tracks; });
}

// Pacing, the hazard and health cadences, real-time settings, outputs, fault injection and the
// integrity envelope.
void AddRunFields(std::map<std::string, ConfigSetter>* fields) {
  std::map<std::string, ConfigSetter>& f = *fields;
  f["rate_hz"] = Double(&FswConfig::rate_hz, 0.1, 1000.0);
  f["pacing"] = OneOf<Pacing>([](FswConfig* c) { return &c->pacing; },
                              {{"realtime", Pacing::kRealtime}, {"lockstep", Pacing::kLockstep}});
  f["hazard_every"] = Int<std::int32_t>([](FswConfig* c) { return &c->hazard_every; }, 1, 100000);
  f["hazard.max_disparities"] =
      Int<std::int32_t>([](FswConfig* c) { return &c->hazard_max_disparities; }, 16, 256);
  f["hazard.downsample"] = OneOf<std::int32_t>([](FswConfig* c) { return &c->hazard_downsample; },
                                               {{"1", 1}, {"2", 2}, {"4", 4}});
  f["health_every"] = Int<std::int32_t>([](FswConfig* c) { return &c->health_every; }, 1, 100000);
  f["max_frames"] =
      Int<std::int64_t>([](FswConfig* c) { return &c->max_frames; }, 0, std::int64_t{1} << 40);
  f["rt.mlockall"] = Bool([](FswConfig* c) { return &c->mlockall; });
  f["rt.priority"] = Int<std::int32_t>([](FswConfig* c) { return &c->priority; }, 0, 98);
  f["rt.cpu"] = Int<std::int32_t>([](FswConfig* c) { return &c->cpu; }, -1, 1023);
  f["lcm.url"] = Text([](FswConfig* c) { return &c->lcm_url; });
  f["lcm.publish"] = Bool([](FswConfig* c) { return &c->publish; });
  f["lcm.channel_prefix"] = Text([](FswConfig* c) { return &c->channel_prefix; });
  f["record.path"] = Text([](FswConfig* c) { return &c->record_path; });
  f["record.frames"] = Bool([](FswConfig* c) { return &c->record_frames; });
  f["summary.path"] = Text([](FswConfig* c) { return &c->summary_path; });
  f["summary.plot_dir"] = Text([](FswConfig* c) { return &c->plot_dir; });
  f["initial"] = OneOf([](FswConfig* c) { return &c->initial; }, {"truth", "position"});
  f["initial.position_m"] = Vector3([](FswConfig* c) { return c->initial_position_m; });
  f["inject.stage"] = [](const std::string& v, FswConfig* c, std::string* why) {
    if (StageIndex(v) < 0 || StageIndex(v) >= kStageCycle) {
      *why = Quoted(v) + " is not a stage (acquire rectify track estimate output map)";
      return false;
    }
    c->inject_stage = v;
    return true;
  };
  f["inject.frame"] =
      Int<std::int64_t>([](FswConfig* c) { return &c->inject_frame; }, -1, std::int64_t{1} << 40);
  f["inject.frames"] =
      Int<std::int64_t>([](FswConfig* c) { return &c->inject_frames; }, 1, std::int64_t{1} << 40);
  f["inject.ms"] = Double(&FswConfig::inject_ms, 0.0, 60000.0);
  f["envelope.min_range_m"] =
      Number([](FswConfig* c) { return &c->envelope_min_range_m; }, 0.0, 1e6, true);
}

const std::map<std::string, ConfigSetter>& Fields() {
  static const std::map<std::string, ConfigSetter> kFields = [] {
    std::map<std::string, ConfigSetter> f;
    AddSourceFields(&f);
    AddImuFields(&f);
    AddCameraFields(&f);
    AddEstimatorFields(&f);
    AddRunFields(&f);
    return f;
  }();
  return kFields;
}

// A configuration is text: NUL (which would silently cut a value short: `window: 5\0junk` read as
// 5) and the other control bytes are refused; tab and carriage return (CRLF files) are blanks.
bool CheckBytes(const std::string& line, const std::string& where, std::string* error) {
  for (std::size_t i = 0; i < line.size(); ++i) {
    const auto ch = static_cast<unsigned char>(line[i]);
    if ((ch < 0x20 && ch != '\t' && ch != '\r') || ch == 0x7f) {
      char what[64];
      std::snprintf(what, sizeof what, "%s (0x%02x) at column %zu",
                    ch == 0 ? "a NUL byte" : "a control byte", ch, i + 1);
      *error = where + ": " + what + ": a configuration is text";
      return false;
    }
  }
  return true;
}

// Splits one line into key and value. A blank or comment-only line gives an empty key.
bool SplitLine(const std::string& raw, const std::string& where, std::string* key,
               std::string* value, std::string* error) {
  std::string line = raw;
  const auto hash = line.find('#');
  if (hash != std::string::npos) line = line.substr(0, hash);
  line = Trim(line);
  key->clear();
  value->clear();
  if (line.empty()) return true;
  const auto colon = line.find(':');
  if (colon == std::string::npos) {
    *error = where + ": expected 'key: value', got '" + Excerpt(line) + "'";
    return false;
  }
  *key = Trim(line.substr(0, colon));
  *value = Trim(line.substr(colon + 1));
  if (key->empty()) {
    *error = where + ": expected 'key: value', got '" + Excerpt(line) + "' (no key)";
    return false;
  }
  return true;
}

// A key of the program's extension (c->extension) when the flight process has no such key; a
// simulator key in a program without the simulator says where it belongs.
// camera.feature.<Name>: any GenICam feature, one key each (a name of letters, digits and '_',
// as GenICam names are), so that an error names the key.
constexpr const char* kFeaturePrefix = "camera.feature.";

const ConfigSetter* FeatureField(const std::string& key) {
  // The value is checked and stored by SetField, which knows the feature's name.
  static const ConfigSetter kAccept = [](const std::string& /*value*/, FswConfig* /*c*/,
                                         std::string* why) {
    why->clear();
    return true;
  };
  if (key.rfind(kFeaturePrefix, 0) != 0) return nullptr;
  const std::string name = key.substr(std::strlen(kFeaturePrefix));
  if (name.empty() || std::isalpha(static_cast<unsigned char>(name[0])) == 0) return nullptr;
  for (const char ch : name) {
    if (std::isalnum(static_cast<unsigned char>(ch)) == 0 && ch != '_') return nullptr;
  }
  return &kAccept;
}

const ConfigSetter* FindField(const std::string& key, const FswConfig& c) {
  if (const ConfigSetter* feature = FeatureField(key)) return feature;
  const auto& fields = Fields();
  if (const auto it = fields.find(key); it != fields.end()) return &it->second;
  if (c.extension != nullptr) {
    const auto& more = *c.extension->fields;
    if (const auto it = more.find(key); it != more.end()) return &it->second;
  }
  return nullptr;
}

bool SetField(const std::string& key, const std::string& value, const std::string& where,
              FswConfig* config, std::string* error) {
  const ConfigSetter* setter = FindField(key, *config);
  if (setter == nullptr) {
    const bool simulator = key.rfind("sim.", 0) == 0 || key.rfind("inject.black_", 0) == 0;
    *error = where + ": " + Excerpt(key) + ": unknown field" +
             (simulator && config->extension == nullptr
                  ? " (a simulator key: swf-sil flies the simulated descent)"
                  : "");
    return false;
  }
  std::string why;
  if (!(*setter)(value, config, &why)) {
    *error = where + ": " + key + ": " + why;
    return false;
  }
  if (key.rfind(kFeaturePrefix, 0) == 0) {
    // A GenICam value is one word (arv_device_set_features_from_string's syntax).
    if (value.empty() || value.find_first_of(" \t=") != std::string::npos) {
      *error = where + ": " + key + ": " + Quoted(value) +
               ": expected one word (the feature's value, e.g. Off, 1000, Mono8)";
      return false;
    }
    config->camera.features[key.substr(std::strlen(kFeaturePrefix))] = value;
  }
  return true;
}

// The file's lines into `c` (which starts from the defaults), recording where each key was set. A
// key set twice is refused: the last one would win silently (`source: aravis` ... `source: sim`
// flies the simulator).
bool ApplyFileText(const std::string& text, const std::string& file, FswConfig* c,
                   std::string* error) {
  c->origins.file = file;
  std::size_t begin = 0;
  int number = 0;
  int settings = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string raw = text.substr(begin, end - begin);
    begin = end + 1;
    const std::string where = file + ":" + std::to_string(++number);
    std::string key;
    std::string value;
    if (!CheckBytes(raw, where, error) || !SplitLine(raw, where, &key, &value, error)) {
      return false;
    }
    if (key.empty()) continue;
    const auto first = c->origins.keys.find(key);
    if (first != c->origins.keys.end()) {
      *error =
          where + ": " + key + ": set again (first on " + first->second + "); a key is set once";
      return false;
    }
    if (!SetField(key, value, where, c, error)) return false;
    c->origins.keys[key] = where;
    c->origins.values[key] = value;
    ++settings;
  }
  // An empty or comments-only file would fly every default (a simulated descent publishing on the
  // bus): what a file does not say is not guessed.
  if (settings == 0) {
    *error = file + ": no settings (the file is empty or only comments)";
    return false;
  }
  if (c->origins.keys.count("source") == 0) {
    *error = file + ": source: required (sim, v4l2, aravis or log): the file names what it flies";
    return false;
  }
  return true;
}

// One command-line override. A key the file sets may be overridden (that is what --set is for); the
// same key twice on the command line is refused like a key twice in the file.
bool ApplyOverride(const std::string& key_value, FswConfig* c, std::string* error) {
  const std::string where = "--set";
  std::string key;
  std::string value;
  if (!CheckBytes(key_value, where, error) || !SplitLine(key_value, where, &key, &value, error)) {
    return false;
  }
  if (key.empty()) {
    *error = where + ": expected 'key: value', got '" + Excerpt(key_value) + "'";
    return false;
  }
  const auto before = c->origins.keys.find(key);
  if (before != c->origins.keys.end() && before->second == where) {
    *error = where + ": " + key + ": given twice on the command line";
    return false;
  }
  if (!SetField(key, value, where, c, error)) return false;
  c->origins.keys[key] = where;
  c->origins.values[key] = value;
  return true;
}

}  // namespace

std::string ConfigWhere(const FswConfig& c, const std::string& field, const std::string& origin) {
  const auto it = c.origins.keys.find(field);
  if (it != c.origins.keys.end()) return it->second;
  return c.origins.file.empty() ? origin : c.origins.file;
}

bool RefuseField(const FswConfig& c, const std::string& field, const std::string& origin,
                 const std::string& why, std::string* error) {
  *error = ConfigWhere(c, field, origin) + ": " + field + ": " + why;
  return false;
}

std::string Fixed(double v, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

// The front end finds a feature's match only within its search, min(max_disparity_px, width / 2)
// (app.cpp FrontendFor), and its sub-pixel fit needs the cost one disparity beyond the minimum: the
// disparity of the closest ground, f b / range, must stay at least 1 px inside. Beyond it every
// close feature is matched to a wrong disparity or not at all, and the estimate diverges while
// reporting ok (demo at 1024 px with max_disparity_px 160: 231 px at 10 m, landmark RMS 6570 m).
// `shift_px`: a disparity the right image adds at every range (the simulator's rotation error).
bool DisparityFits(const FswConfig& c, double fx_px, double baseline_m, int width_px,
                   double range_m, const std::string& range_from, const std::string& rig_from,
                   const std::string& origin, std::string* error, double shift_px) {
  const std::string field = "max_disparity_px";
  const std::string at = ConfigWhere(c, field, origin);
  if (!(range_m > 0.0)) {
    *error = at + ": " + field + ": the closest range flown (" + Fixed(range_m, 2) + " m, " +
             range_from + ") is not above the ground";
    return false;
  }
  const double need_px = fx_px * baseline_m / range_m + shift_px;
  const std::string need =
      std::string("the disparity at the closest range flown, ") + Fixed(need_px, 1) + " px at " +
      Fixed(range_m, 1) + " m (" + range_from + "; f " + Fixed(fx_px, 1) + " px x baseline " +
      Fixed(baseline_m, 3) + " m from " + rig_from +
      (shift_px > 0.0 ? " + " + Fixed(shift_px, 1) + " px of sim.relative_rotation_error_rad"
                      : "") +
      ")";
  if (need_px + 1.0 > c.max_disparity_px) {
    *error = at + ": " + field + ": " + std::to_string(c.max_disparity_px) +
             (c.origins.keys.count(field) ? "" : " (the default)") + " is below " + need +
             " + 1 px for the sub-pixel fit";
    return false;
  }
  const int half_width = width_px / 2;
  if (need_px + 1.0 > half_width) {
    *error = at + ": " + field + ": the front end searches at most half the image width (" +
             std::to_string(half_width) + " px), below " + need +
             "; a shorter baseline, a wider field of view or a higher closest range";
    return false;
  }
  return true;
}

namespace {

bool Extends(const FswConfig& c, const char* source) {
  return c.extension != nullptr && std::strcmp(c.extension->source, source) == 0;
}

// Capacities compiled into the flight estimator (pipeline.hpp). The window holds window + 1 poses
// until the oldest is marginalized, or, held (hold_depth_precision), up to kMaxWindow + 1, and
// each can bring max_tracks landmarks the others do not see: beyond kMaxLandmarks new landmarks
// would be refused in flight (kFaultLandmarkCapacity). A hold needs room above the window and a
// mode that marginalizes a window of more than one pose.
bool CapacitiesHold(const FswConfig& c, const std::string& origin, std::string* error) {
  const bool held = c.hold_depth_precision > 0.0;
  if (held && (c.mode == "ekf" || c.mode == "vo")) {
    *error = ConfigWhere(c, "hold_depth_precision", origin) +
             ": hold_depth_precision: only in mode swf or vsdf (the EKF keeps one pose, VO "
             "deletes its oldest pose instead of marginalizing it)";
    return false;
  }
  if (held && c.window >= kMaxWindow) {
    *error = ConfigWhere(c, "hold_depth_precision", origin) +
             ": hold_depth_precision: cannot hold a pose beyond window " +
             std::to_string(c.window) + ": the compiled capacity kMaxWindow is " +
             std::to_string(kMaxWindow) + " (a window below it leaves the hold room)";
    return false;
  }
  const std::int64_t poses = static_cast<std::int64_t>(held ? kMaxWindow : c.window) + 1;
  const std::int64_t worst = poses * c.max_tracks;
  if (worst > kMaxLandmarks) {
    const std::string held_to =
        held ? "kMaxWindow " + std::to_string(kMaxWindow) + " (held: hold_depth_precision)"
             : "window " + std::to_string(c.window);
    *error = ConfigWhere(c, "max_tracks", origin) +
             ": max_tracks: " + std::to_string(c.max_tracks) + " with " + held_to + " can keep (" +
             std::to_string(poses - 1) + " + 1) x " + std::to_string(c.max_tracks) + " = " +
             std::to_string(worst) +
             " landmarks active, above the compiled capacity kMaxLandmarks = " +
             std::to_string(kMaxLandmarks) + " (at most " + std::to_string(kMaxLandmarks / poses) +
             " tracks at " + held_to + ")";
    return false;
  }
  // Marginalizing a pose moves every landmark it shares with the rest of the window into the
  // prior (eqs. 8-10); a frame's tracks are all such landmarks once the next frame tracks them.
  // A prior without room for them drops their measurements (kFaultPriorCapacity) on every frame.
  if (c.mode != "vo" && c.max_tracks > kMaxPriorLandmarks) {
    *error = ConfigWhere(c, "max_tracks", origin) +
             ": max_tracks: " + std::to_string(c.max_tracks) +
             " tracks can all enter the prior when their pose is "
             "marginalized, above the compiled prior capacity kMaxPriorLandmarks = " +
             std::to_string(kMaxPriorLandmarks) + " (mode vo keeps no prior)";
    return false;
  }
  return true;
}

}  // namespace

const char* SourceName(SourceKind kind) {
  switch (kind) {
    case SourceKind::kSim: return "sim";
    case SourceKind::kV4l2: return "v4l2";
    case SourceKind::kAravis: return "aravis";
    case SourceKind::kLog: return "log";
    case SourceKind::kLcm: return "lcm";
  }
  return "?";
}

int StageIndex(const std::string& name) {
  for (int i = 0; i < kNumStages; ++i) {
    if (name == StageName(i)) return i;
  }
  return -1;
}

bool ValidateConfig(const FswConfig& c, const std::string& origin, std::string* error) {
  auto fail = [&](const std::string& field, const std::string& why) {
    *error = ConfigWhere(c, field, origin) + ": " + field + ": " + why;
    return false;
  };
  if (c.source == SourceKind::kLog && c.log_path.empty()) {
    return fail("log.path", "required when source is log");
  }
  if ((c.source == SourceKind::kV4l2 || (c.source == SourceKind::kAravis && !c.camera.fake))) {
    if (c.camera.left.empty()) return fail("camera.left", "required for a camera source");
    if (c.camera.right.empty()) return fail("camera.right", "required for a camera source");
  }
  if (c.source == SourceKind::kLcm) {
    if (c.lcm_source.channel.empty()) {
      return fail("lcm_source.channel", "required when source is lcm");
    }
    if (c.lcm_source.url.empty() && c.lcm_url.empty()) {
      return fail("lcm_source.url", "empty, and so is lcm.url");
    }
    // Subscribing to one of this process's own outputs would take its messages for frames.
    for (const char* suffix : {kNavSuffix, kLandmarksSuffix, kHazardSuffix, kHealthSuffix}) {
      if (c.lcm_source.channel == c.channel_prefix + suffix) {
        return fail("lcm_source.channel",
                    Quoted(c.lcm_source.channel) + " is this process's own output channel");
      }
    }
    for (const char* field : {"camera.left", "camera.right", "camera.fake"}) {
      if (c.origins.keys.count(field) != 0) {
        return fail(field, "not for source lcm (the frames come from lcm_source.channel)");
      }
    }
  } else {
    for (const char* field : {"lcm_source.url", "lcm_source.channel", "lcm_source.buffers"}) {
      if (c.origins.keys.count(field) != 0) return fail(field, "only for source lcm");
    }
  }
  if (c.source == SourceKind::kV4l2 || c.source == SourceKind::kAravis ||
      c.source == SourceKind::kLcm) {
    if (c.camera.left_calibration.empty()) {
      return fail("camera.left_calibration", "required for a camera source");
    }
    if (c.camera.right_calibration.empty()) {
      return fail("camera.right_calibration", "required for a camera source");
    }
  }
  if (c.source != SourceKind::kAravis) {
    for (const char* field : {"camera.packet_size", "camera.trigger", "camera.trigger_source",
                              "camera.roi_offset_px"}) {
      if (c.origins.keys.count(field) != 0) return fail(field, "only for source aravis");
    }
    if (!c.camera.features.empty()) {
      return fail(kFeaturePrefix + c.camera.features.begin()->first, "only for source aravis");
    }
  }
  if (c.source != SourceKind::kAravis && c.source != SourceKind::kV4l2) {
    for (const char* field : {"camera.exposure_us", "camera.gain"}) {
      if (c.origins.keys.count(field) != 0) return fail(field, "only for a camera source");
    }
  }
  if (c.camera.fake && c.camera.trigger == "hardware") {
    return fail("camera.trigger", "hardware: the fake cameras have no trigger line");
  }
  if (c.source == SourceKind::kV4l2 && c.camera.fake) {
    return fail("camera.fake", "only for source aravis (v4l2 tests script the kernel)");
  }
  if (c.source == SourceKind::kV4l2 && c.camera.left == c.camera.right) {
    return fail("camera.right", "the same device as camera.left");
  }
  if (c.mode == "ekf" && c.window != 1) return fail("window", "must be 1 in mode ekf");
  // The per-track sigma grows with the template's warp, which the front end measures from the
  // estimator's reference pose of the template's frame; without it tracks started without a
  // prediction follow frame-to-frame LK, drift, and report no warp: stated at the bare
  // measurement_sigma_px.
  const bool warp_term = c.measurement_sigma_per_magnification_px > 0.0 ||
                         c.measurement_sigma_per_magnification_rad > 0.0;
  if (warp_term && !c.frontend_reference_from_estimate) {
    return fail(c.measurement_sigma_per_magnification_rad > 0.0
                    ? "measurement_sigma_per_magnification_rad"
                    : "measurement_sigma_per_magnification_px",
                "needs frontend.reference_from_estimate: true (the template's warp is measured "
                "from the estimator's reference pose)");
  }
  if (c.measurement_track_error_shared && !warp_term) {
    return fail("measurement_track_error",
                "shared: needs measurement_sigma_per_magnification_px or _rad > 0 (the shared "
                "part is the warp-grown one)");
  }
  if (c.vsdf_scalar_diagonal && c.mode != "vsdf") {
    return fail("vsdf.schur", "diagonal: only in mode vsdf (how the VSDF marginalizes)");
  }
  if (c.source == SourceKind::kSim && !Extends(c, "sim")) {
    return fail("source",
                "'sim' is the simulated descent, flown by swf-sil (this program flies "
                "v4l2, aravis, log and lcm)");
  }
  if (c.initial == "truth" && c.source != SourceKind::kSim && c.source != SourceKind::kLog) {
    return fail("initial", "'truth' needs the simulator (source sim, or a log of a sim run)");
  }
  if (c.initial == "truth" && !Extends(c, "sim")) {
    return fail("initial",
                "'truth' is the simulator's: swf-sil, or swf-replay for a log of a "
                "simulated descent (the flight process starts from initial.position_m)");
  }
  if (c.imu.enabled && c.sim.imu_unit == "none" && !(c.imu.rate_hz >= 10.0)) {
    return fail("imu.rate_hz", "must be at least 10 Hz for the stereo-inertial estimator");
  }
  // The first state's prior: a zero sigma would be infinite information.
  if (c.imu.enabled && !(c.imu.max_time_offset_ms > 0.0 &&
                         std::abs(c.imu.time_offset_ms) <= c.imu.max_time_offset_ms)) {
    return fail("imu.time_offset_ms", "must be within +-imu.max_time_offset_ms (positive)");
  }
  if (c.imu.enabled && !(c.imu.velocity_sigma_mps > 0.0)) {
    return fail("imu.velocity_sigma_mps", "must be positive (the prior of the first velocity)");
  }
  if (c.inject_ms > 0.0 && c.inject_stage.empty()) {
    return fail("inject.stage", "required when inject.ms is set");
  }
  if (c.publish && c.lcm_url.empty()) return fail("lcm.url", "empty while lcm.publish is true");
  if (c.channel_prefix.size() > 32) return fail("lcm.channel_prefix", "longer than 32 characters");
  if (!CapacitiesHold(c, origin, error)) return false;
  return c.extension == nullptr || c.extension->validate(c, origin, error);
}

bool CheckEnvelopeDisparity(const FswConfig& c, double fx_px, double baseline_m, int width_px,
                            std::string* error) {
  const std::string origin = c.origins.file.empty() ? "configuration" : c.origins.file;
  double range_m = 0.0;
  std::string range_from;
  if (c.source == SourceKind::kSim) return c.extension->envelope_fits(c, fx_px, origin, error);
  if (c.envelope_min_range_m > 0.0) {
    range_m = c.envelope_min_range_m;
    range_from = "envelope.min_range_m";
  } else if (c.source == SourceKind::kLog) {
    return true;  // a replay re-runs recorded frames; the flight was checked when it flew
  } else {
    *error = ConfigWhere(c, "envelope.min_range_m", origin) +
             ": envelope.min_range_m: required for a camera source: the closest range (m) the "
             "flight reaches, to check max_disparity_px against f x baseline = " +
             Fixed(fx_px * baseline_m, 1) + " px m";
    return false;
  }
  return DisparityFits(c, fx_px, baseline_m, width_px, range_m, range_from, "the rectified rig",
                       origin, error);
}

namespace {

// "" when the directory `dir` exists and this process may write it, or does not exist yet and can
// be created (its nearest existing ancestor is a directory this process may write: the run
// creates the missing ones, docs/cli.md); otherwise why not. stat(2) and access(2) only.
std::string WhyNotWritableDirectory(const std::string& dir) {
  std::string probe = dir;
  for (;;) {
    struct stat st {};
    if (::stat(probe.c_str(), &st) == 0) {
      if (!S_ISDIR(st.st_mode)) {
        return probe == dir ? std::string("is not a directory")
                            : Quoted(probe).append(" is not a directory");
      }
      if (::access(probe.c_str(), W_OK | X_OK) != 0) {
        const int e = errno;
        std::string why;
        if (probe != dir) {
          why = Quoted(probe);
          why.append(" cannot be written (to create ").append(Quoted(dir)).append(" in it): ");
        } else {
          why = "cannot be written: ";
        }
        return why.append(std::strerror(e));
      }
      return "";
    }
    // ENOTDIR: a component is a file (found when the walk reaches it).
    if ((errno != ENOENT && errno != ENOTDIR) || probe == "." || probe == "/") {
      return Quoted(probe).append(" cannot be examined: ").append(std::strerror(errno));
    }
    // Up one level: "a/b" -> "a", "/a" -> "/", "a" -> ".".
    const auto slash = probe.find_last_of('/');
    if (slash == std::string::npos) {
      probe.assign(1, '.');
    } else {
      probe.resize(slash == 0 ? 1 : slash);
    }
  }
}

// "" when this process may write the file `path` (an existing non-directory file, or a new file
// in a directory WhyNotWritableDirectory accepts), otherwise why not.
std::string WhyNotWritableFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return "is a directory";
    if (::access(path.c_str(), W_OK) != 0)
      return std::string("cannot be written: ") + std::strerror(errno);
    return "";
  }
  if (errno != ENOENT && errno != ENOTDIR) {
    return std::string("cannot be examined: ") + std::strerror(errno);
  }
  const auto slash = path.find_last_of('/');
  const std::string dir =
      slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const std::string why = WhyNotWritableDirectory(dir);
  if (why.empty()) return why;
  // The directory itself ("its directory 'd' is not a directory") or an ancestor named in `why`.
  return why[0] == '\'' ? std::string("its directory: ").append(why)
                        : std::string("its directory ").append(Quoted(dir)).append(" ").append(why);
}

// Reads a configuration file: a regular file of at most kMaxConfigBytes (a directory opens and
// reads as empty on Linux, a device or FIFO may never end).
bool ReadConfigFile(const std::string& path, std::string* text, std::string* error) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    *error = Excerpt(path) + ": cannot open the configuration file: " + std::strerror(errno);
    return false;
  }
  if (S_ISDIR(st.st_mode)) {
    *error = Excerpt(path) + ": is a directory, not a configuration file";
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    *error = Excerpt(path) + ": is not a regular file";
    return false;
  }
  if (static_cast<std::uint64_t>(st.st_size) > kMaxConfigBytes) {
    *error = Excerpt(path) + ": " + std::to_string(st.st_size) + " bytes, larger than the " +
             std::to_string(kMaxConfigBytes) + " a configuration may have";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = Excerpt(path) + ": cannot open the configuration file";
    return false;
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  *text = buffer.str();
  if (text->size() > kMaxConfigBytes) {  // grew after stat
    *error = Excerpt(path) + ": larger than " + std::to_string(kMaxConfigBytes) + " bytes";
    return false;
  }
  return true;
}

}  // namespace

bool CheckOutputPaths(const FswConfig& c, std::string* error) {
  const std::string origin = c.origins.file.empty() ? "configuration" : c.origins.file;
  auto fail = [&](const char* field, const std::string& path, const std::string& why) {
    *error = ConfigWhere(c, field, origin) + ": " + field + ": " + Quoted(path) + " " + why;
    return false;
  };
  if (!c.summary_path.empty()) {
    const std::string why = WhyNotWritableFile(c.summary_path);
    if (!why.empty()) return fail("summary.path", c.summary_path, why);
  }
  if (!c.record_path.empty()) {
    const std::string why = WhyNotWritableFile(c.record_path);
    if (!why.empty()) return fail("record.path", c.record_path, why);
    if (c.record_path == c.summary_path) {
      return fail("record.path", c.record_path, "is also summary.path");
    }
  }
  if (!c.plot_dir.empty()) {
    const std::string why = WhyNotWritableDirectory(c.plot_dir);
    if (!why.empty()) return fail("summary.plot_dir", c.plot_dir, why);
  }
  return true;
}

bool MakeOutputDirectories(const FswConfig& c, std::string* error) {
  return cli::MakeParentDirectories(c.summary_path, error) &&
         cli::MakeParentDirectories(c.record_path, error) &&
         cli::MakeDirectories(c.plot_dir, error);
}

bool ParseConfig(const std::string& text, const std::string& origin, FswConfig* config,
                 std::string* error, const ConfigExtension* extension) {
  FswConfig c;
  c.extension = extension;
  if (!ApplyFileText(text, origin, &c, error)) return false;
  if (!ValidateConfig(c, origin, error)) return false;
  *config = c;
  return true;
}

bool LoadConfig(const std::string& path, FswConfig* config, std::string* error,
                const ConfigExtension* extension) {
  std::string text;
  if (!ReadConfigFile(path, &text, error)) return false;
  return ParseConfig(text, path, config, error, extension);
}

bool LoadConfig(const std::string& path, const std::vector<std::string>& overrides,
                FswConfig* config, std::string* error, const ConfigExtension* extension) {
  std::string text;
  if (!ReadConfigFile(path, &text, error)) return false;
  FswConfig c;
  c.extension = extension;
  if (!ApplyFileText(text, path, &c, error)) return false;
  for (const std::string& o : overrides) {
    if (!ApplyOverride(o, &c, error)) return false;
  }
  if (!ValidateConfig(c, path, error)) return false;
  *config = c;
  return true;
}

bool OverrideConfig(const std::string& key_value, FswConfig* config, std::string* error) {
  FswConfig c = *config;
  if (!ApplyOverride(key_value, &c, error)) return false;
  if (!ValidateConfig(c, "--set", error)) return false;
  *config = c;
  return true;
}

}  // namespace swf::app
