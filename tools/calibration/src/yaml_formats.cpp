// The YAML calibration formats (EuRoC sensor.yaml, ROS camera_info, Kalibr camchain, OpenCV
// FileStorage) through yaml-cpp. OpenCV's FileStorage writes a "%YAML:1.0" first line, which is
// not a YAML directive (YAML has "%YAML 1.0"): it is blanked to a comment, keeping line numbers.
// Its "!!opencv-matrix" tag needs nothing: a tagged map is still a map.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>

#include "import_internal.hpp"

namespace swf::calibration::internal {

namespace {

using frontend::CameraCalibration;
using PoseD = estimator::Pose<double>;

struct YamlDoc {
  std::string path;
  YAML::Node root;
};

int LineOf(const YAML::Node& node) { return node.IsDefined() ? node.Mark().line + 1 : 0; }

bool LoadYaml(const std::string& path, YamlDoc* doc, std::string* error) {
  std::string text;
  if (!ReadText(path, &text, error)) return false;
  if (text.rfind("%YAML:", 0) == 0) text[0] = '#';
  doc->path = path;
  try {
    doc->root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    *error = Message(path, e.mark.line + 1, "", "not valid YAML (" + e.msg + ")");
    return false;
  }
  if (!doc->root.IsMap()) {
    *error = Message(path, 0, "", "not a YAML map of calibration keys");
    return false;
  }
  return true;
}

// A failed conversion as the message of the node it happened at.
bool Fail(const YamlDoc& doc, const YAML::Node& node, const std::string& key,
          const std::string& what, std::string* error) {
  *error = Message(doc.path, LineOf(node), key, what);
  return false;
}

// Appends the scalars of `node` (a scalar or nested sequences, at most `depth` deep).
bool Flatten(const YAML::Node& node, int depth, std::vector<double>* values) {
  if (node.IsScalar()) {
    try {
      values->push_back(node.as<double>());
    } catch (const YAML::Exception&) {
      return false;
    }
    return true;
  }
  if (!node.IsSequence() || depth == 0) return false;
  for (const YAML::Node& child : node) {
    if (!Flatten(child, depth - 1, values)) return false;
  }
  return true;
}

// The numbers under parent[key]: a sequence (Kalibr's 4x4 as a list of rows too) or a matrix map
// with `data` (ROS, OpenCV, EuRoC's T_BS; rows x cols checked when given). Exactly one of the
// counts in `counts`, all finite.
bool Numbers(const YamlDoc& doc, const YAML::Node& parent, const std::string& key,
             const std::vector<std::size_t>& counts, std::vector<double>* values,
             std::string* error) {
  const YAML::Node node = parent[key];
  if (!node.IsDefined()) return Fail(doc, parent, key, "missing", error);
  values->clear();
  // (A copy, never an assignment: assigning a yaml-cpp node writes through to what it refers to.)
  const YAML::Node list = node.IsMap() ? node["data"] : node;
  if (!list.IsDefined()) return Fail(doc, node, key, "matrix without `data`", error);
  if (!Flatten(list, 2, values)) return Fail(doc, list, key, "is not a list of numbers", error);
  if (node.IsMap() && node["rows"].IsDefined() && node["cols"].IsDefined()) {
    try {
      const long long rows = node["rows"].as<long long>();
      const long long cols = node["cols"].as<long long>();
      if (rows * cols != static_cast<long long>(values->size())) {
        return Fail(doc, node, key,
                    "rows x cols = " + std::to_string(rows * cols) + " but data holds " +
                        std::to_string(values->size()) + " numbers",
                    error);
      }
    } catch (const YAML::Exception&) {
      return Fail(doc, node, key, "rows/cols are not integers", error);
    }
  }
  bool count_ok = false;
  std::string expected;
  for (const std::size_t c : counts) {
    count_ok = count_ok || values->size() == c;
    expected += (expected.empty() ? "" : " or ") + std::to_string(c);
  }
  if (!count_ok) {
    return Fail(doc, list, key,
                "needs " + expected + " numbers, has " + std::to_string(values->size()), error);
  }
  for (const double v : *values) {
    if (!std::isfinite(v)) return Fail(doc, list, key, "holds a non-finite number", error);
  }
  return true;
}

// An optional string key ("" when absent).
bool Text(const YamlDoc& doc, const YAML::Node& parent, const std::string& key, std::string* value,
          std::string* error) {
  value->clear();
  const YAML::Node node = parent[key];
  if (!node.IsDefined()) return true;
  if (!node.IsScalar()) return Fail(doc, node, key, "is not a string", error);
  *value = node.Scalar();
  return true;
}

bool Integer(const YamlDoc& doc, const YAML::Node& parent, const std::string& key, int* value,
             std::string* error) {
  std::vector<double> v;
  if (!Numbers(doc, parent, key, {1}, &v, error)) return false;
  if (v[0] != std::floor(v[0]) || std::fabs(v[0]) > 1e9) {
    return Fail(doc, parent[key], key, "is not a whole number", error);
  }
  *value = static_cast<int>(v[0]);
  return true;
}

// A 4x4 row-major rigid transform: a rotation block and a last row 0 0 0 1.
bool Rigid(const YamlDoc& doc, const YAML::Node& parent, const std::string& key, PoseD* pose,
           std::string* error) {
  std::vector<double> m;
  if (!Numbers(doc, parent, key, {16}, &m, error)) return false;
  Eigen::Matrix4d mat;
  for (int i = 0; i < 16; ++i) mat(i / 4, i % 4) = m[i];
  if (!IsRotation(mat.topLeftCorner<3, 3>())) {
    return Fail(doc, parent[key], key, "the 3x3 block is not a rotation", error);
  }
  if (mat.row(3) != Eigen::RowVector4d(0.0, 0.0, 0.0, 1.0)) {
    return Fail(doc, parent[key], key, "the last row is not 0 0 0 1", error);
  }
  *pose = PoseD::FromMatrix(mat);
  return true;
}

bool Matrix3(const YamlDoc& doc, const YAML::Node& parent, const std::string& key,
             Eigen::Matrix3d* r, std::string* error) {
  std::vector<double> m;
  if (!Numbers(doc, parent, key, {9}, &m, error)) return false;
  for (int i = 0; i < 9; ++i) (*r)(i / 3, i % 3) = m[i];
  return true;
}

// Radial-tangential coefficients k1 k2 p1 p2 [k3] (none: no distortion).
void SetDistortion(const std::vector<double>& d, CameraCalibration* c) {
  if (d.size() < 4) return;
  c->k1 = d[0];
  c->k2 = d[1];
  c->p1 = d[2];
  c->p2 = d[3];
  c->k3 = d.size() >= 5 ? d[4] : 0.0;
}

void SetPinhole(const std::vector<double>& fx_fy_cx_cy, CameraCalibration* c) {
  c->fx = fx_fy_cx_cy[0];
  c->fy = fx_fy_cx_cy[1];
  c->cx = fx_fy_cx_cy[2];
  c->cy = fx_fy_cx_cy[3];
}

// A camera matrix [fx s cx; 0 fy cy; 0 0 1] without skew.
bool SetCameraMatrix(const YamlDoc& doc, const YAML::Node& parent, const std::string& key,
                     CameraCalibration* c, std::string* error) {
  Eigen::Matrix3d k;
  if (!Matrix3(doc, parent, key, &k, error)) return false;
  if (k(0, 1) != 0.0 || k(1, 0) != 0.0 || k(2, 0) != 0.0 || k(2, 1) != 0.0 || k(2, 2) != 1.0) {
    return Fail(doc, parent[key], key, "is not [fx 0 cx; 0 fy cy; 0 0 1] (skew is not supported)",
                error);
  }
  SetPinhole({k(0, 0), k(1, 1), k(0, 2), k(1, 2)}, c);
  return true;
}

bool Resolution(const YamlDoc& doc, const YAML::Node& parent, const std::string& key,
                CameraCalibration* c, std::string* error) {
  std::vector<double> r;
  if (!Numbers(doc, parent, key, {2}, &r, error)) return false;
  if (r[0] != std::floor(r[0]) || r[1] != std::floor(r[1]) || r[0] < 1 || r[1] < 1 || r[0] > 1e6 ||
      r[1] > 1e6) {
    return Fail(doc, parent[key], key, "is not a whole image size in pixels", error);
  }
  c->width = static_cast<int>(r[0]);
  c->height = static_cast<int>(r[1]);
  return true;
}

// A model name that must be one of `accepted` when present.
bool ModelIs(const YamlDoc& doc, const YAML::Node& parent, const std::string& key,
             const std::vector<std::string>& accepted, std::string* error) {
  std::string model;
  if (!Text(doc, parent, key, &model, error)) return false;
  if (model.empty()) return true;
  std::string list;
  for (const std::string& a : accepted) {
    if (model == a) return true;
    list += (list.empty() ? "" : ", ") + a;
  }
  return Fail(doc, parent[key], key,
              "'" + model + "' is not supported (accepted: " + list +
                  "; the front end rectifies pinhole cameras with radial-tangential distortion)",
              error);
}

bool ReadEurocCamera(const std::string& path, CameraCalibration* c, std::string* error) {
  YamlDoc doc;
  if (!LoadYaml(path, &doc, error)) return false;
  const YAML::Node& r = doc.root;
  std::vector<double> intrinsics;
  std::vector<double> distortion;
  if (!ModelIs(doc, r, "camera_model", {"pinhole"}, error) ||
      !ModelIs(doc, r, "distortion_model", {"radial-tangential", "radtan", "plumb_bob"}, error) ||
      !Numbers(doc, r, "intrinsics", {4}, &intrinsics, error) ||
      !Numbers(doc, r, "distortion_coefficients", {4, 5}, &distortion, error) ||
      !Resolution(doc, r, "resolution", c, error)) {
    return false;
  }
  SetPinhole(intrinsics, c);
  SetDistortion(distortion, c);
  return !r["T_BS"].IsDefined() || Rigid(doc, r, "T_BS", &c->body_T_camera, error);
}

// One camera_info: the camera, its rectification rotation R (rect_R_raw) and projection P.
struct RosCamera {
  CameraCalibration camera;
  Eigen::Matrix3d rect_R_raw = Eigen::Matrix3d::Identity();
  std::vector<double> projection;
};

bool ReadRosCamera(const std::string& path, RosCamera* out, std::string* error) {
  YamlDoc doc;
  if (!LoadYaml(path, &doc, error)) return false;
  const YAML::Node& r = doc.root;
  CameraCalibration& c = out->camera;
  std::vector<double> distortion;
  if (!Integer(doc, r, "image_width", &c.width, error) ||
      !Integer(doc, r, "image_height", &c.height, error) ||
      !SetCameraMatrix(doc, r, "camera_matrix", &c, error) ||
      !ModelIs(doc, r, "distortion_model", {"plumb_bob", "radtan"}, error) ||
      !Numbers(doc, r, "distortion_coefficients", {0, 4, 5}, &distortion, error) ||
      !Matrix3(doc, r, "rectification_matrix", &out->rect_R_raw, error) ||
      !Numbers(doc, r, "projection_matrix", {12}, &out->projection, error)) {
    return false;
  }
  if (!IsRotation(out->rect_R_raw)) {
    return Fail(doc, r["rectification_matrix"], "rectification_matrix", "is not a rotation", error);
  }
  SetDistortion(distortion, &c);
  return true;
}

bool ReadKalibrCamera(const YamlDoc& doc, const std::string& name, CameraCalibration* c,
                      std::string* error) {
  const YAML::Node cam = doc.root[name];
  if (!cam.IsDefined() || !cam.IsMap())
    return Fail(doc, doc.root, name, "missing (a camchain needs cam0 and cam1)", error);
  std::vector<double> intrinsics;
  std::vector<double> distortion;
  if (!ModelIs(doc, cam, "camera_model", {"pinhole"}, error) ||
      !ModelIs(doc, cam, "distortion_model", {"radtan", "none"}, error) ||
      !Numbers(doc, cam, "intrinsics", {4}, &intrinsics, error) ||
      !Resolution(doc, cam, "resolution", c, error)) {
    return false;
  }
  std::string model;
  if (!Text(doc, cam, "distortion_model", &model, error)) return false;
  if (model != "none" && !Numbers(doc, cam, "distortion_coeffs", {4}, &distortion, error)) {
    return false;
  }
  SetPinhole(intrinsics, c);
  SetDistortion(distortion, c);
  return true;
}

}  // namespace

std::string YamlKind(const std::string& path, std::string* parse_error) {
  YamlDoc doc;
  if (!LoadYaml(path, &doc, parse_error)) return "";
  const YAML::Node& r = doc.root;
  if (r["cam0"].IsDefined() && r["cam0"].IsMap()) return "kalibr";
  if (r["camera_matrix"].IsDefined()) return "ros";
  if (r["intrinsics"].IsDefined()) return "euroc";
  for (const char* key : {"K1", "M1", "D1", "cameraMatrix1"}) {
    if (r[key].IsDefined()) return "opencv";
  }
  return "";
}

bool ReadEurocPair(const std::string& left, const std::string& right, StereoCalibration* out,
                   std::string* error) {
  return ReadEurocCamera(left, &out->left, error) && ReadEurocCamera(right, &out->right, error);
}

// camera_info of a stereo pair (ROS camera_calibration): R rotates each raw camera into the
// common rectified frame, and the right P = K' [I | -B e_x] (its P[0][3] = -fx' B) puts the right
// rectified camera at +B along the rectified x axis. A left-camera point p maps to the right raw
// camera as R_r^T (R_l p - B e_x), so right_T_left = {R_r^T R_l, -R_r^T B e_x} and the left
// camera is the body.
bool ReadRosPair(const std::string& left, const std::string& right, StereoCalibration* out,
                 std::string* error) {
  RosCamera l;
  RosCamera r;
  if (!ReadRosCamera(left, &l, error) || !ReadRosCamera(right, &r, error)) return false;
  const double f = r.projection[0];
  if (!(f > 0.0)) {
    *error = Message(right, 0, "projection_matrix", "P[0][0] (fx') must be positive");
    return false;
  }
  if (r.projection[7] != l.projection[7]) {
    *error = Message(right, 0, "projection_matrix",
                     "P[1][3] differs from the left's: vertical stereo is not supported");
    return false;
  }
  const double baseline_m = -(r.projection[3] - l.projection[3]) / f;
  const Eigen::Matrix3d right_R_left = r.rect_R_raw.transpose() * l.rect_R_raw;
  const PoseD right_T_left{right_R_left,
                           -(r.rect_R_raw.transpose() * Eigen::Vector3d(baseline_m, 0.0, 0.0))};
  out->left = l.camera;
  out->right = r.camera;
  out->left.body_T_camera = PoseD::Identity();
  out->right.body_T_camera = right_T_left.Inverse();
  return true;
}

// Kalibr: cam1.T_cn_cnm1 maps cam0 coordinates into cam1 (cam1_T_cam0); cam0.T_cam_imu, when
// given, maps IMU coordinates into cam0 and makes the IMU the body frame.
bool ReadKalibr(const std::string& path, StereoCalibration* out, std::string* error) {
  YamlDoc doc;
  if (!LoadYaml(path, &doc, error)) return false;
  if (!ReadKalibrCamera(doc, "cam0", &out->left, error) ||
      !ReadKalibrCamera(doc, "cam1", &out->right, error)) {
    return false;
  }
  PoseD cam1_T_cam0;
  if (!Rigid(doc, doc.root["cam1"], "T_cn_cnm1", &cam1_T_cam0, error)) return false;
  PoseD body_T_cam0;
  if (doc.root["cam0"]["T_cam_imu"].IsDefined()) {
    PoseD cam0_T_imu;
    if (!Rigid(doc, doc.root["cam0"], "T_cam_imu", &cam0_T_imu, error)) return false;
    body_T_cam0 = cam0_T_imu.Inverse();
  }
  out->left.body_T_camera = body_T_cam0;
  out->right.body_T_camera = body_T_cam0 * cam1_T_cam0.Inverse();
  return true;
}

// OpenCV stereoCalibrate's output: x_2 = R x_1 + T (camera 1 = left into camera 2 = right).
bool ReadOpenCv(const std::string& path, const ImportOptions& options, StereoCalibration* out,
                std::string* error) {
  YamlDoc doc;
  if (!LoadYaml(path, &doc, error)) return false;
  const YAML::Node& r = doc.root;
  const auto first_of = [&r](std::initializer_list<const char*> keys) {
    for (const char* k : keys) {
      if (r[k].IsDefined()) return std::string(k);
    }
    return std::string(*keys.begin());
  };
  std::vector<double> d1;
  std::vector<double> d2;
  std::vector<double> t;
  Eigen::Matrix3d right_R_left;
  const std::vector<std::size_t> distortion_counts = {4, 5, 8, 12, 14};
  if (!SetCameraMatrix(doc, r, first_of({"K1", "M1", "cameraMatrix1"}), &out->left, error) ||
      !SetCameraMatrix(doc, r, first_of({"K2", "M2", "cameraMatrix2"}), &out->right, error) ||
      !Numbers(doc, r, first_of({"D1", "distCoeffs1"}), distortion_counts, &d1, error) ||
      !Numbers(doc, r, first_of({"D2", "distCoeffs2"}), distortion_counts, &d2, error) ||
      !Matrix3(doc, r, "R", &right_R_left, error) || !Numbers(doc, r, "T", {3}, &t, error)) {
    return false;
  }
  for (const auto* d : {&d1, &d2}) {
    for (std::size_t i = 5; i < d->size(); ++i) {
      if ((*d)[i] != 0.0) {
        *error = Message(path, 0, "D1/D2",
                         "rational, thin-prism or tilt terms (coefficients 6 and up) are not "
                         "supported: only k1 k2 p1 p2 k3");
        return false;
      }
    }
  }
  if (!IsRotation(right_R_left)) return Fail(doc, r["R"], "R", "is not a rotation", error);
  int width = options.width;
  int height = options.height;
  if (r["image_width"].IsDefined() || r["image_height"].IsDefined()) {
    if (!Integer(doc, r, "image_width", &width, error) ||
        !Integer(doc, r, "image_height", &height, error)) {
      return false;
    }
  } else if (r["image_size"].IsDefined() || r["imageSize"].IsDefined()) {
    if (!Resolution(doc, r, first_of({"image_size", "imageSize"}), &out->left, error)) return false;
    width = out->left.width;
    height = out->left.height;
  }
  if (width <= 0 || height <= 0) {
    *error = Message(path, 0, "image_width",
                     "no image size in the file (image_width/image_height or image_size) and "
                     "none given (--size WxH)");
    return false;
  }
  SetDistortion(d1, &out->left);
  SetDistortion(d2, &out->right);
  for (CameraCalibration* c : {&out->left, &out->right}) {
    c->width = width;
    c->height = height;
  }
  const PoseD right_T_left{right_R_left, Eigen::Vector3d(t[0], t[1], t[2])};
  out->left.body_T_camera = PoseD::Identity();
  out->right.body_T_camera = right_T_left.Inverse();
  return true;
}

}  // namespace swf::calibration::internal
