#include "swf/frontend/rectify.hpp"

#include <algorithm>
#include <cmath>

namespace swf::frontend {

using core::Status;
using estimator::Mat3;
using estimator::Vec3;

namespace {

bool ValidCalibration(const CameraCalibration& c) {
  return c.width > 1 && c.height > 1 && c.fx > 0.0 && c.fy > 0.0 && std::isfinite(c.cx) &&
         std::isfinite(c.cy) && std::isfinite(c.k1) && std::isfinite(c.k2) && std::isfinite(c.p1) &&
         std::isfinite(c.p2) && std::isfinite(c.k3);
}

}  // namespace

bool StereoRectifier::RawPixel(int camera, double u, double v, double* raw_u, double* raw_v) const {
  const CameraCalibration& c = calib_[camera];
  const Vec3<double> ray((u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0);
  const Vec3<double> p = rect_from_cam_[camera].transpose() * ray;
  if (!(p.z() > 1e-6)) return false;
  const double x = p.x() / p.z();
  const double y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
  const double xd = x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y;
  *raw_u = c.fx * xd + c.cx;
  *raw_v = c.fy * yd + c.cy;
  return true;
}

Status StereoRectifier::Configure(const CameraCalibration& left, const CameraCalibration& right,
                                  const RectifyOptions& options) {
  configured_ = false;
  if (!ValidCalibration(left) || !ValidCalibration(right) || !(options.focal_scale > 0.0)) {
    return Status::kInvalidArgument;
  }
  const int w = options.width > 0 ? options.width : left.width;
  const int h = options.height > 0 ? options.height : left.height;
  if (w > kMaxImageWidth || h > kMaxImageHeight || left.width >= kOutside ||
      right.width >= kOutside || left.height >= kOutside || right.height >= kOutside) {
    return Status::kInvalidArgument;
  }
  calib_[0] = left;
  calib_[1] = right;
  const estimator::Pose<double> left_T_right = left.body_T_camera.Inverse() * right.body_T_camera;
  const Vec3<double> t = left_T_right.t;
  const double baseline = t.norm();
  if (!(baseline > 1e-6)) return Status::kInvalidArgument;
  const Mat3<double> left_R_mid =
      estimator::ExpSO3<double>(0.5 * estimator::LogSO3<double>(left_T_right.R));
  const Vec3<double> e1 = t / baseline;
  Vec3<double> e2 = left_R_mid.col(2).cross(e1);
  if (!(e2.norm() > 1e-6)) return Status::kInvalidArgument;  // baseline along the optical axis
  e2.normalize();
  const Vec3<double> e3 = e1.cross(e2);
  Mat3<double> rect_R_left;
  rect_R_left.row(0) = e1.transpose();
  rect_R_left.row(1) = e2.transpose();
  rect_R_left.row(2) = e3.transpose();
  rect_from_cam_[0] = rect_R_left;
  rect_from_cam_[1] = rect_R_left * left_T_right.R;

  // Shared intrinsics: the mean focal length, and a principal point that keeps the mean of the
  // two raw principal rays at the mean of the raw principal points (scaled to the output size).
  const double f = options.focal_scale * 0.25 * (left.fx + left.fy + right.fx + right.fy);
  double ray_x = 0.0;
  double ray_y = 0.0;
  for (int c = 0; c < 2; ++c) {
    const Vec3<double> axis = rect_from_cam_[c].col(2);
    ray_x += 0.5 * axis.x() / axis.z();
    ray_y += 0.5 * axis.y() / axis.z();
  }
  const double sx = static_cast<double>(w) / left.width;
  const double sy = static_cast<double>(h) / left.height;
  camera_.fx = f;
  camera_.fy = f;
  camera_.cx = 0.5 * (left.cx + right.cx) * sx - f * ray_x;
  camera_.cy = 0.5 * (left.cy + right.cy) * sy - f * ray_y;
  camera_.baseline_m = baseline;
  estimator::Pose<double> left_T_rect;
  left_T_rect.R = rect_R_left.transpose();
  rectified_in_body_ = left.body_T_camera * left_T_rect;
  width_ = w;
  height_ = h;

  for (int c = 0; c < 2; ++c) {
    const CameraCalibration& cal = calib_[c];
    Table& table = table_[c];
    for (int v = 0; v < h; ++v) {
      int begin = w;
      int end = 0;
      for (int u = 0; u < w; ++u) {
        const std::size_t k = static_cast<std::size_t>(v) * w + u;
        table.x[k] = kOutside;
        table.y[k] = 0;
        table.wx[k] = 0;
        table.wy[k] = 0;
        double ru = 0.0;
        double rv = 0.0;
        if (!RawPixel(c, u, v, &ru, &rv)) continue;
        if (!(ru >= 0.0 && rv >= 0.0 && ru <= cal.width - 1 && rv <= cal.height - 1)) continue;
        // The last row/column is reached with weight 256 on the second tap, so the 2x2 taps
        // always stay inside the image.
        const int cu = std::min(static_cast<int>(ru), cal.width - 2);
        const int cv = std::min(static_cast<int>(rv), cal.height - 2);
        table.x[k] = static_cast<std::uint16_t>(cu);
        table.y[k] = static_cast<std::uint16_t>(cv);
        table.wx[k] = static_cast<std::uint16_t>(std::lround((ru - cu) * 256.0));
        table.wy[k] = static_cast<std::uint16_t>(std::lround((rv - cv) * 256.0));
        begin = std::min(begin, u);
        end = u + 1;
      }
      bool dense = true;
      for (int u = begin; u < end; ++u) {
        dense = dense && table.x[static_cast<std::size_t>(v) * w + u] != kOutside;
      }
      table.begin[v] = begin < end ? begin : 0;
      table.end[v] = begin < end ? end : 0;
      table.dense[v] = dense;
    }
  }
  configured_ = true;
  return Status::kOk;
}

void StereoRectifier::RemapOne(const GrayView& raw, const Table& table,
                               const MutableGrayView& out) const {
  std::uint8_t p00[kMaxImageWidth];
  std::uint8_t p01[kMaxImageWidth];
  std::uint8_t p10[kMaxImageWidth];
  std::uint8_t p11[kMaxImageWidth];
  for (int v = 0; v < height_; ++v) {
    std::uint8_t* o = out.Row(v);
    const std::size_t row = static_cast<std::size_t>(v) * width_;
    const int begin = table.begin[v];
    const int end = table.end[v];
    for (int u = 0; u < begin; ++u) o[u] = 0;
    for (int u = end; u < width_; ++u) o[u] = 0;
    const std::uint16_t* tx = table.x + row;
    const std::uint16_t* ty = table.y + row;
    const std::uint16_t* twx = table.wx + row;
    const std::uint16_t* twy = table.wy + row;
    if (!table.dense[v]) {
      for (int u = begin; u < end; ++u) {
        if (tx[u] == kOutside) {
          o[u] = 0;
          continue;
        }
        const std::uint8_t* s0 = raw.Row(ty[u]) + tx[u];
        const std::uint8_t* s1 = s0 + raw.stride;
        const int ax = twx[u];
        const int ay = twy[u];
        const int top = s0[0] * (256 - ax) + s0[1] * ax;
        const int bottom = s1[0] * (256 - ax) + s1[1] * ax;
        o[u] = static_cast<std::uint8_t>((top * (256 - ay) + bottom * ay + 32768) >> 16);
      }
      continue;
    }
    // Gather (scalar loads), then blend (vectorised; the same integer formula as above).
    for (int u = begin; u < end; ++u) {
      const std::uint8_t* s0 = raw.Row(ty[u]) + tx[u];
      const std::uint8_t* s1 = s0 + raw.stride;
      p00[u] = s0[0];
      p01[u] = s0[1];
      p10[u] = s1[0];
      p11[u] = s1[1];
    }
    for (int u = begin; u < end; ++u) {
      // top, bottom <= 255 * 256: 16-bit lanes; the second blend widens to 32 bits.
      const std::uint16_t ax = twx[u];
      const std::uint16_t ay = twy[u];
      const auto top = static_cast<std::uint16_t>(p00[u] * (256 - ax) + p01[u] * ax);
      const auto bottom = static_cast<std::uint16_t>(p10[u] * (256 - ax) + p11[u] * ax);
      const std::uint32_t blend =
          static_cast<std::uint32_t>(top) * static_cast<std::uint16_t>(256 - ay) +
          static_cast<std::uint32_t>(bottom) * ay;
      o[u] = static_cast<std::uint8_t>((blend + 32768u) >> 16);
    }
  }
}

Status StereoRectifier::Rectify(const GrayView& left_raw, const GrayView& right_raw,
                                const MutableGrayView& left_out,
                                const MutableGrayView& right_out) const {
  if (!configured_) return Status::kNotConfigured;
  if (!left_raw.Valid() || !right_raw.Valid() || left_raw.width != calib_[0].width ||
      left_raw.height != calib_[0].height || right_raw.width != calib_[1].width ||
      right_raw.height != calib_[1].height || left_out.width != width_ ||
      left_out.height != height_ || right_out.width != width_ || right_out.height != height_ ||
      left_out.data == nullptr || right_out.data == nullptr) {
    return Status::kInvalidArgument;
  }
  RemapOne(left_raw, table_[0], left_out);
  RemapOne(right_raw, table_[1], right_out);
  return Status::kOk;
}

}  // namespace swf::frontend
