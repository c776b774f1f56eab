#include "swf/frontend/rectify.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace swf::frontend {

using core::Status;
using estimator::Mat3;
using estimator::Vec3;

namespace {

// Fixed point of the source coordinates and bilinear weights: 1/128 px.
constexpr int kWeightBits = 7;
constexpr int kWeightOne = 1 << kWeightBits;
constexpr float kWeightOneF = static_cast<float>(kWeightOne);

// GCC vector extensions (SSE2 / NEON).
using V4f [[gnu::vector_size(16)]] = float;
using V4i [[gnu::vector_size(16)]] = std::int32_t;
using V8s [[gnu::vector_size(16)]] = std::int16_t;
using V8u [[gnu::vector_size(16)]] = std::uint16_t;
using V8b [[gnu::vector_size(8)]] = std::uint8_t;

// Low 16 bits of 8 int32 lanes.
inline V8s Narrow(V4i lo, V4i hi) {
  return __builtin_shufflevector(reinterpret_cast<V8s>(lo), reinterpret_cast<V8s>(hi), 0, 2, 4, 6,
                                 8, 10, 12, 14);
}

inline std::uint16_t Load16(const std::uint8_t* p) {
  std::uint16_t v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// The segment's quadratic; the vector code in RemapOne performs the same float operations.
inline float EvalSegment(const float* c, float k) { return c[0] + k * (c[1] + k * c[2]); }

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
  // Raw sizes are bounded so that source offsets fit 32 bits.
  constexpr int kMaxRawSide = 1 << 15;
  if (w > kMaxImageWidth || h > kMaxImageHeight || left.width >= kMaxRawSide ||
      right.width >= kMaxRawSide || left.height >= kMaxRawSide || right.height >= kMaxRawSide) {
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
  segments_per_row_ = (w + kSegment - 1) / kSegment;

  max_table_error_px_ = 0.0;
  identity_ = left.width == w && left.height == h && right.width == w && right.height == h;
  for (int c = 0; c < 2; ++c) {
    const CameraCalibration& cal = calib_[c];
    Table& table = table_[c];
    // Fixed-point limits (1/128 px): the fast path needs both taps inside (X <= (w-1)*128 - 1);
    // a pixel has a source when 0 <= X <= (w-1)*128.
    const auto fast_x = static_cast<float>((cal.width - 1) * kWeightOne);
    const auto fast_y = static_cast<float>((cal.height - 1) * kWeightOne);
    for (int v = 0; v < h; ++v) {
      for (int s = 0; s < segments_per_row_; ++s) {
        const std::size_t index = static_cast<std::size_t>(v) * segments_per_row_ + s;
        Segment& seg = table.segment[index];
        const int u0 = s * kSegment;
        const int len = std::min(kSegment, w - u0);
        double ex[kSegment] = {};
        double ey[kSegment] = {};
        bool visible = true;
        for (int k = 0; k < len; ++k) visible = visible && RawPixel(c, u0 + k, v, &ex[k], &ey[k]);
        const double last = len - 1;
        const double mid = 0.5 * last;
        double mx = 0.0;
        double my = 0.0;
        visible = visible && RawPixel(c, u0 + mid, v, &mx, &my);
        if (!visible) {  // part of the segment is behind the camera: no source at all
          seg = Segment{};
          table.kind[index] = SegmentKind::kOutside;
          identity_ = false;
          continue;
        }
        // Quadratic through k = 0, last / 2, last (Newton form converted to monomials).
        auto fit = [&](double f0, double fm, double fl, float* coef) {
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
        };
        fit(ex[0], mx, ex[len - 1], seg.x);
        fit(ey[0], my, ey[len - 1], seg.y);
        bool all_fast = true;
        bool any_source = false;
        for (int k = 0; k < len; ++k) {
          const float fx = EvalSegment(seg.x, static_cast<float>(k));
          const float fy = EvalSegment(seg.y, static_cast<float>(k));
          const double tx = (fx - 0.5) / kWeightOne;
          const double ty = (fy - 0.5) / kWeightOne;
          const bool source = fx >= 0.0f && fy >= 0.0f && fx < fast_x + 1.0f && fy < fast_y + 1.0f;
          all_fast = all_fast && fx >= 0.0f && fy >= 0.0f && fx < fast_x && fy < fast_y;
          any_source = any_source || source;
          identity_ = identity_ && source && static_cast<int>(fx) == (u0 + k) * kWeightOne &&
                      static_cast<int>(fy) == v * kWeightOne;
          if (ex[k] >= 0.0 && ey[k] >= 0.0 && ex[k] <= cal.width - 1 && ey[k] <= cal.height - 1) {
            max_table_error_px_ = std::max(max_table_error_px_, std::hypot(tx - ex[k], ty - ey[k]));
          }
        }
        table.kind[index] = all_fast     ? SegmentKind::kInside
                            : any_source ? SegmentKind::kMixed
                                         : SegmentKind::kOutside;
      }
    }
  }
  configured_ = true;
  return Status::kOk;
}

bool StereoRectifier::TablePixel(int camera, int u, int v, float* raw_u, float* raw_v) const {
  if (!configured_ || camera < 0 || camera > 1 || u < 0 || v < 0 || u >= width_ || v >= height_) {
    return false;
  }
  const std::size_t index = static_cast<std::size_t>(v) * segments_per_row_ + u / kSegment;
  if (table_[camera].kind[index] == SegmentKind::kOutside) return false;
  const Segment& seg = table_[camera].segment[index];
  const auto k = static_cast<float>(u % kSegment);
  const float fx = EvalSegment(seg.x, k);
  const float fy = EvalSegment(seg.y, k);
  *raw_u = (fx - 0.5f) / kWeightOneF;
  *raw_v = (fy - 0.5f) / kWeightOneF;
  return fx >= 0.0f && fy >= 0.0f &&
         fx < static_cast<float>((calib_[camera].width - 1) * kWeightOne) + 1.0f &&
         fy < static_cast<float>((calib_[camera].height - 1) * kWeightOne) + 1.0f;
}

void StereoRectifier::RemapOne(const GrayView& raw, const Table& table,
                               const MutableGrayView& out) const {
  constexpr int kRow = kMaxSegmentsPerRow * kSegment;
  alignas(16) std::int32_t offset[kRow];
  alignas(16) std::int16_t wx[kRow];
  alignas(16) std::int16_t wy[kRow];
  alignas(16) std::uint8_t blended[kRow];
  const int w = width_;
  const int padded = segments_per_row_ * kSegment;
  const std::int32_t stride = raw.stride;
  const V4i stride4 = {stride, stride, stride, stride};
  const V4f lane = {0.0f, 1.0f, 2.0f, 3.0f};
  const int max_x = raw.width - 1;
  const int max_y = raw.height - 1;
  for (int v = 0; v < height_; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * segments_per_row_;
    const Segment* segs = table.segment + row;
    const SegmentKind* kinds = table.kind + row;
    // 1. Source coordinates of the row in 1/128 px: offset of the top-left tap and the weights.
    for (int s = 0; s < segments_per_row_; ++s) {
      const int u0 = s * kSegment;
      if (kinds[s] != SegmentKind::kInside) {
        for (int k = 0; k < kSegment; ++k) {
          offset[u0 + k] = 0;  // a harmless tap; the pixels are redone in step 4
          wx[u0 + k] = 0;
          wy[u0 + k] = 0;
        }
        continue;
      }
      const Segment& seg = segs[s];
      const V4f x0 = {seg.x[0], seg.x[0], seg.x[0], seg.x[0]};
      const V4f x1 = {seg.x[1], seg.x[1], seg.x[1], seg.x[1]};
      const V4f x2 = {seg.x[2], seg.x[2], seg.x[2], seg.x[2]};
      const V4f y0 = {seg.y[0], seg.y[0], seg.y[0], seg.y[0]};
      const V4f y1 = {seg.y[1], seg.y[1], seg.y[1], seg.y[1]};
      const V4f y2 = {seg.y[2], seg.y[2], seg.y[2], seg.y[2]};
      for (int q = 0; q < kSegment; q += 8) {
        const V4f k_lo = lane + static_cast<float>(q);
        const V4f k_hi = k_lo + 4.0f;
        // The same operations as EvalSegment, 4 lanes at a time; truncation rounds.
        const V4i fx_lo = __builtin_convertvector(x0 + k_lo * (x1 + k_lo * x2), V4i);
        const V4i fx_hi = __builtin_convertvector(x0 + k_hi * (x1 + k_hi * x2), V4i);
        const V4i fy_lo = __builtin_convertvector(y0 + k_lo * (y1 + k_lo * y2), V4i);
        const V4i fy_hi = __builtin_convertvector(y0 + k_hi * (y1 + k_hi * y2), V4i);
        const V4i off_lo = (fy_lo >> kWeightBits) * stride4 + (fx_lo >> kWeightBits);
        const V4i off_hi = (fy_hi >> kWeightBits) * stride4 + (fx_hi >> kWeightBits);
        const V8s ax = Narrow(fx_lo, fx_hi) & (kWeightOne - 1);
        const V8s ay = Narrow(fy_lo, fy_hi) & (kWeightOne - 1);
        std::memcpy(offset + u0 + q, &off_lo, sizeof(off_lo));
        std::memcpy(offset + u0 + q + 4, &off_hi, sizeof(off_hi));
        std::memcpy(wx + u0 + q, &ax, sizeof(ax));
        std::memcpy(wy + u0 + q, &ay, sizeof(ay));
      }
    }
    for (int u = w; u < padded; ++u) offset[u] = 0;  // lanes past the last pixel
    // 2. Gather the two source bytes of the top and of the bottom row (one 16-bit load each,
    // straight into a vector lane) and 3. blend, 8 lanes of 16 bits (exact; file comment).
    const std::uint8_t* src = raw.data;
    for (int u = 0; u < padded; u += 8) {
      const std::int32_t* off = offset + u;
      V8u t;
      V8u b;
      const std::uint8_t* below = src + stride;
      for (int i = 0; i < 8; ++i) {  // unrolled: one 16-bit lane insert per load
        t[i] = Load16(src + off[i]);
        b[i] = Load16(below + off[i]);
      }
      V8s ax;
      V8s ay;
      std::memcpy(&ax, wx + u, sizeof(ax));
      std::memcpy(&ay, wy + u, sizeof(ay));
      const V8s bx = kWeightOne - ax;
      const V8s upper = reinterpret_cast<V8s>(t & 0xFF) * bx + reinterpret_cast<V8s>(t >> 8) * ax;
      const V8s lower = reinterpret_cast<V8s>(b & 0xFF) * bx + reinterpret_cast<V8s>(b >> 8) * ax;
      // upper + (lower - upper) ay / 128 with 16-bit products: split the difference into its
      // high (signed) and low (unsigned) byte.
      const V8s d = lower - upper;
      const V8s mid = upper + (((d >> 8) * ay) << 1) + (((d & 0xFF) * ay) >> kWeightBits);
      const V8s result = (mid + (kWeightOne / 2)) >> kWeightBits;
      const V8b bytes = __builtin_convertvector(result, V8b);
      std::memcpy(blended + u, &bytes, sizeof(bytes));
    }
    std::uint8_t* o = out.Row(v);
    std::memcpy(o, blended, static_cast<std::size_t>(w));
    // 4. Segments not entirely inside: per-pixel checks with the same arithmetic in scalar.
    for (int s = 0; s < segments_per_row_; ++s) {
      if (kinds[s] == SegmentKind::kInside) continue;
      const int u0 = s * kSegment;
      const int len = std::min(kSegment, w - u0);
      if (kinds[s] == SegmentKind::kOutside) {
        std::memset(o + u0, 0, static_cast<std::size_t>(len));
        continue;
      }
      for (int k = 0; k < len; ++k) {
        const float fx = EvalSegment(segs[s].x, static_cast<float>(k));
        const float fy = EvalSegment(segs[s].y, static_cast<float>(k));
        if (!(fx >= 0.0f && fy >= 0.0f && fx < static_cast<float>(max_x * kWeightOne) + 1.0f &&
              fy < static_cast<float>(max_y * kWeightOne) + 1.0f)) {
          o[u0 + k] = 0;
          continue;
        }
        const int ix = static_cast<int>(fx);
        const int iy = static_cast<int>(fy);
        // The last row/column is reached with the full weight on the second tap.
        const int cx = std::min(ix >> kWeightBits, max_x - 1);
        const int cy = std::min(iy >> kWeightBits, max_y - 1);
        const int ax = ix - cx * kWeightOne;
        const int ay = iy - cy * kWeightOne;
        const std::uint8_t* s0 = raw.Row(cy) + cx;
        const std::uint8_t* s1 = s0 + stride;
        const int upper = s0[0] * (kWeightOne - ax) + s0[1] * ax;
        const int lower = s1[0] * (kWeightOne - ax) + s1[1] * ax;
        o[u0 + k] = static_cast<std::uint8_t>(
            (upper * (kWeightOne - ay) + lower * ay + kWeightOne * kWeightOne / 2) >>
            (2 * kWeightBits));
      }
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
