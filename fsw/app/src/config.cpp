#include "swf/app/config.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
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

#include "swf/app/sim_world.hpp"
#include "swf/sim/rig.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::app {

namespace {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

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

// Each field: a setter that parses the text value or writes why not.
using Setter = std::function<bool(const std::string& value, FswConfig* c, std::string* why)>;

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

Setter Double(double FswConfig::*field, double lo, double hi) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    double d = 0.0;
    if (!ParseDouble(v, &d, why)) return false;
    if (d < lo || d > hi) {
      std::ostringstream o;
      o << Excerpt(v) << " is outside [" << lo << ", " << hi << "]";
      *why = o.str();
      return false;
    }
    c->*field = d;
    return true;
  };
}

// `limit_note` says where a compiled limit comes from.
template <typename T, typename Get>
Setter Int(Get get, std::int64_t lo, std::int64_t hi, const char* limit_note = "") {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    std::int64_t i = 0;
    if (!ParseInt(v, &i, why)) return false;
    if (i < lo || i > hi) {
      *why = Excerpt(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]" +
             limit_note;
      return false;
    }
    *get(c) = static_cast<T>(i);
    return true;
  };
}

template <typename Get>
Setter Bool(Get get) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    if (v == "true" || v == "yes" || v == "1") {
      *get(c) = true;
    } else if (v == "false" || v == "no" || v == "0") {
      *get(c) = false;
    } else {
      *why = Quoted(v) + " is not true/false";
      return false;
    }
    return true;
  };
}

template <typename Get>
Setter Text(Get get) {
  return [=](const std::string& v, FswConfig* c, std::string*) {
    *get(c) = v;
    return true;
  };
}

template <typename Get>
Setter OneOf(Get get, std::initializer_list<const char*> allowed) {
  std::vector<std::string> options(allowed.begin(), allowed.end());
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    for (const std::string& o : options) {
      if (v == o) {
        *get(c) = v;
        return true;
      }
    }
    *why = Quoted(v) + " is not one of";
    for (const std::string& o : options) *why += " " + o;
    return false;
  };
}

// Three finite numbers ("x y z" or "x, y, z") into field[3].
template <typename Get>
Setter Vector3(Get get) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    std::string spaced = v;
    for (char& ch : spaced) ch = ch == ',' ? ' ' : ch;
    std::istringstream in(spaced);
    double p[3];
    std::string rest;
    if (!(in >> p[0] >> p[1] >> p[2]) || (in >> rest) || !std::isfinite(p[0]) ||
        !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      *why = Quoted(v) + " is not three finite numbers (x y z)";
      return false;
    }
    for (int i = 0; i < 3; ++i) get(c)[i] = p[i];
    return true;
  };
}

// "[lo, hi]", with "(" when the low end is excluded.
std::string Interval(double lo, double hi, bool lo_open) {
  std::ostringstream o;
  o << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
  return o.str();
}

bool InInterval(double d, double lo, double hi, bool lo_open) {
  return (lo_open ? d > lo : d >= lo) && d <= hi;
}

// A finite number into a member of SimConfig, inside [lo, hi] (or (lo, hi]).
Setter SimNumber(double SimConfig::*field, double lo, double hi, bool lo_open = false) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    double d = 0.0;
    if (!ParseDouble(v, &d, why)) return false;
    if (!InInterval(d, lo, hi, lo_open)) {
      *why = Excerpt(v) + " is outside " + Interval(lo, hi, lo_open);
      return false;
    }
    c->sim.*field = d;
    return true;
  };
}

// N finite numbers ("a b" or "a, b") into a member array of SimConfig, each inside [lo, hi];
// `names` says what they are ("vx, vy").
template <int N>
Setter SimNumbers(double (SimConfig::*field)[N], double lo, double hi, const char* names) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    std::string spaced = v;
    for (char& ch : spaced) ch = ch == ',' ? ' ' : ch;
    std::istringstream in(spaced);
    double p[N];
    for (double& x : p) {
      if (!(in >> x) || !std::isfinite(x)) {
        *why = Quoted(v) + " is not " + std::to_string(N) + " finite numbers (" + names + ")";
        return false;
      }
    }
    std::string rest;
    if (in >> rest) {
      *why = Quoted(v) + " is not " + std::to_string(N) + " finite numbers (" + names + ")";
      return false;
    }
    for (const double x : p) {
      if (!InInterval(x, lo, hi, false)) {
        std::ostringstream o;
        o << Excerpt(v) << ": " << x << " is outside " << Interval(lo, hi, false);
        *why = o.str();
        return false;
      }
    }
    for (int i = 0; i < N; ++i) (c->sim.*field)[i] = p[i];
    return true;
  };
}

