// Format detection, dispatch, the checks every imported calibration gets, the rectified pair and
// the EuRoC writer.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "import_internal.hpp"

namespace swf::calibration {

namespace internal {

bool ReadText(const std::string& path, std::string* text, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  *text = buffer.str();
  if (text->size() > kMaxFileBytes) {
    *error = path + ": larger than a calibration file can be (1 MiB)";
    return false;
  }
  if (text->find('\0') != std::string::npos) {
    *error = path + ": contains a NUL byte (not a text file)";
    return false;
  }
  return true;
}

std::string Message(const std::string& path, int line, const std::string& key,
                    const std::string& what) {
  std::string m = path;
  if (line > 0) m += ":" + std::to_string(line);
  if (!key.empty()) m += ": " + key;
  return m + ": " + what;
}

bool IsRotation(const Eigen::Matrix3d& r) {
  return r.allFinite() && (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-3 &&
         r.determinant() > 0.0;
}

}  // namespace internal

namespace {

using frontend::CameraCalibration;

constexpr int kMaxImageSide = 16384;  // as image_io::kMaxImageSide

struct FormatNameEntry {
  CalibrationFormat format;
  const char* name;
};
constexpr FormatNameEntry kFormatNames[] = {
    {CalibrationFormat::kAuto, "auto"},     {CalibrationFormat::kEuroc, "euroc"},
    {CalibrationFormat::kRos, "ros"},       {CalibrationFormat::kKalibr, "kalibr"},
    {CalibrationFormat::kOpenCv, "opencv"}, {CalibrationFormat::kKitti, "kitti"},
    {CalibrationFormat::kCahvor, "cahvor"},
};

bool FilesNeeded(CalibrationFormat format) {
  return format == CalibrationFormat::kEuroc || format == CalibrationFormat::kRos ||
         format == CalibrationFormat::kCahvor;
}

// What one camera must be after any format: a size the tools accept, finite numbers, positive
// focal lengths, a rigid pose.
bool CheckCamera(const CameraCalibration& c, const std::string& path, std::string* error) {
  if (c.width < 1 || c.height < 1 || c.width > kMaxImageSide || c.height > kMaxImageSide) {
    *error = internal::Message(path, 0, "",
                               "image size " + std::to_string(c.width) + " x " +
                                   std::to_string(c.height) + " is outside 1.." +
                                   std::to_string(kMaxImageSide));
    return false;
  }
  const double values[] = {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3};
  for (const double v : values) {
    if (!std::isfinite(v)) {
      *error = internal::Message(path, 0, "", "non-finite intrinsics or distortion");
      return false;
    }
  }
  if (!(c.fx > 0.0 && c.fy > 0.0)) {
    *error = internal::Message(path, 0, "", "focal lengths must be positive");
    return false;
  }
  if (!c.body_T_camera.t.allFinite() || !internal::IsRotation(c.body_T_camera.R)) {
    *error = internal::Message(path, 0, "", "the camera's extrinsics are not a rigid transform");
    return false;
  }
  return true;
}

bool Dispatch(const std::vector<std::string>& files, const ImportOptions& options,
              CalibrationFormat format, StereoCalibration* out, std::string* error) {
  switch (format) {
    case CalibrationFormat::kEuroc: return internal::ReadEurocPair(files[0], files[1], out, error);
    case CalibrationFormat::kRos: return internal::ReadRosPair(files[0], files[1], out, error);
    case CalibrationFormat::kKalibr: return internal::ReadKalibr(files[0], out, error);
    case CalibrationFormat::kOpenCv: return internal::ReadOpenCv(files[0], options, out, error);
    case CalibrationFormat::kKitti: return internal::ReadKitti(files[0], options, out, error);
    case CalibrationFormat::kCahvor:
      return internal::ReadCahvorPair(files[0], files[1], options, out, error);
    case CalibrationFormat::kAuto: break;
  }
  *error = "no calibration format given";
  return false;
}

std::string Joined(const std::vector<std::string>& files) {
  std::string s;
  for (const std::string& f : files) s += (s.empty() ? "" : " + ") + f;
  return s;
}

}  // namespace

const char* FormatName(CalibrationFormat format) {
  for (const FormatNameEntry& e : kFormatNames) {
    if (e.format == format) return e.name;
  }
  return "?";
}

bool ParseFormatName(const std::string& name, CalibrationFormat* format) {
  for (const FormatNameEntry& e : kFormatNames) {
    if (name == e.name) {
      *format = e.format;
      return true;
    }
  }
  return false;
}

bool DetectFormat(const std::vector<std::string>& files, CalibrationFormat* format,
                  std::string* error) {
  if (files.empty() || files.size() > 2) {
    *error =
        "give one calibration file (Kalibr, OpenCV, KITTI) or two (left and right: EuRoC, "
        "ROS camera_info, CAHVOR)";
    return false;
  }
  std::string text;
  if (!internal::ReadText(files[0], &text, error)) return false;
  CalibrationFormat found = CalibrationFormat::kAuto;
  if (internal::LooksLikeKitti(text)) {
    found = CalibrationFormat::kKitti;
  } else if (internal::LooksLikeCahvor(text)) {
    found = CalibrationFormat::kCahvor;
  } else {
    std::string parse_error;
    const std::string kind = internal::YamlKind(files[0], &parse_error);
    if (!kind.empty()) ParseFormatName(kind, &found);
    if (kind.empty() && parse_error.find("not valid YAML") != std::string::npos) {
      *error = parse_error;
      return false;
    }
  }
  if (found == CalibrationFormat::kAuto) {
    *error = files[0] +
             ": not a calibration format this tool knows (EuRoC sensor.yaml, ROS camera_info, "
             "Kalibr camchain, OpenCV stereo YAML, KITTI calib.txt, CAHV/CAHVOR/CAHVORE); "
             "name one with --format to see what is missing";
    return false;
  }
  *format = found;
  return true;
}

bool ImportStereoCalibration(const std::vector<std::string>& files, const ImportOptions& options,
                             StereoCalibration* calibration, std::string* error) {
  *calibration = StereoCalibration{};
  CalibrationFormat format = options.format;
  if (format == CalibrationFormat::kAuto && !DetectFormat(files, &format, error)) return false;
  const std::size_t needed = FilesNeeded(format) ? 2 : 1;
  if (files.size() != needed) {
    *error = std::string("format ") + FormatName(format) + " needs " + std::to_string(needed) +
             (needed == 2 ? " files (left, right)" : " file") + ", given " +
             std::to_string(files.size());
    return false;
  }
  try {
    if (!Dispatch(files, options, format, calibration, error)) return false;
  } catch (const std::exception& e) {  // a reader's bug must not end the program
    *error = Joined(files) + ": unexpected error while reading: " + e.what();
    return false;
  }
  calibration->format = format;
  const std::string& right_file = files.back();
  if (!CheckCamera(calibration->left, files[0], error) ||
      !CheckCamera(calibration->right, right_file, error)) {
    return false;
  }
  if (calibration->left.width != calibration->right.width ||
      calibration->left.height != calibration->right.height) {
    *error = Joined(files) + ": the left and right images differ in size";
    return false;
  }
  if ((options.width > 0 && options.width != calibration->left.width) ||
      (options.height > 0 && options.height != calibration->left.height)) {
    *error = Joined(files) + ": the calibration is for " + std::to_string(calibration->left.width) +
             " x " + std::to_string(calibration->left.height) + " px, not the size given";
    return false;
  }
  RectifiedPair pair;
  if (!RectifyCalibration(*calibration, &pair, error)) {
    *error = Joined(files) + ": " + *error;
    return false;
  }
  return true;
}

bool RectifyCalibration(const StereoCalibration& calibration, RectifiedPair* pair,
                        std::string* error) {
  // The rectifier holds both remap tables at the front end's largest image: on the heap.
  auto rectifier = std::make_unique<frontend::StereoRectifier>();
  const core::Status s =
      rectifier->Configure(calibration.left, calibration.right, frontend::RectifyOptions{});
  if (s != core::Status::kOk) {
    char text[240];
    std::snprintf(text, sizeof text,
                  "the front end cannot rectify this pair (%s: zero baseline, images over %d x "
                  "%d px, or intrinsics it refuses)",
                  core::ToString(s), frontend::kMaxImageWidth, frontend::kMaxImageHeight);
    *error = text;
    return false;
  }
  pair->width = rectifier->Width();
  pair->height = rectifier->Height();
  pair->camera = rectifier->Camera();
  pair->body_T_rectified = rectifier->RectifiedInBody();
  return true;
}

std::string EurocSensorYaml(const CameraCalibration& c) {
  const Eigen::Matrix4d m = c.body_T_camera.Matrix();
  std::string text =
      "%YAML:1.0\n# Written by swf-convert calib (docs/calibration.md).\nsensor_type: camera\n"
      "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  char number[40];
  for (int i = 0; i < 16; ++i) {
    std::snprintf(number, sizeof number, "%s%.17g", i == 0 ? "" : ", ", m(i / 4, i % 4));
    text += number;
  }
  char body[600];
  std::snprintf(body, sizeof body,
                "]\nresolution: [%d, %d]\ncamera_model: pinhole\n"
                "intrinsics: [%.17g, %.17g, %.17g, %.17g]\n"
                "distortion_model: radial-tangential\n"
                "distortion_coefficients: [%.17g, %.17g, %.17g, %.17g, %.17g]\n",
                c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3);
  return text + body;
}

}  // namespace swf::calibration
