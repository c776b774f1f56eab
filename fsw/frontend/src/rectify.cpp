#include "swf/frontend/rectify.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rectify_kernels.hpp"
#include "swf/core/portable_math.hpp"

namespace swf::frontend {

using core::Status;
using estimator::Mat3;
using estimator::Vec3;

namespace {

using rectify_detail::BestKernel;
using rectify_detail::EvalHalf;
using rectify_detail::EvalSegment;
using rectify_detail::KernelSupported;
using rectify_detail::kFineOne;
using rectify_detail::kFineToWeight;
using rectify_detail::kHalf;
using rectify_detail::kWeightOne;
using rectify_detail::kWeightOneF;
using rectify_detail::Quadratic;
using rectify_detail::Segment;
using rectify_detail::SegmentKind;
using rectify_detail::WindowHalf;
constexpr int kSegment = rectify_detail::kSegment;

bool ValidCalibration(const CameraCalibration& c) {
  return c.width > 1 && c.height > 1 && c.fx > 0.0 && c.fy > 0.0 && std::isfinite(c.cx) &&
         std::isfinite(c.cy) && std::isfinite(c.k1) && std::isfinite(c.k2) && std::isfinite(c.p1) &&
         std::isfinite(c.p2) && std::isfinite(c.k3);
}

// One coordinate of a WindowHalf: the quadratic through the exact raw coordinate f0, fm, f7 at
// j = 0, 3.5, 7, in 1/1024 px from `origin` with the 1/256-px rounding offset folded in (so that
// X >> 3 rounds to 1/128 px). False when a coefficient does not fit its 16-bit lane.
bool FitHalf(double f0, double fm, double f7, int origin, std::int16_t* c) {
  const double c2 = ((f7 - f0) / 7.0 - (fm - f0) / 3.5) / 3.5;
  const double c1 = (fm - f0) / 3.5 - c2 * 3.5;
  const double coef[3] = {(f0 - origin) * kFineOne + (1 << (kFineToWeight - 1)),
                          c1 * kFineOne * (1 << 3), c2 * kFineOne * (1 << 6)};
  for (int i = 0; i < 3; ++i) {
    const double r = std::round(coef[i]);
    if (!(std::fabs(r) <= 32767.0)) return false;
    c[i] = static_cast<std::int16_t>(r);
  }
  return true;
}

// Makes `half` the WindowHalf of pixels whose exact raw coordinates are (ex[j], ey[j]), j = 0 .. 7
// (mx, my at j = 3.5): the window's column / row is the smallest tap column / row (or one less),
// and every pixel's X must stay in 0 .. 15 px (taps dx, dx + 1 <= 15), Y in 0 .. 2 px, the window
// inside the raw image. False when no origin works.
bool FitWindowHalf(const double* ex, const double* ey, double mx, double my, int raw_width,
                   int raw_height, WindowHalf* half) {
  const int column = static_cast<int>(std::floor(std::min(ex[0], ex[kHalf - 1])));
  const int row = static_cast<int>(std::floor(std::min(ey[0], ey[kHalf - 1])));
  for (int dc = 0; dc < 2; ++dc) {
    for (int dr = 0; dr < 2; ++dr) {
      const int c = column - dc;
      const int r = row - dr;
      if (c < 0 || r < 0 || c + 15 > raw_width - 1 || r + 2 > raw_height - 1) continue;
      if (!FitHalf(ex[0], mx, ex[kHalf - 1], c, half->x) ||
          !FitHalf(ey[0], my, ey[kHalf - 1], r, half->y)) {
        return false;
      }
      bool ok = true;
      for (int j = 0; j < kHalf; ++j) {
        const int x = EvalHalf(half->x, j);
        const int y = EvalHalf(half->y, j);
        ok = ok && x >= 0 && x < 15 * kFineOne && y >= 0 && y < 2 * kFineOne;
      }
      if (ok) {
        half->column = static_cast<std::int16_t>(c);  // raw sides < 2^15
        half->row = static_cast<std::int16_t>(r);
        return true;
      }
    }
  }
  return false;
}

// The rectifying rotation of the left camera (file comment): the baseline becomes +x and the
// optical axis the half-way rotation's, made perpendicular to the baseline. False for a baseline
// too short or along the optical axis.
bool RectifyingRotation(const estimator::Pose<double>& left_T_right, Mat3<double>* rect_R_left) {
  const Vec3<double> t = left_T_right.t;
  const double baseline = t.norm();
  if (!(baseline > 1e-6)) return false;
  const Mat3<double> left_R_mid =
      estimator::ExpSO3<double>(0.5 * estimator::LogSO3<double>(left_T_right.R));
  const Vec3<double> e1 = t / baseline;
  Vec3<double> e2 = left_R_mid.col(2).cross(e1);
  if (!(e2.norm() > 1e-6)) return false;  // baseline along the optical axis
  e2.normalize();
  const Vec3<double> e3 = e1.cross(e2);
  rect_R_left->row(0) = e1.transpose();
  rect_R_left->row(1) = e2.transpose();
  rect_R_left->row(2) = e3.transpose();
  return true;
}

// The exact map (RawPixel) at a segment's output pixels u0 + k, k = 0 .. len - 1, and at its
// middle, u0 + (len - 1) / 2.
struct ExactSegment {
  double x[kSegment] = {};
  double y[kSegment] = {};
  double mid_x = 0.0;
  double mid_y = 0.0;
};

// False when part of the segment is behind the camera.
bool SampleExactMap(const StereoRectifier& rectifier, int camera, int u0, int v, int len,
                    ExactSegment* exact) {
  bool visible = true;
  for (int k = 0; k < len; ++k) {
    visible = visible && rectifier.RawPixel(camera, u0 + k, v, &exact->x[k], &exact->y[k]);
  }
  const double mid = 0.5 * (len - 1);
  return visible && rectifier.RawPixel(camera, u0 + mid, v, &exact->mid_x, &exact->mid_y);
}

// One coordinate of a Quadratic: through f0, fm, fl at k = 0, (len - 1) / 2, len - 1 (Newton form
// converted to monomials).
void FitQuadratic(double f0, double fm, double fl, int len, float* coef) {
  const double last = len - 1;
  const double mid = 0.5 * last;
  double c1 = 0.0;
  double c2 = 0.0;
  if (len > 1) {
    const double slope_m = (fm - f0) / mid;
    const double slope_l = (fl - f0) / last;
    c2 = (slope_l - slope_m) / (last - mid);
    c1 = slope_m - c2 * mid;
  }
  // Stored in 1/128 px with the rounding offset folded in: truncation rounds.
  coef[0] = static_cast<float>(f0 * kWeightOne + 0.5);
  coef[1] = static_cast<float>(c1 * kWeightOne);
  coef[2] = static_cast<float>(c2 * kWeightOne);
}

// True when the exact source (x, y) lies in the raw image: the pixels MaxTableErrorPx covers.
bool InRawImage(const CameraCalibration& cal, double x, double y) {
  return x >= 0.0 && y >= 0.0 && x <= cal.width - 1 && y <= cal.height - 1;
}

// One table segment as FitSegment leaves it. A default one has no source at all.
struct SegmentFit {
  Segment segment{};
  SegmentKind kind = SegmentKind::kOutside;
  bool identity = false;  // every pixel rounds to itself
  double error = 0.0;     // largest |table - exact map| over the pixels in the raw image
};

// A segment stored as `quad`: its kind (kInside when both taps of every pixel are inside, kMixed
// when some pixel has a source, else kOutside) and its error against the exact map.
SegmentFit CheckQuadratic(const Quadratic& quad, const ExactSegment& exact,
                          const CameraCalibration& cal, int u0, int v, int len) {
  // Fixed-point limits (1/128 px): the fast path needs both taps inside (X <= (w-1)*128 - 1);
  // a pixel has a source when 0 <= X <= (w-1)*128.
  const auto fast_x = static_cast<float>((cal.width - 1) * kWeightOne);
  const auto fast_y = static_cast<float>((cal.height - 1) * kWeightOne);
  SegmentFit fit;
  fit.segment.quad = quad;
  fit.identity = true;
  bool all_fast = true;
  bool any_source = false;
  for (int k = 0; k < len; ++k) {
    const float fx = EvalSegment(quad.x, static_cast<float>(k));
    const float fy = EvalSegment(quad.y, static_cast<float>(k));
    const double tx = (fx - 0.5) / kWeightOne;
    const double ty = (fy - 0.5) / kWeightOne;
    const bool source = fx >= 0.0f && fy >= 0.0f && fx < fast_x + 1.0f && fy < fast_y + 1.0f;
    all_fast = all_fast && fx >= 0.0f && fy >= 0.0f && fx < fast_x && fy < fast_y;
    any_source = any_source || source;
    fit.identity = fit.identity && source && static_cast<int>(fx) == (u0 + k) * kWeightOne &&
                   static_cast<int>(fy) == v * kWeightOne;
    if (InRawImage(cal, exact.x[k], exact.y[k])) {
      fit.error = std::max(fit.error, core::Hypot(tx - exact.x[k], ty - exact.y[k]));
    }
  }
  fit.kind = all_fast     ? SegmentKind::kInside
             : any_source ? SegmentKind::kMixed
                          : SegmentKind::kOutside;
  return fit;
}

// The two WindowHalfs of a full segment: their own quadratics through the exact map at j = 0, 3.5,
// 7. False when a half fits no window.
bool FitWindow(const StereoRectifier& rectifier, int camera, const CameraCalibration& cal,
               const ExactSegment& exact, int u0, int v, WindowHalf* halves) {
  for (int h = 0; h < 2; ++h) {
    const int k0 = h * kHalf;
    double hx = 0.0;
    double hy = 0.0;
    if (!rectifier.RawPixel(camera, u0 + k0 + 3.5, v, &hx, &hy) ||
        !FitWindowHalf(exact.x + k0, exact.y + k0, hx, hy, cal.width, cal.height, &halves[h])) {
      return false;
    }
  }
  return true;
}

// Largest |table - exact map| of a kWindow segment over the pixels in the raw image.
double WindowError(const WindowHalf* halves, const ExactSegment& exact,
                   const CameraCalibration& cal) {
  double error = 0.0;
  for (int k = 0; k < kSegment; ++k) {
    const WindowHalf& half = halves[k / kHalf];
    const double tx = half.column + (EvalHalf(half.x, k % kHalf) - 4.0) / kFineOne;
    const double ty = half.row + (EvalHalf(half.y, k % kHalf) - 4.0) / kFineOne;
    if (InRawImage(cal, exact.x[k], exact.y[k])) {
      error = std::max(error, core::Hypot(tx - exact.x[k], ty - exact.y[k]));
    }
  }
  return error;
}

// Table segment of camera `camera` (calibration `cal`) at output pixels u0 .. u0 + len - 1 of row
// v: kWindow where both halves fit a window, else the segment's Quadratic.
SegmentFit FitSegment(const StereoRectifier& rectifier, int camera, const CameraCalibration& cal,
                      int u0, int v, int len) {
  ExactSegment exact;
  if (!SampleExactMap(rectifier, camera, u0, v, len, &exact)) return SegmentFit{};
  Quadratic quad;
  FitQuadratic(exact.x[0], exact.mid_x, exact.x[len - 1], len, quad.x);
  FitQuadratic(exact.y[0], exact.mid_y, exact.y[len - 1], len, quad.y);
  SegmentFit fit = CheckQuadratic(quad, exact, cal, u0, v, len);
  WindowHalf halves[2];
  if (fit.kind == SegmentKind::kInside && len == kSegment &&
      FitWindow(rectifier, camera, cal, exact, u0, v, halves)) {
    fit.segment.half[0] = halves[0];
    fit.segment.half[1] = halves[1];
    fit.kind = SegmentKind::kWindow;
    fit.error = WindowError(halves, exact, cal);
  }
  return fit;
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
  const RemapKernel kernel = options.kernel == RemapKernel::kAuto ? BestKernel() : options.kernel;
  if (!KernelSupported(kernel)) return Status::kInvalidArgument;
  kernel_ = kernel;
  const int w = options.width > 0 ? options.width : left.width;
  const int h = options.height > 0 ? options.height : left.height;
  // Raw sizes are bounded so that source offsets fit 32 bits.
  constexpr int kMaxRawSide = 1 << 15;
  if (w > kMaxImageWidth || h > kMaxImageHeight || left.width >= kMaxRawSide ||
      right.width >= kMaxRawSide || left.height >= kMaxRawSide || right.height >= kMaxRawSide) {
    return Status::kInvalidArgument;
  }
  calib_[0] = left;
  calib_[1] = right;
  if (const Status s = ConfigureGeometry(options, w, h); s != Status::kOk) return s;
  width_ = w;
  height_ = h;
  segments_per_row_ = (w + kSegment - 1) / kSegment;
  max_table_error_px_ = 0.0;
  identity_ = left.width == w && left.height == h && right.width == w && right.height == h;
  std::size_t windows = 0;
  for (int c = 0; c < 2; ++c) windows += BuildTable(c);
  window_fraction_ =
      static_cast<double>(windows) / (2.0 * static_cast<double>(h) * segments_per_row_);
  configured_ = true;
  return Status::kOk;
}

Status StereoRectifier::ConfigureGeometry(const RectifyOptions& options, int width, int height) {
  const CameraCalibration& left = calib_[0];
  const CameraCalibration& right = calib_[1];
  const estimator::Pose<double> left_T_right = left.body_T_camera.Inverse() * right.body_T_camera;
  Mat3<double> rect_R_left;
  if (!RectifyingRotation(left_T_right, &rect_R_left)) return Status::kInvalidArgument;
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
  const double sx = static_cast<double>(width) / left.width;
  const double sy = static_cast<double>(height) / left.height;
  camera_.fx = f;
  camera_.fy = f;
  camera_.cx = 0.5 * (left.cx + right.cx) * sx - f * ray_x;
  camera_.cy = 0.5 * (left.cy + right.cy) * sy - f * ray_y;
  camera_.baseline_m = left_T_right.t.norm();
  estimator::Pose<double> left_T_rect;
  left_T_rect.R = rect_R_left.transpose();
  rectified_in_body_ = left.body_T_camera * left_T_rect;
  return Status::kOk;
}

std::size_t StereoRectifier::BuildTable(int camera) {
  Table& table = table_[camera];
  std::size_t windows = 0;
  for (int v = 0; v < height_; ++v) {
    table.row_inside[v] = true;
    table.row_window[v] = true;
    for (int s = 0; s < segments_per_row_; ++s) {
      const std::size_t index = static_cast<std::size_t>(v) * segments_per_row_ + s;
      const int u0 = s * kSegment;
      const SegmentFit fit =
          FitSegment(*this, camera, calib_[camera], u0, v, std::min(kSegment, width_ - u0));
      const bool window = fit.kind == SegmentKind::kWindow;
      table.segment[index] = fit.segment;
      table.kind[index] = fit.kind;
      table.row_inside[v] = table.row_inside[v] && (window || fit.kind == SegmentKind::kInside);
      table.row_window[v] = table.row_window[v] && window;
      identity_ = identity_ && fit.identity;
      max_table_error_px_ = std::max(max_table_error_px_, fit.error);
      windows += window ? 1 : 0;
    }
  }
  return windows;
}

bool StereoRectifier::TablePixel(int camera, int u, int v, float* raw_u, float* raw_v) const {
  if (!configured_ || camera < 0 || camera > 1 || u < 0 || v < 0 || u >= width_ || v >= height_) {
    return false;
  }
  const std::size_t index = static_cast<std::size_t>(v) * segments_per_row_ + u / kSegment;
  if (table_[camera].kind[index] == SegmentKind::kOutside) return false;
  const Segment& seg = table_[camera].segment[index];
  if (table_[camera].kind[index] == SegmentKind::kWindow) {  // inside by construction
    const WindowHalf& half = seg.half[(u % kSegment) / kHalf];
    const int j = u % kHalf;
    constexpr float kRounding = 1 << (kFineToWeight - 1);
    *raw_u = half.column + (static_cast<float>(EvalHalf(half.x, j)) - kRounding) / kFineOne;
    *raw_v = half.row + (static_cast<float>(EvalHalf(half.y, j)) - kRounding) / kFineOne;
    return true;
  }
  const auto k = static_cast<float>(u % kSegment);
  const float fx = EvalSegment(seg.quad.x, k);
  const float fy = EvalSegment(seg.quad.y, k);
  *raw_u = (fx - 0.5f) / kWeightOneF;
  *raw_v = (fy - 0.5f) / kWeightOneF;
  return fx >= 0.0f && fy >= 0.0f &&
         fx < static_cast<float>((calib_[camera].width - 1) * kWeightOne) + 1.0f &&
         fy < static_cast<float>((calib_[camera].height - 1) * kWeightOne) + 1.0f;
}

void StereoRectifier::RemapOne(const GrayView& raw, const Table& table,
                               const MutableGrayView& out) const {
  const rectify_detail::RemapJob job{table.segment,
                                     table.kind,
                                     table.row_inside,
                                     table.row_window,
                                     segments_per_row_,
                                     width_,
                                     height_,
                                     &raw,
                                     &out};
  rectify_detail::Remap(kernel_, job);
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
  if (identity_) {  // already rectified: the table would return every source pixel unchanged
    for (int v = 0; v < height_; ++v) {
      std::memcpy(left_out.Row(v), left_raw.Row(v), static_cast<std::size_t>(width_));
      std::memcpy(right_out.Row(v), right_raw.Row(v), static_cast<std::size_t>(width_));
    }
    return Status::kOk;
  }
  RemapOne(left_raw, table_[0], left_out);
  RemapOne(right_raw, table_[1], right_out);
  return Status::kOk;
}

}  // namespace swf::frontend
