// The simulator's configuration keys (sim.*, inject.black_*) and the checks between them and the
// flight process's keys: the descent geometry, the camera faults, the attitude, and the disparity
// the front end must find at the closest range the simulated descent flies.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <string>

#include "swf/app/config_fields.hpp"
#include "swf/sil/sil.hpp"
#include "swf/sil/sim_world.hpp"
#include "swf/sim/rig.hpp"
#include "swf/sim/trajectory.hpp"

namespace swf::sil {

using app::Bool;
using app::ConfigSetter;
using app::ConfigWhere;
using app::DisparityFits;
using app::Excerpt;
using app::Fixed;
using app::FswConfig;
using app::Int;
using app::Number;
using app::Numbers;
using app::OneOf;
using app::ParseDouble;
using app::RefuseField;
using app::SimConfig;
using app::SourceKind;
using app::Text;

namespace {

// A finite number into a member of SimConfig, inside [lo, hi] (or (lo, hi]).
ConfigSetter SimNumber(double SimConfig::*field, double lo, double hi, bool lo_open = false) {
  return Number([=](FswConfig* c) { return &(c->sim.*field); }, lo, hi, lo_open);
}

// N finite numbers into a member array of SimConfig, each inside [lo, hi].
template <int N>
ConfigSetter SimNumbers(double (SimConfig::*field)[N], double lo, double hi, const char* names) {
  return Numbers<N>([=](FswConfig* c) { return c->sim.*field; }, lo, hi, names);
}

// The dispersions of the simulated flight (SimConfig; their consistency is checked in
// DispersionsHold).
void AddDispersionFields(std::map<std::string, ConfigSetter>* fields) {
  std::map<std::string, ConfigSetter>& f = *fields;
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

// The simulator's keys: the scene, the rig, the motion input and IMU unit, the descent target,
// the dispersions and the blinded camera.
std::map<std::string, ConfigSetter> SimFields() {
  std::map<std::string, ConfigSetter> f;
  f["sim.scenario"] = OneOf([](FswConfig* c) { return &c->sim.scenario; },
                            {"descent", "hover", "sideways", "lab", "lab_static"});
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
  f["sim.baseline_m"] = SimNumber(&SimConfig::baseline_m, 0.0, 100.0, true);
  f["sim.frames"] = Int<std::int32_t>([](FswConfig* c) { return &c->sim.frames; }, 0, 100000);
  f["sim.terrain_size"] =
      Int<std::int32_t>([](FswConfig* c) { return &c->sim.terrain_size; }, 64, 8192);
  f["sim.seed"] =
      Int<std::uint64_t>([](FswConfig* c) { return &c->sim.seed; }, 0, std::int64_t{1} << 62);
  f["sim.shared"] = Text([](FswConfig* c) { return &c->sim.shared_dir; });
  f["sim.render_threads"] =
      Int<std::int32_t>([](FswConfig* c) { return &c->sim.render_threads; }, 1, 64);
  f["sim.imu"] = Bool([](FswConfig* c) { return &c->sim.imu; });
  f["sim.imu_sigma_m"] = SimNumber(&SimConfig::imu_sigma_m, 0.0, 10.0);
  f["sim.imu_sigma_rad"] = SimNumber(&SimConfig::imu_sigma_rad, 0.0, 0.5);
  f["sim.imu_unit"] =
      OneOf([](FswConfig* c) { return &c->sim.imu_unit; }, {"none", "mems", "tactical"});
  f["sim.imu_clock_offset_ms"] = SimNumber(&SimConfig::imu_clock_offset_ms, -500.0, 500.0);
  f["sim.handover_error"] =
      OneOf([](FswConfig* c) { return &c->sim.handover_error; }, {"none", "drawn"});
  AddDispersionFields(&f);
  f["sim.target"] = OneOf([](FswConfig* c) { return &c->sim.target; }, {"nominal", "orbital"});
  // 60 m keeps the search square (plus the 10 m clearance cap) and the 100 m view inside the
  // 204.8 m terrain.
  f["sim.target_search_m"] = SimNumber(&SimConfig::target_search_m, 0.0, 60.0);
  f["inject.black_from"] = Int<std::int64_t>([](FswConfig* c) { return &c->inject_black_from; }, -1,
                                             std::int64_t{1} << 40);
  f["inject.black_frames"] = Int<std::int64_t>([](FswConfig* c) { return &c->inject_black_frames; },
                                               1, std::int64_t{1} << 40);
  return f;
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

// The simulator's flown envelope: the disparity the front end must find in the true images, at
// the closest range over the trajectory (SimViewOf), with the true baseline (sim.baseline_m +
// sim.baseline_error_m) and f of the calibration `fx_px`; a rotation error of the right camera
// shifts the right image by up to f |ry| + |rz| (larger image side) / 2 px on top.
bool SimEnvelopeFits(const FswConfig& c, double fx_px, const std::string& origin,
                     std::string* error) {
  SimView view;
  std::string why;
  if (!SimViewOf(c, &view, &why)) {
    *error = ConfigWhere(c, "sim.scenario", origin) + ": " + why;
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

// The descent geometry: for the descent only, ending below its start, a bounded frame count.
bool DescentHolds(const FswConfig& c, const std::string& origin, std::string* error) {
  const SimConfig& s = c.sim;
  if (const char* key = DescentKeyChanged(s); key != nullptr && s.scenario != "descent") {
    return RefuseField(c, key, origin, "shapes the descent: needs sim.scenario descent", error);
  }
  if (!(s.end_altitude_m < s.start_altitude_m)) {
    // Name the key that was given (the other one kept its default).
    const bool end_given = c.origins.keys.count("sim.end_altitude_m") > 0;
    return RefuseField(c, end_given ? "sim.end_altitude_m" : "sim.start_altitude_m", origin,
                       Fixed(s.end_altitude_m, 2) + " m end altitude is not below the " +
                           Fixed(s.start_altitude_m, 2) + " m start altitude",
                       error);
  }
  const double frames = (s.start_altitude_m - s.end_altitude_m) / s.descent_rate_mps * c.rate_hz;
  if (s.scenario == "descent" && frames > 100000.0) {
    return RefuseField(c, "sim.descent_rate_mps", origin,
                       Fixed(s.start_altitude_m - s.end_altitude_m, 1) + " m at " +
                           Fixed(s.descent_rate_mps, 3) + " m/s and rate_hz " +
                           Fixed(c.rate_hz, 1) + " is " + Fixed(frames, 0) +
                           " frames, more than 100000 (all rendered before start)",
                       error);
  }
  return true;
}

// The simulated camera's faults: a baseline left, stamps that stay in order.
bool CameraFaultsHold(const FswConfig& c, const std::string& origin, std::string* error) {
  const SimConfig& s = c.sim;
  if (!(s.baseline_m + s.baseline_error_m > 0.0)) {
    return RefuseField(c, "sim.baseline_error_m", origin,
                       "leaves no baseline (sim.baseline_m " + Fixed(s.baseline_m, 3) + " m)",
                       error);
  }
  // Truncated at 4 sigma, a jitter of at most a tenth of the frame period keeps the stamps in
  // order (at least 0.2 periods apart) and each frame's IMU interval positive.
  const double max_jitter_ms = 100.0 / c.rate_hz;
  if (s.timestamp_jitter_ms > max_jitter_ms) {
    return RefuseField(c, "sim.timestamp_jitter_ms", origin,
                       Fixed(s.timestamp_jitter_ms, 3) +
                           " ms is above a tenth of the frame period (" + Fixed(max_jitter_ms, 3) +
                           " ms at rate_hz " + Fixed(c.rate_hz, 1) +
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
    *error = ConfigWhere(c, "sim.scenario", origin) + ": " + why;  // `why` names its field
    return false;
  }
  constexpr double kMaxTiltDeg = 60.0;
  const double tilt_deg = view.max_tilt_rad * 180.0 / std::numbers::pi;
  if (tilt_deg <= kMaxTiltDeg) return true;
  const double* rate = c.sim.attitude_rate_dps;
  const bool turning = rate[0] != 0.0 || rate[1] != 0.0 || rate[2] != 0.0;
  return RefuseField(c, turning ? "sim.attitude_rate_dps" : "sim.attitude_deg", origin,
                     "tilts the camera " + Fixed(tilt_deg, 1) +
                         " deg off nadir during the descent (at most " + Fixed(kMaxTiltDeg, 0) +
                         ")",
                     error);
}

// The simulated flight's dispersions hold together (each key's own range is its setter's).
bool DispersionsHold(const FswConfig& c, const std::string& origin, std::string* error) {
  return DescentHolds(c, origin, error) && CameraFaultsHold(c, origin, error) &&
         AttitudeHolds(c, origin, error);
}

// The checks of ValidateConfig that concern the simulator.
bool ValidateSim(const FswConfig& c, const std::string& origin, std::string* error) {
  auto fail = [&](const std::string& field, const std::string& why) {
    return RefuseField(c, field, origin, why, error);
  };
  const bool sim = c.source == SourceKind::kSim;
  if (sim && c.sim.width_px % 2 != 0) {
    return fail("sim.width_px", "must be even (principal point on a pixel boundary)");
  }
  if (c.sim.target == "orbital" && c.sim.scenario != "descent") {
    return fail("sim.target", "'orbital' selects a descent target: needs sim.scenario descent");
  }
  if (sim && c.max_disparity_px >= c.sim.width_px) {
    return fail("max_disparity_px", "must be smaller than sim.width_px");
  }
  if (sim && c.envelope_min_range_m > 0.0) {
    return fail(
        "envelope.min_range_m",
        "only for camera and log sources (the simulator's closest range is its trajectory)");
  }
  if (c.imu.enabled && sim && c.sim.imu_unit == "none") {
    return fail("imu.enabled", "the simulator carries no IMU: set sim.imu_unit (mems, tactical)");
  }
  if (c.inject_black_from >= 0 && !sim) {
    return fail("inject.black_from", "blinds the simulated camera: needs source sim");
  }
  if (!DispersionsHold(c, origin, error)) return false;
  // The simulator's rig and trajectory from the configuration, as sim_world.cpp builds them.
  return !sim || SimEnvelopeFits(c, sim::MakeStereoCamera(SimRig(c)).fx, origin, error);
}

}  // namespace

const app::ConfigExtension* SimConfigExtension() {
  static const std::map<std::string, ConfigSetter> kFields = SimFields();
  // The front end searches the true rig's images: their baseline is the configuration's (with
  // sim.baseline_error_m), not the calibration's.
  static const app::ConfigExtension kExtension{"sim", &kFields, &ValidateSim, &SimEnvelopeFits};
  return &kExtension;
}

}  // namespace swf::sil
