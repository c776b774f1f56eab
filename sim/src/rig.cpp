#include "swf/sim/rig.hpp"

#include <cmath>
#include <numbers>

namespace swf::sim {

RigOptions EdlRig() { return RigOptions{}; }

RigOptions LabRig() {
  RigOptions rig;
  rig.baseline_m = 0.1;
  return rig;
}

core::Status ValidateRig(const RigOptions& rig) {
  if (rig.width_px < 2 || rig.height_px < 2 || rig.width_px > 16384 || rig.height_px > 16384) {
    return core::Status::kInvalidArgument;
  }
  if (!(rig.horizontal_fov_deg > 0.0 && rig.horizontal_fov_deg < 170.0)) {
    return core::Status::kInvalidArgument;
  }
  if (!(rig.baseline_m > 0.0) || !std::isfinite(rig.baseline_m)) {
    return core::Status::kInvalidArgument;
  }
  return core::Status::kOk;
}

estimator::StereoCamera<double> MakeStereoCamera(const RigOptions& rig) {
  const double half_fov_rad = 0.5 * rig.horizontal_fov_deg * std::numbers::pi / 180.0;
  estimator::StereoCamera<double> camera;
  camera.fx = 0.5 * rig.width_px / std::tan(half_fov_rad);
  camera.fy = camera.fx;
  camera.cx = 0.5 * (rig.width_px - 1);
  camera.cy = 0.5 * (rig.height_px - 1);
  camera.baseline_m = rig.baseline_m;
  return camera;
}

}  // namespace swf::sim
