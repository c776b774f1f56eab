// File formats for tools and data tests: 8-bit images (PNG, JPEG, binary PGM/PPM via stb),
// Middlebury .flo optical flow, and stereo calibration YAML (EuRoC sensor.yaml; ROS/OpenCV
// camera_info-style camera_matrix + distortion_coefficients). Errors come back as a message that
// names the file, never a crash. Every decoder checks sizes against the limits below before it
// allocates, so a small hostile file cannot make it reserve gigabytes; each has an in-memory
// entry point (Decode*, Parse*) that the file readers wrap and the fuzz harnesses call.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "swf/frontend/image.hpp"
#include "swf/frontend/rectify.hpp"

namespace swf::image_io {

// Largest image accepted, checked in the file header before decoding: 16384 px a side and 2^26
// pixels (64 Mpx, 256 MB as RGBA), far above any camera or data set the tools read.
inline constexpr int kMaxImageSide = 16384;
inline constexpr std::int64_t kMaxImagePixels = std::int64_t{1} << 26;
// Largest image or flow file read (bytes): a file above it is refused before it is read.
inline constexpr std::size_t kMaxImageFileBytes = std::size_t{1} << 28;
// Largest calibration file read (bytes): a sensor.yaml holds a few hundred.
inline constexpr std::size_t kMaxCalibrationFileBytes = std::size_t{1} << 20;

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

// Loads a PNG or JPEG (8 or 16 bit, grey or colour) or an 8-bit binary PGM/PPM and converts it
// to 8-bit grey (stb's luma). Refused, with a reason naming the file: other formats, a size above
// the limits, a PNG chunk whose CRC does not match or a PNG/JPEG cut short.
bool LoadGray(const std::string& path, GrayImage* image, std::string* error);
// Loads an image keeping its first channel's raw value (for ground-truth disparity PNGs).
bool LoadChannel0(const std::string& path, GrayImage* image, std::string* error);
// The same from bytes in memory; `name` stands for the file in messages.
bool DecodeGray(const std::uint8_t* data, std::size_t size, const std::string& name,
                GrayImage* image, std::string* error);
bool DecodeChannel0(const std::uint8_t* data, std::size_t size, const std::string& name,
                    GrayImage* image, std::string* error);
// Width and height from the file's header only (no pixel is decoded), with the same checks.
bool ReadImageSize(const std::string& path, int* width, int* height, std::string* error);

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
bool DecodeFlo(const std::uint8_t* data, std::size_t size, const std::string& name, FlowField* flow,
               std::string* error);

// Reads one camera's calibration. EuRoC: intrinsics [fu fv cu cv], distortion_coefficients
// [k1 k2 p1 p2], resolution [w h], T_BS data (4x4 row-major, camera in body). ROS/OpenCV:
// image_width, image_height, camera_matrix data (3x3), distortion_coefficients data
// [k1 k2 p1 p2 (k3)], and optionally T_BS or T_cam_body-free (identity extrinsics).
// Refused besides missing fields: a resolution outside 1..kMaxImageSide, non-finite values,
// non-positive focal lengths, and a T_BS whose rotation block is not orthonormal (1e-3) or whose
// last row is not 0 0 0 1. (Whether the values describe a usable camera is the caller's check.)
bool LoadCalibration(const std::string& path, frontend::CameraCalibration* calibration,
                     std::string* error);
// The same from the file's text; `name` stands for the file in messages.
bool ParseCalibration(const std::string& text, const std::string& name,
                      frontend::CameraCalibration* calibration, std::string* error);

}  // namespace swf::image_io