// A non-negative finite number into a member of ImuConfig, at most hi.
Setter ImuNumber(double ImuConfig::*field, double hi) {
  return [=](const std::string& v, FswConfig* c, std::string* why) {
    double d = 0.0;
    if (!ParseDouble(v, &d, why)) return false;
    if (d < 0.0 || d > hi) {
      std::ostringstream o;
      o << Excerpt(v) << " is outside [0, " << hi << "]";
      *why = o.str();
      return false;
    }
    c->imu.*field = d;
    return true;
  };
}

// The dispersions of the simulated flight (SimConfig; their consistency is checked in
// DispersionsHold).
void AddDispersionFields(std::map<std::string, Setter>* fields) {
  std::map<std::string, Setter>& f = *fields;
  f["sim.start_altitude_m"] = SimNumber(&SimConfig::start_altitude_m, 0.0, 1000.0, true);
  f["sim.end_altitude_m"] = SimNumber(&SimConfig::end_altitude_m, 0.0, 1000.0, true);
  f["sim.descent_rate_mps"] = SimNumber(&SimConfig::descent_rate_mps, 0.0, 100.0, true);
  f["sim.horizontal_velocity_mps"] =
      SimNumbers<2>(&SimConfig::horizontal_velocity_mps, -100.0, 100.0, "vx, vy");
  f["sim.attitude_deg"] =
      SimNumbers<3>(&SimConfig::attitude_deg, -180.0, 180.0, "roll, pitch, yaw");
  f["sim.attitude_rate_dps"] =
      SimNumbers<3>(&SimConfig::attitude_rate_dps, -100.0, 100.0, "roll, pitch, yaw rates");
  // The appearance's own limits (sim/appearance.hpp): a sun on or below the horizon lights
  // nothing.
  f["sim.sun_elevation_deg"] = SimNumber(&SimConfig::sun_elevation_deg, 0.0, 90.0, true);
  f["sim.sun_azimuth_deg"] = SimNumber(&SimConfig::sun_azimuth_deg, -360.0, 360.0);
  f["sim.read_noise_e"] = SimNumber(&SimConfig::read_noise_e, 0.0, 10000.0);
  f["sim.e_per_dn"] = SimNumber(&SimConfig::e_per_dn, 0.0, 100000.0, true);
  f["sim.exposure_dn"] = SimNumber(&SimConfig::exposure_dn, 0.0, 1000.0, true);
  f["sim.baseline_error_m"] = SimNumber(&SimConfig::baseline_error_m, -100.0, 100.0);
  // Small: a calibration error, not another rig (0.1 rad moves the right image by 10 % of f).
  f["sim.relative_rotation_error_rad"] =
      SimNumbers<3>(&SimConfig::relative_rotation_error_rad, -0.1, 0.1, "rx, ry, rz");
  f["sim.frame_drop_probability"] = [](const std::string& v, FswConfig* c, std::string* why) {
    double d = 0.0;
    if (!ParseDouble(v, &d, why)) return false;
    if (!(d >= 0.0 && d < 1.0)) {
      *why = Excerpt(v) + " is outside [0, 1)";
      return false;
    }
    c->sim.frame_drop_probability = d;
    return true;
  };
  f["sim.timestamp_jitter_ms"] = SimNumber(&SimConfig::timestamp_jitter_ms, 0.0, 1000.0);
}

