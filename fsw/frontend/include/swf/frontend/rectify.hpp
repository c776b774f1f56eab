// Stereo rectification from a calibrated rig (pinhole + radial-tangential distortion +
// extrinsics), computed once at start-up as a compact remap table and applied per frame with
// bilinear interpolation in fixed point.
//
// Rectifying rotation (Bouguet-style): with left_T_right = {R, t} (t: right centre in the left
// frame), the common optical axis is the "half-way" rotation z_mid = Exp(Log(R)/2) e_z; the
// rectified axes are e1 = t/|t| (the baseline becomes +x, as estimator::StereoCamera requires),
// e2 = normalize(z_mid x e1), e3 = e1 x e2, and rect_R_left = [e1 e2 e3]^T,
// rect_R_right = rect_R_left R. Both rectified cameras share K_new = [f 0 cx; 0 f cy; 0 0 1].
// Remap: rectified pixel -> ray K_new^-1 (u,v,1) -> raw camera frame cam_R_rect ray ->
// distortion (x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2), y likewise)
// -> raw pixel.
//
// Table: each output row is cut into segments of kSegment pixels, 32 bytes per segment instead of
// a per-pixel entry. A segment whose 8-pixel halves each take all their taps from a 16 x 3-byte raw
// window (kWindow; every segment of the benchmark and EuRoC rigs) stores per half the window origin
// and, relative to it, each source coordinate as a quadratic in the pixel index with 16-bit
// coefficients (WindowHalf, 1/1024 px), through the exact map at the half's first, middle and last
// pixel. The other segments store one single-precision quadratic per coordinate over the 16 pixels
// (Quadratic, 1/128 px). Both fold in the offset that makes truncation round to 1/128 px.
// Configure measures the largest distance between what Rectify samples (before that rounding) and
// the exact map over every output pixel whose source is inside the raw image (MaxTableErrorPx;
// 0.0026 / 0.0024 px for the benchmark / EuRoC rigs, mostly the 16-bit coefficients' rounding). A
// segment with a pixel behind a camera has no source at all.
// Per frame: the coordinates are evaluated (16-bit rounding multiply-highs for kWindow, float
// vectors for the rest, in every kernel the same operations as the scalar check) and rounded to
// 1/128 px, the 2x2 source bytes are fetched, and the blend runs in 16-bit lanes. It is exact
// integer arithmetic: top/bottom = p0 (128 - wx) + p1 wx, mid = top + round((bottom - top) wy /
// 128), out = round(mid / 128) (halves rounded up), so every kernel (RemapKernel) gives the same
// bytes. The portable kernel (GCC vector extensions) fetches the taps with two 16-bit loads per
// pixel; the SSSE3 / AVX2 / NEON kernels fetch those of a kWindow segment from three 16-byte rows
// with byte shuffles. A rig whose table rounds every output pixel to itself (already rectified:
// the simulator) is copied row by row, which is the output the table would give.
#pragma once

#include <cstddef>
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

// Gather/blend kernel of Rectify. Every kernel gives bit-identical output; kAuto picks the fastest
// one this CPU supports once in Configure (x86-64: AVX2, else SSSE3, else portable; AArch64: NEON).
// Naming another kernel forces it (tests and benchmarks); Configure rejects one the CPU lacks.
enum class RemapKernel : std::uint8_t { kAuto, kPortable, kSsse3, kAvx2, kNeon };

struct RectifyOptions {
  int width = 0;  // output size; 0 = the input size
  int height = 0;
  double focal_scale = 1.0;  // < 1 zooms out (keeps more of the raw field of view)
  RemapKernel kernel = RemapKernel::kAuto;
};

