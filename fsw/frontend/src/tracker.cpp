#include "swf/frontend/tracker.hpp"

#include <algorithm>
#include <cmath>

namespace swf::frontend {

using core::Status;

namespace {

// Samples the (warped) patch at centre (x, y); false when it leaves the image (unless clamped).
// grid_radius >= 0 says the offsets are the plain integer grid of that radius (no warp), which
// takes the shared-weight fast path when the patch is inside the image.
bool Sample(const GrayView& image, const float* offsets, int count, int grid_radius, bool clamped,
            float margin, float x, float y, float* samples, float* mean) {
  float sum = 0.0f;
  if (grid_radius >= 0 && InsideForSampling(image, x, y, margin)) {
    SampleGrid(image, x, y, grid_radius, samples);
    for (int k = 0; k < count; ++k) sum += samples[k];
  } else if (clamped) {
    for (int k = 0; k < count; ++k) {
      samples[k] = SampleBilinearClamped(image, x + offsets[2 * k], y + offsets[2 * k + 1]);
      sum += samples[k];
    }
  } else {
    if (!InsideForSampling(image, x, y, margin)) return false;
    for (int k = 0; k < count; ++k) {
      samples[k] = SampleBilinear(image, x + offsets[2 * k], y + offsets[2 * k + 1]);
      sum += samples[k];
    }
  }
  *mean = sum / static_cast<float>(count);
  return true;
}

// The image's gradient at each sample by central differences of bilinear samples one pixel to
// either side (the caller guarantees a margin of the offsets' reach + 2).
void SampleGradients(const GrayView& image, const float* offsets, int count, float x, float y,
                     float* ix, float* iy) {
  for (int k = 0; k < count; ++k) {
    const float sx = x + offsets[2 * k];
    const float sy = y + offsets[2 * k + 1];
    ix[k] = 0.5f * (SampleBilinear(image, sx + 1.0f, sy) - SampleBilinear(image, sx - 1.0f, sy));
    iy[k] = 0.5f * (SampleBilinear(image, sx, sy + 1.0f) - SampleBilinear(image, sx, sy - 1.0f));
  }
}

// The normal equations of a translation with Jacobian rows (jx, jy) per sample: the rows
// centred by their mean times `centre` (1/count when the brightness offset is eliminated, 0
// without) and [sum c c^T].
struct NormalEquations {
  float cx[kMaxPatchPixels];
  float cy[kMaxPatchPixels];
  float hxx = 0.0f;
  float hxy = 0.0f;
  float hyy = 0.0f;