const std::map<std::string, Setter>& Fields() {
  static const std::map<std::string, Setter> kFields = [] {
    std::map<std::string, Setter> f;
    f["source"] = [](const std::string& v, FswConfig* c, std::string* why) {
      if (v == "sim")
        c->source = SourceKind::kSim;
      else if (v == "v4l2")
        c->source = SourceKind::kV4l2;
      else if (v == "aravis")
        c->source = SourceKind::kAravis;
      else if (v == "log")
        c->source = SourceKind::kLog;
      else {
        *why = Quoted(v) + " is not one of sim v4l2 aravis log";
        return false;
      }
      return true;
    };
    f["log.path"] = Text([](FswConfig* c) { return &c->log_path; });
    f["sim.scenario"] = OneOf([](FswConfig* c) { return &c->sim.scenario; },
                              {"descent", "hover", "sideways", "lab"});
    f["sim.terrain"] =
        OneOf([](FswConfig* c) { return &c->sim.terrain; }, {"plains", "craters", "rocks"});
    f["sim.width_px"] = Int<std::int32_t>([](FswConfig* c) { return &c->sim.width_px; }, 32,
                                          frontend::kMaxImageWidth);
    f["sim.height_px"] = Int<std::int32_t>([](FswConfig* c) { return &c->sim.height_px; }, 32,
                                           frontend::kMaxImageHeight);
    f["sim.hfov_deg"] = [](const std::string& v, FswConfig* c, std::string* why) {
      double d = 0;
      if (!ParseDouble(v, &d, why)) return false;
      if (!(d > 1.0 && d < 170.0)) {
        *why = Excerpt(v) + " is outside (1, 170)";
        return false;
      }
      c->sim.hfov_deg = d;
      return true;
    };
    f["sim.baseline_m"] = [](const std::string& v, FswConfig* c, std::string* why) {
      double d = 0;
      if (!ParseDouble(v, &d, why)) return false;
      if (!(d > 0.0 && d <= 100.0)) {
        *why = Excerpt(v) + " is outside (0, 100]";
        return false;
      }
      c->sim.baseline_m = d;
      return true;
    };
    f["sim.frames"] = Int<std::int32_t>([](FswConfig* c) { return &c->sim.frames; }, 0, 100000);
    f["sim.terrain_size"] =
        Int<std::int32_t>([](FswConfig* c) { return &c->sim.terrain_size; }, 64, 8192);
    f["sim.seed"] =
        Int<std::uint64_t>([](FswConfig* c) { return &c->sim.seed; }, 0, std::int64_t{1} << 62);
    f["sim.shared"] = Text([](FswConfig* c) { return &c->sim.shared_dir; });
    f["sim.render_threads"] =
        Int<std::int32_t>([](FswConfig* c) { return &c->sim.render_threads; }, 1, 64);
    f["sim.imu"] = Bool([](FswConfig* c) { return &c->sim.imu; });
    f["sim.imu_sigma_m"] = [](const std::string& v, FswConfig* c, std::string* why) {
      double d = 0;
      if (!ParseDouble(v, &d, why)) return false;
      if (d < 0.0 || d > 10.0) {
        *why = Excerpt(v) + " is outside [0, 10]";
        return false;
      }
      c->sim.imu_sigma_m = d;
      return true;
    };
    f["sim.imu_sigma_rad"] = [](const std::string& v, FswConfig* c, std::string* why) {
      double d = 0;
      if (!ParseDouble(v, &d, why)) return false;
      if (d < 0.0 || d > 0.5) {
        *why = Excerpt(v) + " is outside [0, 0.5]";
        return false;
      }
      c->sim.imu_sigma_rad = d;
      return true;
    };
    f["sim.imu_unit"] =
        OneOf([](FswConfig* c) { return &c->sim.imu_unit; }, {"none", "mems", "tactical"});
    AddDispersionFields(&f);
    f["imu.enabled"] = Bool([](FswConfig* c) { return &c->imu.enabled; });
    f["imu.static_start"] = Bool([](FswConfig* c) { return &c->imu.static_start; });
    f["imu.channel"] = Text([](FswConfig* c) { return &c->imu.channel; });
    f["imu.rate_hz"] = ImuNumber(&ImuConfig::rate_hz, 10000.0);
    f["imu.gyro_noise_density"] = ImuNumber(&ImuConfig::gyro_noise_density, 1.0);
    f["imu.gyro_random_walk"] = ImuNumber(&ImuConfig::gyro_random_walk, 1.0);
    f["imu.accel_noise_density"] = ImuNumber(&ImuConfig::accel_noise_density, 10.0);
    f["imu.accel_random_walk"] = ImuNumber(&ImuConfig::accel_random_walk, 10.0);
    f["imu.gyro_range_radps"] = ImuNumber(&ImuConfig::gyro_range_radps, 1000.0);
    f["imu.accel_range_mps2"] = ImuNumber(&ImuConfig::accel_range_mps2, 10000.0);
    f["imu.gravity_mps2"] = ImuNumber(&ImuConfig::gravity_mps2, 100.0);
    f["imu.gyro_bias_sigma_radps"] = ImuNumber(&ImuConfig::gyro_bias_sigma_radps, 10.0);
    f["imu.accel_bias_sigma_mps2"] = ImuNumber(&ImuConfig::accel_bias_sigma_mps2, 100.0);
    f["imu.camera_t_imu_m"] = Vector3([](FswConfig* c) { return c->imu.camera_t_imu_m; });
    f["imu.camera_r_imu_rad"] = Vector3([](FswConfig* c) { return c->imu.camera_r_imu_rad; });
    f["imu.initial_velocity_mps"] =
        Vector3([](FswConfig* c) { return c->imu.initial_velocity_mps; });
    f["sim.target"] = OneOf([](FswConfig* c) { return &c->sim.target; }, {"nominal", "orbital"});
    f["sim.target_search_m"] = [](const std::string& v, FswConfig* c, std::string* why) {
      double d = 0.0;
      if (!ParseDouble(v, &d, why)) return false;
      // 60 m keeps the search square (plus the 10 m clearance cap) and the 100 m view inside the
      // 204.8 m terrain.
      if (d < 0.0 || d > 60.0) {
        *why = Excerpt(v) + " is outside [0, 60]";
        return false;
      }
      c->sim.target_search_m = d;
      return true;
    };
    f["camera.left"] = Text([](FswConfig* c) { return &c->camera.left; });
    f["camera.right"] = Text([](FswConfig* c) { return &c->camera.right; });
    f["camera.left_calibration"] = Text([](FswConfig* c) { return &c->camera.left_calibration; });
    f["camera.right_calibration"] = Text([](FswConfig* c) { return &c->camera.right_calibration; });
    f["camera.fake"] = Bool([](FswConfig* c) { return &c->camera.fake; });
    f["camera.format"] =
        OneOf([](FswConfig* c) { return &c->camera.format; }, {"grey", "y16", "yuyv"});
    // The V4L2 source holds up to 2 pairs and the kernel needs 2 more buffers to keep streaming.
    f["camera.buffers"] = Int<std::int32_t>([](FswConfig* c) { return &c->camera.buffers; }, 4, 16);
    f["camera.pair_tolerance_ms"] = [](const std::string& v, FswConfig* c, std::string* why) {
      double d = 0;
      if (!ParseDouble(v, &d, why)) return false;
      if (!(d >= 0.0 && d <= 1000.0)) {
        *why = Excerpt(v) + " is outside [0, 1000]";
        return false;
      }
      c->camera.pair_tolerance_ms = d;
      return true;
    };
    f["mode"] = OneOf([](FswConfig* c) { return &c->mode; }, {"swf", "ekf", "vo", "vsdf"});
    f["window"] = Int<std::int32_t>([](FswConfig* c) { return &c->window; }, 1, kMaxWindow,
                                    " (kMaxWindow, the filter's compiled window capacity)");
    f["max_iterations"] =
        Int<std::int32_t>([](FswConfig* c) { return &c->max_iterations; }, 1, 100);
    f["measurement_sigma_px"] = Double(&FswConfig::measurement_sigma_px, 1e-3, 100.0);
    f["min_quality"] = Double(&FswConfig::min_quality, -1.0, 1.0);
    f["process_sigma_m"] = Double(&FswConfig::process_sigma_m, 1e-6, 1e3);
    f["process_sigma_rad"] = Double(&FswConfig::process_sigma_rad, 1e-8, 3.0);
    f["calibration.baseline_sigma_m"] = Double(&FswConfig::calibration_baseline_sigma_m, 0.0, 1.0);
    f["calibration.disparity_sigma_px"] =
        Double(&FswConfig::calibration_disparity_sigma_px, 0.0, 10.0);
    f["max_tracks"] = Int<std::int32_t>([](FswConfig* c) { return &c->max_tracks; }, 8,
                                        static_cast<std::int64_t>(frontend::kMaxTracks),
                                        " (frontend::kMaxTracks, the compiled track capacity)");
    f["max_disparity_px"] = Int<std::int32_t>([](FswConfig* c) { return &c->max_disparity_px; }, 8,
                                              frontend::kMaxDisparity);
    f["rate_hz"] = Double(&FswConfig::rate_hz, 0.1, 1000.0);
    f["pacing"] = [](const std::string& v, FswConfig* c, std::string* why) {
      if (v == "realtime")
        c->pacing = Pacing::kRealtime;
      else if (v == "lockstep")
        c->pacing = Pacing::kLockstep;
      else {
        *why = Quoted(v) + " is not one of realtime lockstep";
        return false;
      }
      return true;
    };
    f["hazard_every"] = Int<std::int32_t>([](FswConfig* c) { return &c->hazard_every; }, 1, 100000);
    f["hazard.max_disparities"] =
        Int<std::int32_t>([](FswConfig* c) { return &c->hazard_max_disparities; }, 16, 256);
    f["hazard.downsample"] = [](const std::string& v, FswConfig* c, std::string* why) {
      if (v == "1" || v == "2" || v == "4") {
        c->hazard_downsample = v[0] - '0';
        return true;
      }
      *why = Quoted(v) + " is not one of 1 2 4";
      return false;
    };
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
    f["inject.black_from"] = Int<std::int64_t>([](FswConfig* c) { return &c->inject_black_from; },
                                               -1, std::int64_t{1} << 40);
    f["inject.black_frames"] = Int<std::int64_t>(
        [](FswConfig* c) { return &c->inject_black_frames; }, 1, std::int64_t{1} << 40);
    f["envelope.min_range_m"] = [](const std::string& v, FswConfig* c, std::string* why) {
      double d = 0.0;
      if (!ParseDouble(v, &d, why)) return false;
      if (!(d > 0.0 && d <= 1e6)) {
        *why = Excerpt(v) + " is outside (0, 1e6]";
        return false;
      }
      c->envelope_min_range_m = d;
      return true;
    };
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

bool SetField(const std::string& key, const std::string& value, const std::string& where,
              FswConfig* config, std::string* error) {
  const auto& fields = Fields();
  const auto it = fields.find(key);
  if (it == fields.end()) {
    *error = where + ": " + Excerpt(key) + ": unknown field";
    return false;
  }
  std::string why;
  if (!it->second(value, config, &why)) {
    *error = where + ": " + key + ": " + why;
    return false;
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
  return true;
}

// Where the error about `field` points: the line (or --set) that set it; the file when the field
// kept its default.
std::string Where(const FswConfig& c, const std::string& field, const std::string& origin) {
  const auto it = c.origins.keys.find(field);
  if (it != c.origins.keys.end()) return it->second;
  return c.origins.file.empty() ? origin : c.origins.file;
}

std::string Fixed(double v, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

// How the simulated camera sees the datum z = 0 over its trajectory (its attitude without the
// 0.1 deg jitter: SteeredAttitude, sim/trajectory.hpp).
struct SimView {
  // The closest range: the smallest camera-frame depth of the datum anywhere in the image over
  // the flight. For a nadir camera that is the lowest camera height above the datum; tilted, the
  // image corner nearest the ground sees it closer: depth = height / max over the image of
  // (camera-frame down . (xn, yn, 1)), a linear function of (xn, yn) whose maximum is at a corner.
  double closest_depth_m = 0.0;
  double max_tilt_rad = 0.0;  // of the optical axis from nadir
  bool tilted = false;        // the attitude is not nadir (sim.attitude_*)
};

// Terrain relief (0.5 m rms) and rocks (up to 1.25 m) bring ground closer than the datum and are
// not included (building the terrain takes seconds), so the check is necessary, not sufficient,
// and max_disparity_px wants margin above it.
bool SimViewOf(const FswConfig& c, SimView* view, std::string* error) {
  FswConfig nominal = c;
  // `sim.target: orbital` only moves the descent sideways (SimTrajectory adds the target's x and y
  // to the start) and needs the terrain to say where: its altitudes are the nominal ones.
  nominal.sim.target = "nominal";
  sim::Trajectory trajectory;
  sim::RigOptions rig;
  if (!SimTrajectory(nominal, &trajectory, &rig, error)) return false;
  const estimator::StereoCamera<double> camera = sim::MakeStereoCamera(rig);
  const double corner_x = 0.5 * rig.width_px / camera.fx;  // pixel edges, not centres
  const double corner_y = 0.5 * rig.height_px / camera.fy;
  const sim::TrajectoryOptions& o = trajectory.Options();
  view->closest_depth_m = std::numeric_limits<double>::infinity();
  view->max_tilt_rad = 0.0;
  view->tilted =
      !((o.attitude_offset_rad.array() == 0.0).all() && (o.body_rate_radps.array() == 0.0).all());
  for (std::int32_t k = 0; k < trajectory.NumFrames(); ++k) {
    const Eigen::Vector3d down =
        sim::SteeredAttitude(o, k / o.rate_hz).transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
    const double nearest = down.z() + std::abs(down.x()) * corner_x + std::abs(down.y()) * corner_y;
    const double height_m = trajectory.WorldTCamera(k).t.z();
    view->closest_depth_m = std::min(view->closest_depth_m, height_m / nearest);
    view->max_tilt_rad = std::max(view->max_tilt_rad, std::acos(std::clamp(down.z(), -1.0, 1.0)));
  }
  return true;
}

// The settings the simulated rig comes from (an override changing one shows up here).
std::string SimRigFrom(const FswConfig& c) {
  std::ostringstream o;
  o << "sim.width_px " << c.sim.width_px << ", sim.hfov_deg " << c.sim.hfov_deg
    << ", sim.baseline_m " << c.sim.baseline_m;
  if (c.sim.baseline_error_m != 0.0) o << " + sim.baseline_error_m " << c.sim.baseline_error_m;
  return o.str();
}

// The front end finds a feature's match only within its search, min(max_disparity_px, width / 2)
// (app.cpp FrontendFor), and its sub-pixel fit needs the cost one disparity beyond the minimum: the
// disparity of the closest ground, f b / range, must stay at least 1 px inside. Beyond it every
// close feature is matched to a wrong disparity or not at all, and the estimate diverges while
// reporting ok (demo at 1024 px with max_disparity_px 160: 231 px at 10 m, landmark RMS 6570 m).
// `shift_px`: a disparity the right image adds at every range (the simulator's rotation error).
bool DisparityFits(const FswConfig& c, double fx_px, double baseline_m, int width_px,
                   double range_m, const std::string& range_from, const std::string& rig_from,
                   const std::string& origin, std::string* error, double shift_px = 0.0) {
  const std::string field = "max_disparity_px";
  const std::string at = Where(c, field, origin);
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

// The simulator's flown envelope: the disparity the front end must find in the true images, at
// the closest range over the trajectory (SimViewOf), with the true baseline (sim.baseline_m +
// sim.baseline_error_m) and f of the calibration `fx_px`; a rotation error of the right camera
// shifts the right image by up to f |ry| + |rz| (larger image side) / 2 px on top.
bool SimEnvelopeFits(const FswConfig& c, double fx_px, const std::string& origin,
                     std::string* error) {
  SimView view;
  std::string why;
  if (!SimViewOf(c, &view, &why)) {
    *error = Where(c, "sim.scenario", origin) + ": " + why;
    return false;
  }
  const double* r = c.sim.relative_rotation_error_rad;
  const double shift_px =
      fx_px * std::abs(r[1]) + std::abs(r[2]) * 0.5 * std::max(c.sim.width_px, c.sim.height_px);
  const std::string range_from =
      view.tilted ? std::string("the closest datum depth in view over the tilted sim.") +
                        c.sim.scenario + " trajectory"
                  : std::string("the lowest altitude of the sim.") + c.sim.scenario + " trajectory";
  return DisparityFits(c, fx_px, c.sim.baseline_m + c.sim.baseline_error_m, c.sim.width_px,
                       view.closest_depth_m, range_from, SimRigFrom(c), origin, error, shift_px);
}

// Capacities compiled into the flight estimator (pipeline.hpp). The window holds window + 1 poses
// until the oldest is marginalized, and each can bring max_tracks landmarks the others do not see:
// beyond kMaxLandmarks new landmarks would be refused in flight (kFaultLandmarkCapacity).
bool CapacitiesHold(const FswConfig& c, const std::string& origin, std::string* error) {
  const std::int64_t poses = static_cast<std::int64_t>(c.window) + 1;
  const std::int64_t worst = poses * c.max_tracks;
  if (worst > kMaxLandmarks) {
    *error = Where(c, "max_tracks", origin) + ": max_tracks: " + std::to_string(c.max_tracks) +
             " with window " + std::to_string(c.window) + " can keep (" + std::to_string(c.window) +
             " + 1) x " + std::to_string(c.max_tracks) + " = " + std::to_string(worst) +
             " landmarks active, above the compiled capacity kMaxLandmarks = " +
             std::to_string(kMaxLandmarks) + " (at most " + std::to_string(kMaxLandmarks / poses) +
             " tracks at window " + std::to_string(c.window) + ")";
    return false;
  }
  return true;
}

// The descent geometry keys other than the nominal flight's: they shape the descent preset only.
const char* DescentKeyChanged(const SimConfig& s) {
  const SimConfig nominal;
  if (s.start_altitude_m != nominal.start_altitude_m) return "sim.start_altitude_m";
  if (s.end_altitude_m != nominal.end_altitude_m) return "sim.end_altitude_m";
  if (s.descent_rate_mps != nominal.descent_rate_mps) return "sim.descent_rate_mps";
  for (const double v : s.horizontal_velocity_mps)
    if (v != 0.0) return "sim.horizontal_velocity_mps";
  for (const double a : s.attitude_deg)
    if (a != 0.0) return "sim.attitude_deg";
  for (const double w : s.attitude_rate_dps)
    if (w != 0.0) return "sim.attitude_rate_dps";
  return nullptr;
}

// "<where>: <field>: <why>" into `error`; false.
bool Refuse(const FswConfig& c, const std::string& field, const std::string& origin,
            const std::string& why, std::string* error) {
  *error = Where(c, field, origin) + ": " + field + ": " + why;
  return false;
}

// The descent geometry: for the descent only, ending below its start, a bounded frame count.
bool DescentHolds(const FswConfig& c, const std::string& origin, std::string* error) {
  const SimConfig& s = c.sim;
  if (const char* key = DescentKeyChanged(s); key != nullptr && s.scenario != "descent") {
    return Refuse(c, key, origin, "shapes the descent: needs sim.scenario descent", error);
  }
  if (!(s.end_altitude_m < s.start_altitude_m)) {
    // Name the key that was given (the other one kept its default).
    const bool end_given = c.origins.keys.count("sim.end_altitude_m") > 0;
    return Refuse(c, end_given ? "sim.end_altitude_m" : "sim.start_altitude_m", origin,
                  Fixed(s.end_altitude_m, 2) + " m end altitude is not below the " +
                      Fixed(s.start_altitude_m, 2) + " m start altitude",
                  error);
  }
  const double frames = (s.start_altitude_m - s.end_altitude_m) / s.descent_rate_mps * c.rate_hz;
  if (s.scenario == "descent" && frames > 100000.0) {
    return Refuse(c, "sim.descent_rate_mps", origin,
                  Fixed(s.start_altitude_m - s.end_altitude_m, 1) + " m at " +
                      Fixed(s.descent_rate_mps, 3) + " m/s and rate_hz " + Fixed(c.rate_hz, 1) +
                      " is " + Fixed(frames, 0) +
                      " frames, more than 100000 (all rendered before start)",
                  error);
  }
  return true;
}

// The simulated camera's faults: a baseline left, stamps that stay in order.
bool CameraFaultsHold(const FswConfig& c, const std::string& origin, std::string* error) {
  const SimConfig& s = c.sim;
  if (!(s.baseline_m + s.baseline_error_m > 0.0)) {
    return Refuse(c, "sim.baseline_error_m", origin,
                  "leaves no baseline (sim.baseline_m " + Fixed(s.baseline_m, 3) + " m)", error);
  }
  // Truncated at 4 sigma, a jitter of at most a tenth of the frame period keeps the stamps in
  // order (at least 0.2 periods apart) and each frame's IMU interval positive.
  const double max_jitter_ms = 100.0 / c.rate_hz;
  if (s.timestamp_jitter_ms > max_jitter_ms) {
    return Refuse(c, "sim.timestamp_jitter_ms", origin,
                  Fixed(s.timestamp_jitter_ms, 3) + " ms is above a tenth of the frame period (" +
                      Fixed(max_jitter_ms, 3) + " ms at rate_hz " + Fixed(c.rate_hz, 1) +
                      "): the jittered stamps could reorder frames",
                  error);
  }
  return true;
}

// The simulated camera keeps looking at the ground: at most 60 deg off nadir over the descent
// (the optical axis's slant range within twice the altitude).
bool AttitudeHolds(const FswConfig& c, const std::string& origin, std::string* error) {
  if (c.source != SourceKind::kSim || c.sim.scenario != "descent") return true;
  SimView view;
  std::string why;
  if (!SimViewOf(c, &view, &why)) {
    *error = Where(c, "sim.scenario", origin) + ": " + why;  // `why` names its field
    return false;
  }
  constexpr double kMaxTiltDeg = 60.0;
  const double tilt_deg = view.max_tilt_rad * 180.0 / std::numbers::pi;
  if (tilt_deg <= kMaxTiltDeg) return true;
  const double* rate = c.sim.attitude_rate_dps;
  const bool turning = rate[0] != 0.0 || rate[1] != 0.0 || rate[2] != 0.0;
  return Refuse(c, turning ? "sim.attitude_rate_dps" : "sim.attitude_deg", origin,
                "tilts the camera " + Fixed(tilt_deg, 1) +
                    " deg off nadir during the descent (at most " + Fixed(kMaxTiltDeg, 0) + ")",
                error);
}

// The simulated flight's dispersions hold together (each key's own range is its setter's).
bool DispersionsHold(const FswConfig& c, const std::string& origin, std::string* error) {
  return DescentHolds(c, origin, error) && CameraFaultsHold(c, origin, error) &&
         AttitudeHolds(c, origin, error);
}

}  // namespace

const char* SourceName(SourceKind kind) {
  switch (kind) {
    case SourceKind::kSim: return "sim";
    case SourceKind::kV4l2: return "v4l2";
    case SourceKind::kAravis: return "aravis";
    case SourceKind::kLog: return "log";
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
    *error = Where(c, field, origin) + ": " + field + ": " + why;
    return false;
  };
  if (c.source == SourceKind::kLog && c.log_path.empty()) {
    return fail("log.path", "required when source is log");
  }
  if ((c.source == SourceKind::kV4l2 || (c.source == SourceKind::kAravis && !c.camera.fake))) {
    if (c.camera.left.empty()) return fail("camera.left", "required for a camera source");
    if (c.camera.right.empty()) return fail("camera.right", "required for a camera source");
  }
  if (c.source == SourceKind::kV4l2 || c.source == SourceKind::kAravis) {
    if (c.camera.left_calibration.empty()) {
      return fail("camera.left_calibration", "required for a camera source");
    }
    if (c.camera.right_calibration.empty()) {
      return fail("camera.right_calibration", "required for a camera source");
    }
  }
  if (c.source == SourceKind::kV4l2 && c.camera.fake) {
    return fail("camera.fake", "only for source aravis (v4l2 tests script the kernel)");
  }
  if (c.source == SourceKind::kV4l2 && c.camera.left == c.camera.right) {
    return fail("camera.right", "the same device as camera.left");
  }
  if (c.mode == "ekf" && c.window != 1) return fail("window", "must be 1 in mode ekf");
  if (c.source == SourceKind::kSim && c.sim.width_px % 2 != 0) {
    return fail("sim.width_px", "must be even (principal point on a pixel boundary)");
  }
  if (c.sim.target == "orbital" && c.sim.scenario != "descent") {
    return fail("sim.target", "'orbital' selects a descent target: needs sim.scenario descent");
  }
  if (c.max_disparity_px >= c.sim.width_px && c.source == SourceKind::kSim) {
    return fail("max_disparity_px", "must be smaller than sim.width_px");
  }
  if (c.source == SourceKind::kSim && c.envelope_min_range_m > 0.0) {
    return fail(
        "envelope.min_range_m",
        "only for camera and log sources (the simulator's closest range is its trajectory)");
  }
  if (c.initial == "truth" && c.source != SourceKind::kSim && c.source != SourceKind::kLog) {
    return fail("initial", "'truth' needs the simulator (source sim, or a log of a sim run)");
  }
  if (c.imu.enabled && c.source == SourceKind::kSim && c.sim.imu_unit == "none") {
    return fail("imu.enabled", "the simulator carries no IMU: set sim.imu_unit (mems, tactical)");
  }
  if (c.imu.enabled && c.sim.imu_unit == "none" && !(c.imu.rate_hz >= 10.0)) {
    return fail("imu.rate_hz", "must be at least 10 Hz for the stereo-inertial estimator");
  }
  if (c.inject_black_from >= 0 && c.source != SourceKind::kSim) {
    return fail("inject.black_from", "blinds the simulated camera: needs source sim");
  }
  if (c.inject_ms > 0.0 && c.inject_stage.empty()) {
    return fail("inject.stage", "required when inject.ms is set");
  }
  if (c.publish && c.lcm_url.empty()) return fail("lcm.url", "empty while lcm.publish is true");
  if (c.channel_prefix.size() > 32) return fail("lcm.channel_prefix", "longer than 32 characters");
  if (!CapacitiesHold(c, origin, error)) return false;
  if (!DispersionsHold(c, origin, error)) return false;
  if (c.source == SourceKind::kSim) {
    // The simulator's rig and trajectory from the configuration, as sim_world.cpp builds them.
    if (!SimEnvelopeFits(c, sim::MakeStereoCamera(SimRig(c)).fx, origin, error)) return false;
  }
  return true;
}

bool CheckEnvelopeDisparity(const FswConfig& c, double fx_px, double baseline_m, int width_px,
                            std::string* error) {
  const std::string origin = c.origins.file.empty() ? "configuration" : c.origins.file;
  double range_m = 0.0;
  std::string range_from;
  if (c.source == SourceKind::kSim) {
    // The front end searches the true rig's images: their baseline is the configuration's (with
    // sim.baseline_error_m), not the calibration's baseline_m.
    return SimEnvelopeFits(c, fx_px, origin, error);
  }
  if (c.envelope_min_range_m > 0.0) {
    range_m = c.envelope_min_range_m;
    range_from = "envelope.min_range_m";
  } else if (c.source == SourceKind::kLog) {
    return true;  // a replay re-runs recorded frames; the flight was checked when it flew
  } else {
    *error = Where(c, "envelope.min_range_m", origin) +
             ": envelope.min_range_m: required for a camera source: the closest range (m) the "
             "flight reaches, to check max_disparity_px against f x baseline = " +
             Fixed(fx_px * baseline_m, 1) + " px m";
    return false;
  }
  return DisparityFits(c, fx_px, baseline_m, width_px, range_m, range_from, "the rectified rig",
                       origin, error);
}

namespace {

// stat(2) and access(2) on `path`: "" when this process may write it (an existing non-directory
// file, or a new file in an existing directory), otherwise why not.
std::string WhyNotWritableFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return "is a directory";
    if (::access(path.c_str(), W_OK) != 0)
      return std::string("cannot be written: ") + std::strerror(errno);
    return "";
  }
  // ENOTDIR: a component of the directory is a file (said below about the directory).
  if (errno != ENOENT && errno != ENOTDIR) {
    return std::string("cannot be examined: ") + std::strerror(errno);
  }
  const auto slash = path.find_last_of('/');
  const std::string dir =
      slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  if (::stat(dir.c_str(), &st) != 0) {
    const int e = errno;  // before anything else can change it
    return std::string("its directory ") + Quoted(dir) + " " +
           (e == ENOENT ? std::string("does not exist")
                        : std::string("cannot be examined: ") + std::strerror(e));
  }
  if (!S_ISDIR(st.st_mode)) return Quoted(dir) + " is not a directory";
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    const int e = errno;
    return std::string("its directory ") + Quoted(dir) + " cannot be written: " + std::strerror(e);
  }
  return "";
}

std::string WhyNotWritableDirectory(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return errno == ENOENT ? std::string("does not exist")
                           : std::string("cannot be examined: ") + std::strerror(errno);
  }
  if (!S_ISDIR(st.st_mode)) return "is not a directory";
  if (::access(path.c_str(), W_OK | X_OK) != 0) {
    return std::string("cannot be written: ") + std::strerror(errno);
  }
  return "";
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
    *error = Where(c, field, origin) + ": " + field + ": " + Quoted(path) + " " + why;
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

bool ParseConfig(const std::string& text, const std::string& origin, FswConfig* config,
                 std::string* error) {
  FswConfig c;
  if (!ApplyFileText(text, origin, &c, error)) return false;
  if (!ValidateConfig(c, origin, error)) return false;
  *config = c;
  return true;
}

bool LoadConfig(const std::string& path, FswConfig* config, std::string* error) {
  std::string text;
  if (!ReadConfigFile(path, &text, error)) return false;
  return ParseConfig(text, path, config, error);
}

bool LoadConfig(const std::string& path, const std::vector<std::string>& overrides,
                FswConfig* config, std::string* error) {
  std::string text;
  if (!ReadConfigFile(path, &text, error)) return false;
  FswConfig c;
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
