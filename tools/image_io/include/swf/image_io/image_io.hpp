// File formats for tools and data tests: 8-bit images (PNG, JPG, PGM via stb), Middlebury .flo
// optical flow, and stereo calibration YAML (EuRoC sensor.yaml; ROS/OpenCV camera_info-style
// camera_matrix + distortion_coefficients). Errors come back as a message, never a crash.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "swf/frontend/image.hpp"
#include "swf/frontend/rectify.hpp"

namespace swf::image_io {

struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;

  frontend::GrayView View() const {
    return frontend::GrayView{pixels.data(), width, height, width};
  }
  frontend::MutableGrayView MutableView() {
    return frontend::MutableGrayView{pixels.data(), width, height, width};
  }
  void Resize(int w, int h) {
    width = w;
    height = h;
    pixels.assign(static_cast<std::size_t>(w) * h, 0);
  }
};

// Loads any 8/16-bit grey or colour image and converts it to 8-bit grey (stb's luma).
bool LoadGray(const std::string& path, GrayImage* image, std::string* error);
// Loads an image keeping its first channel's raw value (for ground-truth disparity PNGs).
bool LoadChannel0(const std::string& path, GrayImage* image, std::string* error);

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // r, g, b interleaved
};
bool SavePng(const std::string& path, const RgbImage& image, std::string* error);

// Middlebury .flo: u, v per pixel; unknown values (> 1e9) are NaN.
struct FlowField {
  int width = 0;
  int height = 0;
  std::vector<float> uv;  // row-major pairs
  bool Known(int x, int y) const;
  float U(int x, int y) const { return uv[2 * (static_cast<std::size_t>(y) * width + x)]; }
  float V(int x, int y) const { return uv[2 * (static_cast<std::size_t>(y) * width + x) + 1]; }
};
bool LoadFlo(const std::string& path, FlowField* flow, std::string* error);

// Reads one camera's calibration. EuRoC: intrinsics [fu fv cu cv], distortion_coefficients
// [k1 k2 p1 p2], resolution [w h], T_BS data (4x4 row-major, camera in body). ROS/OpenCV:
// image_width, image_height, camera_matrix data (3x3), distortion_coefficients data
// [k1 k2 p1 p2 (k3)], and optionally T_BS or T_cam_body-free (identity extrinsics).
bool LoadCalibration(const std::string& path, frontend::CameraCalibration* calibration,
                     std::string* error);

}  // namespace swf::image_io