  void Build(const float* jx, const float* jy, int count, float centre) {
    float mean_x = 0.0f;
    float mean_y = 0.0f;
    for (int k = 0; k < count; ++k) {
      mean_x += jx[k];
      mean_y += jy[k];
    }
    mean_x *= centre;
    mean_y *= centre;
    hxx = hxy = hyy = 0.0f;
    for (int k = 0; k < count; ++k) {
      cx[k] = jx[k] - mean_x;
      cy[k] = jy[k] - mean_y;
      hxx += cx[k] * cx[k];
      hxy += cx[k] * cy[k];
      hyy += cy[k] * cy[k];
    }
  }
  float Det() const { return hxx * hyy - hxy * hxy; }
  // The step d of [sum c c^T] d = sum c e for residuals e; false when singular.
  bool Step(const float* e, int count, float* dx, float* dy) const {
    float bx = 0.0f;
    float by = 0.0f;
    for (int k = 0; k < count; ++k) {
      bx += cx[k] * e[k];
      by += cy[k] * e[k];
    }
    const float det = Det();
    if (!(det > 0.0f)) return false;
    *dx = (hyy * bx - hxy * by) / det;
    *dy = (hxx * by - hxy * bx) / det;
    return true;
  }
};

}  // namespace

float Zncc(const float* a, float mean_a, const float* b, float mean_b, int count) {
  float num = 0.0f;
  float den_a = 0.0f;
  float den_b = 0.0f;
  for (int k = 0; k < count; ++k) {
    const float da = a[k] - mean_a;
    const float db = b[k] - mean_b;
    num += da * db;
    den_a += da * da;
    den_b += db * db;
  }
  const float den = std::sqrt(den_a * den_b);
  return den > 0.0f ? num / den : 0.0f;
}

float ScharrX(const float* g, int stride) {
  const float* up = g - stride;
  const float* down = g + stride;
  return (3.0f * (up[1] - up[-1]) + 10.0f * (g[1] - g[-1]) + 3.0f * (down[1] - down[-1])) *
         (1.0f / 32.0f);
}

float ScharrY(const float* g, int stride) {
  const float* up = g - stride;
  const float* down = g + stride;
  return (3.0f * (down[-1] - up[-1]) + 10.0f * (down[0] - up[0]) + 3.0f * (down[1] - up[1])) *
         (1.0f / 32.0f);
}

Eigen::Matrix3d PlaneHomography(const estimator::StereoCamera<double>& camera,
                                const estimator::Pose<double>& cur_T_ref, double depth_ref_m) {
  Eigen::Matrix3d k;
  k << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0;
  Eigen::Matrix3d k_inv;
  k_inv << 1.0 / camera.fx, 0.0, -camera.cx / camera.fx, 0.0, 1.0 / camera.fy,
      -camera.cy / camera.fy, 0.0, 0.0, 1.0;
  const Eigen::Vector3d n(0.0, 0.0, 1.0);
  const Eigen::Matrix3d euclidean = cur_T_ref.R + cur_T_ref.t * n.transpose() / depth_ref_m;
  return k * euclidean * k_inv;
}

Status PatchTracker::Configure(const TrackerOptions& options) {
  configured_ = false;
  if (options.patch_radius < 1 || options.patch_radius > kMaxPatchRadius ||
      options.pyramid_levels < 1 || options.pyramid_levels > kMaxPyramidLevels ||
      options.max_iterations < 1 || !(options.epsilon_px > 0.0f) ||
      !(options.coarse_epsilon_px > 0.0f) || !(options.max_prediction_error_px > 0.0f) ||
      options.search_radius_px < 1 || options.search_radius_px > kMaxSearchRadius) {
    return Status::kInvalidArgument;
  }
  options_ = options;
  configured_ = true;
  return Status::kOk;
}

bool PatchTracker::ExtractTemplate(const GrayView& image, float x, float y,
                                   PatchTemplate* tmpl) const {
  const int r = options_.patch_radius;
  if (!InsideForSampling(image, x, y, static_cast<float>(r) + 1.0f)) return false;
  // One grid one pixel larger than the patch gives values and Scharr derivatives.
  constexpr int kExt = 2 * kMaxPatchRadius + 3;
  float grid[kExt * kExt];
  const int side = 2 * r + 1;
  const int ext = side + 2;
  SampleGrid(image, x, y, r + 1, grid);
  tmpl->radius = r;
  tmpl->ref_x = x;
  tmpl->ref_y = y;
  for (int j = 0, k = 0; j < side; ++j) {
    const float* g = grid + (j + 1) * ext + 1;
    for (int i = 0; i < side; ++i, ++k) {
      tmpl->value[k] = g[i];
      tmpl->gx[k] = ScharrX(g + i, ext);
      tmpl->gy[k] = ScharrY(g + i, ext);
    }
  }
  return true;
}

void PatchTracker::ExtractTemplateClamped(const GrayView& image, float x, float y,
                                          PatchTemplate* tmpl) const {
  const int r = options_.patch_radius;
  tmpl->radius = r;
  tmpl->ref_x = x;
  tmpl->ref_y = y;
  for (int j = -r, k = 0; j <= r; ++j) {
    for (int i = -r; i <= r; ++i, ++k) {
      const float px = x + static_cast<float>(i);
      const float py = y + static_cast<float>(j);
      float g[9];  // 3x3 neighbourhood, row-major
      for (int dy = -1, n = 0; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx, ++n) {
          g[n] = SampleBilinearClamped(image, px + static_cast<float>(dx),
                                       py + static_cast<float>(dy));
        }
      }
      tmpl->value[k] = g[4];
      tmpl->gx[k] = ScharrX(g + 4, 3);
      tmpl->gy[k] = ScharrY(g + 4, 3);
    }
  }
}

