// Stereo calibration import for the ground tools: the calibration files cameras and calibration
// toolboxes deliver, read into the two frontend::CameraCalibration (pinhole + radial-tangential
// distortion + camera-in-body extrinsics) that the flight front end rectifies. yaml-cpp reads the
// YAML formats, so this module is ground-only; the flight binary keeps its own small reader of
// the EuRoC form (tools/image_io), which WriteEurocSensorYaml writes.
//
// Formats (docs/calibration.md has one example of each):
//   kEuroc      two EuRoC/ASL sensor.yaml (intrinsics, distortion_coefficients, resolution, T_BS)
//   kRos        two ROS camera_info YAML (camera_matrix, distortion_coefficients plumb_bob,
//               rectification_matrix, projection_matrix; the baseline from the right P)
//   kKalibr     one Kalibr camchain (cam0, cam1: intrinsics, distortion_coeffs radtan,
//               resolution, cam1.T_cn_cnm1; cam0.T_cam_imu optional, makes the IMU the body)
//   kOpenCv     one OpenCV FileStorage stereo YAML (K1 D1 K2 D2 R T, image size)
//   kKitti      one KITTI calib.txt (P0, P1 of a rectified pair; image size from the options)
//   kCahvor     two JPL CAHV / CAHVOR / CAHVORE models, linearized to pinhole + radial
// Every refusal names the file and, where the format has them, the line and key
// ("cam0.yaml:12: intrinsics: needs 4 numbers, has 3"). Nothing here throws to the caller.
#pragma once

#include <string>
#include <vector>

#include "swf/frontend/rectify.hpp"

namespace swf::calibration {

enum class CalibrationFormat { kAuto, kEuroc, kRos, kKalibr, kOpenCv, kKitti, kCahvor };

// "auto", "euroc", "ros", "kalibr", "opencv", "kitti", "cahvor".
const char* FormatName(CalibrationFormat format);
bool ParseFormatName(const std::string& name, CalibrationFormat* format);

struct ImportOptions {
  CalibrationFormat format = CalibrationFormat::kAuto;
  // Image size for formats that do not carry one (KITTI; OpenCV files without image_width /
  // image_height); 0 = not given. A file that carries a size must agree with it.
  int width = 0;
  int height = 0;
  // CAHVOR/CAHVORE: the largest distance (pixels, over the image) between the JPL model and the
  // pinhole + radial model it is linearized to before the import is refused.
  double max_linearization_error_px = 0.5;
};

struct StereoCalibration {
  frontend::CameraCalibration left;
  frontend::CameraCalibration right;
  CalibrationFormat format = CalibrationFormat::kAuto;  // the format read
  // CAHVOR/CAHVORE: largest model-to-linearization distance over both images (pixels).
  double linearization_error_px = 0.0;
};

// The common pinhole camera of the rectified pair the front end makes of a calibration.
struct RectifiedPair {
  int width = 0;
  int height = 0;
  estimator::StereoCamera<double> camera;    // the rectifier's (fx, fy, cx, cy, baseline)
  estimator::Pose<double> body_T_rectified;  // rectified left camera in the body frame
};

// The calibration format of `files` from their content (one file: Kalibr, OpenCV or KITTI; two:
// EuRoC, ROS or CAHVOR). False with *error when no format fits.
bool DetectFormat(const std::vector<std::string>& files, CalibrationFormat* format,
                  std::string* error);

// Reads `files` (one or two, as the format needs; left first) into *calibration. Refused, with
// *error naming the file: unreadable or malformed files, missing or ill-sized keys, unsupported
// camera or distortion models, non-finite numbers, non-positive focal lengths, sizes outside
// 1..image_io::kMaxImageSide, extrinsics that are not rigid, and a pair the front end cannot
// rectify (zero baseline, larger than the front end's capacity).
bool ImportStereoCalibration(const std::vector<std::string>& files, const ImportOptions& options,
                             StereoCalibration* calibration, std::string* error);

// The rectified pair of a calibration, as frontend::StereoRectifier computes it. False with
// *error when the rectifier refuses the calibration.
bool RectifyCalibration(const StereoCalibration& calibration, RectifiedPair* pair,
                        std::string* error);

// One camera as an EuRoC sensor.yaml (what swf-fsw's camera.*_calibration reads), full precision.
std::string EurocSensorYaml(const frontend::CameraCalibration& camera);

}  // namespace swf::calibration
