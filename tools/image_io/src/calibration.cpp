// Stereo calibration YAML (EuRoC sensor.yaml; ROS/OpenCV camera_info), in an object of its own:
// the flight binary reads its cameras' calibrations and links no image decoder.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "files.hpp"
#include "swf/image_io/image_io.hpp"

namespace swf::image_io {

namespace {

// The numbers of the first [...] list after `key:` (searched from `from`), or empty.
std::vector<double> ListAfter(const std::string& text, const std::string& key,
                              std::size_t from = 0) {
  std::vector<double> values;
  std::size_t k = text.find(key + ":", from);
  while (k != std::string::npos && k > 0 && text[k - 1] != '\n' && text[k - 1] != ' ') {
    k = text.find(key + ":", k + 1);  // only whole keys
  }
  if (k == std::string::npos) return values;
  const std::size_t open = text.find('[', k);
  const std::size_t close = text.find(']', open);
  if (open == std::string::npos || close == std::string::npos) return values;
  std::string body = text.substr(open + 1, close - open - 1);
  for (char& c : body) {
    if (c == ',' || c == '\n' || c == '\r') c = ' ';
  }
  std::istringstream in(body);
  double v = 0.0;
  while (in >> v) values.push_back(v);
  return values;
}

bool ScalarAfter(const std::string& text, const std::string& key, double* value) {
  const std::size_t k = text.find(key + ":");
  if (k == std::string::npos) return false;
  return std::sscanf(text.c_str() + k + key.size() + 1, "%lf", value) == 1;
}

// A resolution read as doubles, checked before it becomes an int.
bool SetResolution(double w, double h, const std::string& name, frontend::CameraCalibration* c,
                   std::string* error) {
  if (!(w >= 1.0 && w <= kMaxImageSide && h >= 1.0 && h <= kMaxImageSide) || w != std::floor(w) ||
      h != std::floor(h)) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), ": resolution %g x %g is not whole pixels in 1..%d", w, h,
                  kMaxImageSide);
    *error = name + buf;
    return false;
  }
  c->width = static_cast<int>(w);
  c->height = static_cast<int>(h);
  return true;
}

bool ParseIntrinsics(const std::string& text, const std::string& name,
                     frontend::CameraCalibration* c, std::vector<double>* distortion,
                     std::string* error) {
  const std::vector<double> intrinsics = ListAfter(text, "intrinsics");
  if (intrinsics.size() == 4) {  // EuRoC / Kalibr
    c->fx = intrinsics[0];
    c->fy = intrinsics[1];
    c->cx = intrinsics[2];
    c->cy = intrinsics[3];
    const std::vector<double> resolution = ListAfter(text, "resolution");
    if (resolution.size() != 2) {
      *error = name + ": resolution [w, h] missing";
      return false;
    }
    *distortion = ListAfter(text, "distortion_coefficients");
    return SetResolution(resolution[0], resolution[1], name, c, error);
  }
  // ROS camera_info / OpenCV
  const std::size_t k = text.find("camera_matrix:");
  const std::vector<double> m =
      k == std::string::npos ? std::vector<double>{} : ListAfter(text, "data", k);
  double w = 0.0;
  double h = 0.0;
  if (m.size() != 9 || !ScalarAfter(text, "image_width", &w) ||
      !ScalarAfter(text, "image_height", &h)) {
    *error = name + ": neither EuRoC intrinsics nor ROS camera_matrix/image_width found";
    return false;
  }
  c->fx = m[0];
  c->cx = m[2];
  c->fy = m[4];
  c->cy = m[5];
  const std::size_t d = text.find("distortion_coefficients:");
  if (d != std::string::npos) *distortion = ListAfter(text, "data", d);
  return SetResolution(w, h, name, c, error);
}

// T_BS (camera in body), when given: 16 finite numbers, a rotation block and a last row 0 0 0 1.
bool ParseExtrinsics(const std::string& text, const std::string& name,
                     frontend::CameraCalibration* c, std::string* error) {
  const std::size_t t = text.find("T_BS:");
  if (t == std::string::npos) return true;
  const std::vector<double> m = ListAfter(text, "data", t);
  if (m.size() != 16) {
    *error = name + ": T_BS must hold 16 numbers";
    return false;
  }
  Eigen::Matrix4d mat;
  for (int i = 0; i < 16; ++i) mat(i / 4, i % 4) = m[i];
  const Eigen::Matrix3d r = mat.topLeftCorner<3, 3>();
  if (!mat.allFinite() || (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-3 ||
      r.determinant() < 0.0) {
    *error = name + ": T_BS's 3x3 block is not a rotation";
    return false;
  }
  if (mat.row(3) != Eigen::RowVector4d(0.0, 0.0, 0.0, 1.0)) {
    *error = name + ": T_BS's last row is not 0 0 0 1";
    return false;
  }
  c->body_T_camera = estimator::Pose<double>::FromMatrix(mat);
  return true;
}

}  // namespace

bool ParseCalibration(const std::string& text, const std::string& name,
                      frontend::CameraCalibration* c, std::string* error) {
  *c = frontend::CameraCalibration{};
  std::vector<double> distortion;
  if (!ParseIntrinsics(text, name, c, &distortion, error)) return false;
  if (distortion.size() < 4 || distortion.size() > 5) {
    *error = name + ": need 4 or 5 radial-tangential distortion coefficients";
    return false;
  }
  c->k1 = distortion[0];
  c->k2 = distortion[1];
  c->p1 = distortion[2];
  c->p2 = distortion[3];
  c->k3 = distortion.size() == 5 ? distortion[4] : 0.0;
  if (!ParseExtrinsics(text, name, c, error)) return false;
  const double values[] = {c->fx, c->fy, c->cx, c->cy, c->k1, c->k2, c->p1, c->p2, c->k3};
  for (double v : values) {
    if (!std::isfinite(v)) {
      *error = name + ": non-finite intrinsics or distortion";
      return false;
    }
  }
  if (!(c->fx > 0.0 && c->fy > 0.0)) {
    *error = name + ": focal lengths must be positive";
    return false;
  }
  return true;
}

bool LoadCalibration(const std::string& path, frontend::CameraCalibration* c, std::string* error) {
  std::vector<std::uint8_t> bytes;
  if (!internal::ReadBytes(path, kMaxCalibrationFileBytes, &bytes, error)) return false;
  const std::string text(bytes.begin(), bytes.end());
  if (text.find('\0') != std::string::npos) {
    *error = path + ": contains a NUL byte (not a text file)";
    return false;
  }
  return ParseCalibration(text, path, c, error);
}

}  // namespace swf::image_io