bool PatchTracker::Align(const GrayView& image, const float* value, const float* gx,
                         const float* gy, const float* offsets, int count, int grid_radius,
                         bool clamped, bool second_order, float epsilon, float* cx, float* cy,
                         float* quality) const {
  float mean_t = 0.0f;
  float max_offset = 0.0f;
  for (int k = 0; k < count; ++k) {
    mean_t += value[k];
    max_offset =
        std::fmax(max_offset, std::fmax(std::fabs(offsets[2 * k]), std::fabs(offsets[2 * k + 1])));
  }
  const float inv_n = 1.0f / static_cast<float>(count);
  mean_t *= inv_n;
  // With the offset b eliminated the gradients and residuals are centred; with constant
  // brightness they are not (a ramp across the patch then also constrains the translation).
  const float centre = options_.brightness_offset ? inv_n : 0.0f;
  const float offset_t = options_.brightness_offset ? mean_t : 0.0f;
  NormalEquations normal;
  normal.Build(gx, gy, count, centre);
  // Reject an ill-conditioned (edge-like or flat) patch: smallest eigenvalue too small.
  const float trace = normal.hxx + normal.hyy;
  const float min_eig =
      0.5f * (trace - std::sqrt(std::fmax(0.0f, trace * trace - 4.0f * normal.Det())));
  if (!(min_eig > 1e-2f * static_cast<float>(count))) return false;

  // The second-order Jacobian samples one more pixel around every sample.
  const float margin = max_offset + (second_order ? 2.0f : 1.0f);
  float ix[kMaxPatchPixels];
  float iy[kMaxPatchPixels];
  float residual[kMaxPatchPixels];
  float samples[kMaxPatchPixels];
  float x = *cx;
  float y = *cy;
  float mean_s = 0.0f;
  bool sampled_at_xy = false;
  for (int it = 0; it < options_.max_iterations; ++it) {
    if (!Sample(image, offsets, count, grid_radius, clamped, margin, x, y, samples, &mean_s))
      return false;
    sampled_at_xy = true;
    const float offset_s = options_.brightness_offset ? mean_s : 0.0f;
    for (int k = 0; k < count; ++k) residual[k] = (value[k] - offset_t) - (samples[k] - offset_s);
    if (second_order) {
      // ESM: the mean of the template's mapped gradient and the image's at the samples.
      SampleGradients(image, offsets, count, x, y, ix, iy);
      for (int k = 0; k < count; ++k) {
        ix[k] = 0.5f * (ix[k] + gx[k]);
        iy[k] = 0.5f * (iy[k] + gy[k]);
      }
      normal.Build(ix, iy, count, centre);
    }
    float dx = 0.0f;
    float dy = 0.0f;
    if (!normal.Step(residual, count, &dx, &dy)) return false;
    x += dx;
    y += dy;
    sampled_at_xy = false;
    if (!(std::isfinite(x) && std::isfinite(y))) return false;
    if (dx * dx + dy * dy < epsilon * epsilon) break;
  }
  if (!sampled_at_xy) {
    if (!Sample(image, offsets, count, grid_radius, clamped, margin, x, y, samples, &mean_s))
      return false;
  }
  *quality = Zncc(value, mean_t, samples, mean_s, count);
  *cx = x;
  *cy = y;
  return true;
}

bool PatchTracker::TrackFlow(const Pyramid& prev, const Pyramid& cur, float prev_x, float prev_y,
                             float* cur_x, float* cur_y, float* quality) const {
  if (!configured_) return false;
  const int levels = std::min(std::min(prev.NumLevels(), cur.NumLevels()), options_.pyramid_levels);
  const int r = options_.patch_radius;
  const int count = (2 * r + 1) * (2 * r + 1);
  float offsets[2 * kMaxPatchPixels];
  for (int j = -r, k = 0; j <= r; ++j) {
    for (int i = -r; i <= r; ++i, ++k) {
      offsets[2 * k] = static_cast<float>(i);
      offsets[2 * k + 1] = static_cast<float>(j);
    }
  }
  // Work in displacement: the guess is propagated from coarse to fine.
  float dx = *cur_x - prev_x;
  float dy = *cur_y - prev_y;
  float q = 0.0f;
  PatchTemplate tmpl;
  for (int l = levels - 1; l >= 0; --l) {
    const float scale = 1.0f / static_cast<float>(1 << l);
    const float px = prev_x * scale;
    const float py = prev_y * scale;
    // Coarse levels replicate the border so patches near it still get a coarse estimate; the
    // finest level is strict (a feature leaving the image is lost).
    const bool clamped = l > 0;
    if (clamped) {
      if (!ExtractTemplate(prev.Level(l), px, py, &tmpl)) {
        ExtractTemplateClamped(prev.Level(l), px, py, &tmpl);
      }
    } else if (!ExtractTemplate(prev.Level(l), px, py, &tmpl)) {
      return false;
    }
    float x = px + dx * scale;
    float y = py + dy * scale;
    const float epsilon = l == 0 ? options_.epsilon_px : options_.coarse_epsilon_px;
    if (!Align(cur.Level(l), tmpl.value, tmpl.gx, tmpl.gy, offsets, count, r, clamped, false,
               epsilon, &x, &y, &q)) {
      if (l == 0) return false;
      continue;
    }
    dx = (x - px) / scale;
    dy = (y - py) / scale;
  }
  *cur_x = prev_x + dx;
  *cur_y = prev_y + dy;
  *quality = q;
  return q >= options_.min_zncc;
}

