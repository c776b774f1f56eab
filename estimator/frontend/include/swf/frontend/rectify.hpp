// Stereo rectification from a calibrated rig (pinhole + radial-tangential distortion +
// extrinsics), computed once at start-up as a remap table and applied per frame with bilinear
// interpolation in 8-bit fixed point. Per row, the source pixels are gathered first (scalar loads)
// and then blended in a separate, vectorisable pass.
//
// Rectifying rotation (Bouguet-style): with left_T_right = {R, t} (t: right centre in the left
// frame), the common optical axis is the "half-way" rotation z_mid = Exp(Log(R)/2) e_z; the
// rectified axes are e1 = t/|t| (the baseline becomes +x, as estimator::StereoCamera requires),
// e2 = normalize(z_mid x e1), e3 = e1 x e2, and rect_R_left = [e1 e2 e3]^T,
// rect_R_right = rect_R_left R. Both rectified cameras share K_new = [f 0 cx; 0 f cy; 0 0 1].
// Remap: rectified pixel -> ray K_new^-1 (u,v,1) -> raw camera frame cam_R_rect ray ->
// distortion (x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2), y likewise)
// -> raw pixel.
#pragma once

#include <cstdint>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/frontend/config.hpp"
#include "swf/frontend/image.hpp"

namespace swf::frontend {

struct CameraCalibration {
  int width = 0;
  int height = 0;
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  double k1 = 0.0;  // radial-tangential ("plumb bob") distortion
  double k2 = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
  double k3 = 0.0;
  estimator::Pose<double> body_T_camera;  // extrinsics (EuRoC T_BS)
};

struct RectifyOptions {
  int width = 0;  // output size; 0 = the input size
  int height = 0;
  double focal_scale = 1.0;  // < 1 zooms out (keeps more of the raw field of view)
};

class StereoRectifier {
 public:
  // Computes rotations, the rectified camera and both remap tables. kInvalidArgument for a
  // calibration that cannot be rectified (zero baseline, bad intrinsics, sizes over capacity).
  core::Status Configure(const CameraCalibration& left, const CameraCalibration& right,
                         const RectifyOptions& options);

  // Remaps raw images into the outputs (which must be width() x height()). Pixels that fall
  // outside the raw image become 0. Never allocates.
  core::Status Rectify(const GrayView& left_raw, const GrayView& right_raw,
                       const MutableGrayView& left_out, const MutableGrayView& right_out) const;

  int Width() const { return width_; }
  int Height() const { return height_; }
  // The rectified stereo camera (the estimator's measurement model).
  const estimator::StereoCamera<double>& Camera() const { return camera_; }
  // Rectified left camera in the body frame (for ground truth comparison and the process model).
  const estimator::Pose<double>& RectifiedInBody() const { return rectified_in_body_; }
  // Raw pixel of a rectified pixel (index 0 = left, 1 = right). False when behind the camera.
  bool RawPixel(int camera, double u, double v, double* raw_u, double* raw_v) const;

 private:
  // Remap table of one camera, structure of arrays so the per-pixel arithmetic vectorises: the
  // top-left source pixel (x, y) and the fractional position * 256 (wx, wy in [0, 256]).
  // x == kOutside: no source pixel (output 0).
  struct Table {
    std::uint16_t x[kMaxPixels];
    std::uint16_t y[kMaxPixels];
    std::uint16_t wx[kMaxPixels];
    std::uint16_t wy[kMaxPixels];
    // Per output row: the columns [begin, end) with a source, and whether every column of that
    // span has one (then the row takes the branch-free path).
    std::int32_t begin[kMaxImageHeight];
    std::int32_t end[kMaxImageHeight];
    bool dense[kMaxImageHeight];
  };
  static constexpr std::uint16_t kOutside = 0xFFFF;
  void RemapOne(const GrayView& raw, const Table& table, const MutableGrayView& out) const;

  CameraCalibration calib_[2]{};
  estimator::Mat3<double> rect_from_cam_[2];
  estimator::StereoCamera<double> camera_{};
  estimator::Pose<double> rectified_in_body_{};
  int width_ = 0;
  int height_ = 0;
  bool configured_ = false;
  Table table_[2];
};

}  // namespace swf::frontend
