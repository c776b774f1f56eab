// Synthetic images with exactly known geometry for the front end's unit tests and benchmark: a
// smooth, band-limited texture (a sum of plane waves with wavelengths of 7-120 px) that can be
// sampled analytically at any real position, so shifted, disparate or warped copies are exact up
// to the final 8-bit rounding. Not part of the flight library (it allocates).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace swf::frontend::synthetic {

class Texture {
 public:
  explicit Texture(std::uint32_t seed = 1) {
    std::uint32_t s = seed * 2654435761u + 12345u;
    auto next = [&s]() {
      s = s * 1664525u + 1013904223u;
      return static_cast<double>(s >> 8) / static_cast<double>(1u << 24);
    };
    for (Wave& w : waves_) {
      // Log-uniform wavelengths (7-120 px) with amplitude rising with wavelength, roughly
      // the 1/f spectrum of natural images, so coarse pyramid levels keep texture too.
      const double wavelength = 7.0 * std::exp(std::log(120.0 / 7.0) * next());
      const double angle = 2.0 * M_PI * next();
      w.kx = 2.0 * M_PI * std::cos(angle) / wavelength;
      w.ky = 2.0 * M_PI * std::sin(angle) / wavelength;
      w.phase = 2.0 * M_PI * next();
      w.amplitude = 5.0 * std::sqrt(wavelength / 7.0) * (0.5 + next());
    }
  }
  double operator()(double x, double y) const {
    double v = 128.0;
    for (const Wave& w : waves_) v += w.amplitude * std::sin(w.kx * x + w.ky * y + w.phase);
    return v;
  }

  // Renders pixel (x, y) = texture(x - dx, y - dy) without a sine per pixel: each wave splits as
  // sin(a + b) = sin a cos b + cos a sin b with a per-column and b per-row table (the unit tests
  // also run under QEMU, where libm is slow).
  template <typename Image>
  Image RenderShifted(int w, int h, double dx, double dy) const {
    Image img(w, h);
    std::vector<double> sa(static_cast<std::size_t>(w) * kWaves);
    std::vector<double> ca(sa.size());
    std::vector<double> sb(static_cast<std::size_t>(h) * kWaves);
    std::vector<double> cb(sb.size());
    for (int k = 0; k < kWaves; ++k) {
      for (int x = 0; x < w; ++x) {
        const double a = waves_[k].kx * (x - dx) + waves_[k].phase;
        sa[static_cast<std::size_t>(x) * kWaves + k] = waves_[k].amplitude * std::sin(a);
        ca[static_cast<std::size_t>(x) * kWaves + k] = waves_[k].amplitude * std::cos(a);
      }
      for (int y = 0; y < h; ++y) {
        const double b = waves_[k].ky * (y - dy);
        sb[static_cast<std::size_t>(y) * kWaves + k] = std::sin(b);
        cb[static_cast<std::size_t>(y) * kWaves + k] = std::cos(b);
      }
    }
    for (int y = 0; y < h; ++y) {
      const double* s_row = &sb[static_cast<std::size_t>(y) * kWaves];
      const double* c_row = &cb[static_cast<std::size_t>(y) * kWaves];
      for (int x = 0; x < w; ++x) {
        const double* s_col = &sa[static_cast<std::size_t>(x) * kWaves];
        const double* c_col = &ca[static_cast<std::size_t>(x) * kWaves];
        double v = 128.0;
        for (int k = 0; k < kWaves; ++k) v += s_col[k] * c_row[k] + c_col[k] * s_row[k];
        v = std::round(v);
        img.pixels[static_cast<std::size_t>(y) * w + x] =
            static_cast<std::uint8_t>(v < 0.0 ? 0.0 : (v > 255.0 ? 255.0 : v));
      }
    }
    return img;
  }

 private:
  struct Wave {
    double kx, ky, phase, amplitude;
  };
  static constexpr int kWaves = 16;
  Wave waves_[kWaves];
};

}  // namespace swf::frontend::synthetic