bool PatchTracker::WarpTemplate(const PatchTemplate& tmpl, const Eigen::Matrix3d& homography,
                                float* offsets, float* gx, float* gy) const {
  if (!configured_ || tmpl.radius < 1 || tmpl.radius > kMaxPatchRadius) return false;
  const int r = tmpl.radius;
  const Eigen::Vector3d c = homography * Eigen::Vector3d(tmpl.ref_x, tmpl.ref_y, 1.0);
  if (!(c.z() > 1e-9)) return false;
  const double ux = c.x() / c.z();
  const double uy = c.y() / c.z();
  // A = d(H p)/dp at p_ref (quotient rule), used to map template gradients: g = A^-T grad T.
  Eigen::Matrix2d a;
  a(0, 0) = (homography(0, 0) - ux * homography(2, 0)) / c.z();
  a(0, 1) = (homography(0, 1) - ux * homography(2, 1)) / c.z();
  a(1, 0) = (homography(1, 0) - uy * homography(2, 0)) / c.z();
  a(1, 1) = (homography(1, 1) - uy * homography(2, 1)) / c.z();
  const double det = a.determinant();
  if (!(std::fabs(det) > 1e-6)) return false;
  const Eigen::Matrix2d a_inv_t = a.inverse().transpose();
  for (int j = -r, k = 0; j <= r; ++j) {
    for (int i = -r; i <= r; ++i, ++k) {
      const Eigen::Vector3d p = homography * Eigen::Vector3d(tmpl.ref_x + i, tmpl.ref_y + j, 1.0);
      offsets[2 * k] = static_cast<float>(p.x() / p.z() - ux);
      offsets[2 * k + 1] = static_cast<float>(p.y() / p.z() - uy);
      const Eigen::Vector2d g = a_inv_t * Eigen::Vector2d(tmpl.gx[k], tmpl.gy[k]);
      gx[k] = static_cast<float>(g.x());
      gy[k] = static_cast<float>(g.y());
    }
  }
  return true;
}

bool PatchTracker::TrackWarped(const GrayView& image, const PatchTemplate& tmpl,
                               const Eigen::Matrix3d& homography, float* cur_x, float* cur_y,
                               float* quality) const {
  float offsets[2 * kMaxPatchPixels];
  float gx[kMaxPatchPixels];
  float gy[kMaxPatchPixels];
  if (!WarpTemplate(tmpl, homography, offsets, gx, gy)) return false;
  const int count = (2 * tmpl.radius + 1) * (2 * tmpl.radius + 1);
  const float x0 = *cur_x;
  const float y0 = *cur_y;
  float x = x0;
  float y = y0;
  float q = 0.0f;
  if (!Align(image, tmpl.value, gx, gy, offsets, count, -1, false, true, options_.epsilon_px, &x,
             &y, &q)) {
    return false;
  }
  const float ex = x - x0;
  const float ey = y - y0;
  if (ex * ex + ey * ey > options_.max_prediction_error_px * options_.max_prediction_error_px) {
    return false;
  }
  *cur_x = x;
  *cur_y = y;
  *quality = q;
  return q >= options_.min_zncc;
}

