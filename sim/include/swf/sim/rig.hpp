// Stereo rig model of the simulator: a rectified pinhole pair (the StereoCamera of
// estimator/geometry.hpp) described by the quantities an engineer specifies a rig with.
//
// Pixel convention: pixel (c, r) covers [c - 0.5, c + 0.5) x [r - 0.5, r + 0.5), i.e. pixel centres
// sit at integer coordinates, and the principal point is the image centre ((w-1)/2, (h-1)/2).
#pragma once

#include <cstdint>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"

namespace swf::sim {

struct RigOptions {
  std::int32_t width_px = 1024;
  std::int32_t height_px = 768;
  double horizontal_fov_deg = 25.0;  // full horizontal field of view of each camera
  double baseline_m = 1.0;           // right camera at +baseline along the left camera's x axis
};

// The paper's EDL rig: 1 m baseline, ~25 deg FOV, 1024 x 768 (paper section 4.2.2).
RigOptions EdlRig();
// The paper's lab rig (Flea cameras, Fig. 10c): ~10 cm baseline, ~25 deg FOV, 1024 x 768.
RigOptions LabRig();

// kInvalidArgument for non-positive sizes, a FOV outside (0, 170) deg or a non-positive baseline.
core::Status ValidateRig(const RigOptions& rig);

// fx = fy = (width / 2) / tan(fov / 2); principal point at the image centre.
estimator::StereoCamera<double> MakeStereoCamera(const RigOptions& rig);

}  // namespace swf::sim