namespace rectify_detail {
constexpr int kSegment = 16;  // output pixels per table segment
// Every pixel's source is inside (fast path), some are (per-pixel checks), none is (zeros).
// kWindow: inside, and each 8-pixel half reads its taps from a 16 x 3 byte window (rows r .. r + 2,
// columns c .. c + 15 of the raw image), so that the SIMD kernels fetch the taps with three 16-byte
// loads and byte shuffles instead of 16 loads.
enum class SegmentKind : std::uint8_t { kInside, kWindow, kMixed, kOutside };
// kInside / kMixed: raw u = x[0] + k (x[1] + k x[2]), k = 0 .. kSegment - 1 (1/128 px, floats).
struct Quadratic {
  float x[3];
  float y[3];
};
// kWindow: one 8-pixel half in 16-bit fixed point, relative to its window so that a 16-bit lane
// holds it: X(j) = x[0] + ((j x[1] + 4) >> 3) + ((j^2 x[2] + 32) >> 6) (1/1024 px from column,
// j = 0 .. 7; the shifts are what a rounding multiply-high, pmulhrsw / sqrdmulh, by j 2^12 and
// j^2 2^9 gives), Y likewise from row; Configure keeps X in [0, 15) px and Y in [0, 2) px. 16
// bytes: a 128-bit SIMD lane holds a half's entry.
struct WindowHalf {
  std::int16_t x[3];
  std::int16_t y[3];
  std::int16_t column;  // top-left raw pixel of the window
  std::int16_t row;
};
// 32 bytes; which member is live follows the segment's kind.
struct alignas(32) Segment {
  union {
    Quadratic quad;
    WindowHalf half[2];
  };
};
}  // namespace rectify_detail

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
  // The raw pixel the table uses for output pixel (u, v) before rounding to 1/128 px (what
  // Rectify samples). False when the table marks that pixel as having no source.
  bool TablePixel(int camera, int u, int v, float* raw_u, float* raw_v) const;
  // Largest |table - exact map| over the output pixels with a source, both cameras (pixels).
  double MaxTableErrorPx() const { return max_table_error_px_; }
  // True when the table maps every output pixel to itself (both cameras) and Rectify copies rows.
  bool IsIdentity() const { return identity_; }
  // The kernel Configure selected (never kAuto once configured).
  RemapKernel Kernel() const { return kernel_; }
  // Fraction of the table's segments (both cameras) that the shuffle kernels fetch by windows.
  double WindowFraction() const { return window_fraction_; }

 private:
  // Remap table of one camera (file comment). Segment s of output row v is entry
  // v * segments_per_row_ + s.
  static constexpr int kSegment = rectify_detail::kSegment;
  static constexpr int kMaxSegmentsPerRow = (kMaxImageWidth + kSegment - 1) / kSegment;
  static constexpr std::size_t kMaxSegments =
      static_cast<std::size_t>(kMaxSegmentsPerRow) * kMaxImageHeight;
  using SegmentKind = rectify_detail::SegmentKind;
  using Segment = rectify_detail::Segment;
  struct Table {
    Segment segment[kMaxSegments];  // 32-byte aligned: the AVX2 kernel loads a whole entry
    SegmentKind kind[kMaxSegments];
    bool row_inside[kMaxImageHeight];  // every segment of the row is kInside or kWindow
    bool row_window[kMaxImageHeight];  // every segment of the row is kWindow
  };
  // Configure's steps: the rectifying rotations and the rectified camera (kInvalidArgument when
  // the rig cannot be rectified), then one camera's table (returns its count of kWindow segments).
  core::Status ConfigureGeometry(const RectifyOptions& options, int width, int height);
  std::size_t BuildTable(int camera);
  void RemapOne(const GrayView& raw, const Table& table, const MutableGrayView& out) const;

  CameraCalibration calib_[2]{};
  estimator::Mat3<double> rect_from_cam_[2];
  estimator::StereoCamera<double> camera_{};
  estimator::Pose<double> rectified_in_body_{};
  int width_ = 0;
  int height_ = 0;
  int segments_per_row_ = 0;
  double max_table_error_px_ = 0.0;
  double window_fraction_ = 0.0;
  RemapKernel kernel_ = RemapKernel::kPortable;
  bool identity_ = false;
  bool configured_ = false;
  Table table_[2];
};

}  // namespace swf::frontend