bool PatchTracker::SearchWarped(const GrayView& image, const PatchTemplate& tmpl,
                                const Eigen::Matrix3d& homography, float* cur_x, float* cur_y,
                                float* quality) const {
  const int radius = options_.search_radius_px;
  float offsets[2 * kMaxPatchPixels];
  float gx[kMaxPatchPixels];
  float gy[kMaxPatchPixels];
  if (radius < 1 || !WarpTemplate(tmpl, homography, offsets, gx, gy)) return false;
  const int count = (2 * tmpl.radius + 1) * (2 * tmpl.radius + 1);
  // Every candidate is the prediction moved by whole pixels, so each sample keeps its bilinear
  // weights over the whole search: its cell and weights are computed once.
  int cell_x[kMaxPatchPixels];
  int cell_y[kMaxPatchPixels];
  float ax[kMaxPatchPixels];
  float ay[kMaxPatchPixels];
  float centred[kMaxPatchPixels];  // the template minus its mean
  int min_x = 1 << 30;
  int min_y = 1 << 30;
  int max_x = -(1 << 30);
  int max_y = -(1 << 30);
  float mean_t = 0.0f;
  for (int k = 0; k < count; ++k) {
    const float sx = *cur_x + offsets[2 * k];
    const float sy = *cur_y + offsets[2 * k + 1];
    if (!(std::isfinite(sx) && std::isfinite(sy)) || std::fabs(sx) > 1e6f || std::fabs(sy) > 1e6f) {
      return false;
    }
    cell_x[k] = static_cast<int>(std::floor(sx));
    cell_y[k] = static_cast<int>(std::floor(sy));
    ax[k] = sx - static_cast<float>(cell_x[k]);
    ay[k] = sy - static_cast<float>(cell_y[k]);
    min_x = std::min(min_x, cell_x[k]);
    min_y = std::min(min_y, cell_y[k]);
    max_x = std::max(max_x, cell_x[k]);
    max_y = std::max(max_y, cell_y[k]);
    mean_t += tmpl.value[k];
  }
  mean_t /= static_cast<float>(count);
  float norm_t = 0.0f;
  for (int k = 0; k < count; ++k) {
    centred[k] = tmpl.value[k] - mean_t;
    norm_t += centred[k] * centred[k];
  }
  if (!(norm_t > 0.0f)) return false;
  float best = -2.0f;
  int best_i = 0;
  int best_j = 0;
  for (int j = -radius; j <= radius; ++j) {
    if (min_y + j < 0 || max_y + j + 1 >= image.height) continue;
    for (int i = -radius; i <= radius; ++i) {
      if (min_x + i < 0 || max_x + i + 1 >= image.width) continue;
      float sum = 0.0f;
      float sum2 = 0.0f;
      float cross = 0.0f;
      for (int k = 0; k < count; ++k) {
        const std::uint8_t* r0 = image.Row(cell_y[k] + j) + cell_x[k] + i;
        const std::uint8_t* r1 = r0 + image.stride;
        const float top = static_cast<float>(r0[0]) + ax[k] * static_cast<float>(r0[1] - r0[0]);
        const float bottom = static_cast<float>(r1[0]) + ax[k] * static_cast<float>(r1[1] - r1[0]);
        const float s = top + ay[k] * (bottom - top);
        sum += s;
        sum2 += s * s;
        cross += s * centred[k];
      }
      const float var = sum2 - sum * sum / static_cast<float>(count);
      if (!(var > 0.0f)) continue;
      const float zncc = cross / std::sqrt(var * norm_t);
      if (zncc > best) {  // ties: the first in raster order
        best = zncc;
        best_i = i;
        best_j = j;
      }
    }
  }
  if (best < options_.min_zncc) return false;
  const float px = *cur_x;
  const float py = *cur_y;
  float x = px + static_cast<float>(best_i);
  float y = py + static_cast<float>(best_j);
  float q = 0.0f;
  if (!Align(image, tmpl.value, gx, gy, offsets, count, -1, false, true, options_.epsilon_px, &x,
             &y, &q) ||
      q < options_.min_zncc) {
    return false;
  }
  const float limit = static_cast<float>(radius) + 1.0f;
  if (std::fabs(x - px) > limit || std::fabs(y - py) > limit) return false;
  *cur_x = x;
  *cur_y = y;
  *quality = q;
  return true;
}

}  // namespace swf::frontend
