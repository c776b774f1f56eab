// The line-oriented calibration formats: KITTI's calib.txt and JPL's CAHV / CAHVOR / CAHVORE
// camera model files.
//
// CAHV (Yakimovsky and Cunningham, "A system for extracting three-dimensional measurements from a
// stereo pair of TV cameras", CGIP 7, 1978): a point P images at
//   x = (P - C).H / (P - C).A,   y = (P - C).V / (P - C).A
// with C the entrance pupil, A the unit optical axis and H, V the horizontal and vertical vectors
// (focal length and principal point folded in). Its pinhole parameters are
//   hc = A.H, hs = |A x H|, vc = A.V, vs = |A x V|,  H' = (H - hc A) / hs,  V' = (V - vc A) / vs,
// so that x = hc + hs (P - C).H' / (P - C).A: camera axes x = H', y ~ V', z = A.
// CAHVOR (Gennery, "Least-squares camera calibration including lens distortion and automatic
// editing of calibration points", in Calibration and Orientation of Cameras in Computer Vision,
// Springer 2001) adds radial distortion about the optical axis O: with z = (P - C).O,
// l = (P - C) - z O and t = l.l / z^2, the point is moved to P + mu l, mu = r0 + r1 t + r2 t^2,
// before the CAHV projection.
// CAHVORE (Gennery, "Generalized camera calibration including fish-eye lenses", IJCV 68(3), 2006)
// generalizes the projection about O by the angle theta between the ray and O: chi = tan(L theta)
// / L (L > 0), sin(L theta) / L (L < 0), theta (L = 0; L = 1 perspective, 0 fisheye), then the
// same radial polynomial chi' = chi (1 + r0 + r1 chi^2 + r2 chi^4), and an entrance pupil that
// moves along O with theta (E). With L = 1 and E = 0 it is CAHVOR. Directions (points far away)
// do not see the pupil's movement, so E is left out of the linearization below (its effect is a
// parallax of at most |E| metres on near points).
//
// Linearization: the camera axes above, fx = hs b0, fy = vs b0, (cx, cy) = (hc, vc) and the
// radial coefficients k_i = b_i / b0 of the least-squares fit of
//   x = hc + hs xn (b0 + b1 r^2 + b2 r^4 + b3 r^6),  y = vc + vs yn (same),  r^2 = xn^2 + yn^2,
// to the model's projections of a grid of directions (xn, yn, 1) covering the image. With O = A
// this is exact for CAHVOR (b0 = 1 + r0, b1 = r1, b2 = r2); O off A, a skewed V or a fisheye lens
// leave a residual, reported and refused above ImportOptions::max_linearization_error_px.
#include <cmath>
#include <map>
#include <sstream>

#include "import_internal.hpp"

namespace swf::calibration::internal {

namespace {

using frontend::CameraCalibration;
using PoseD = estimator::Pose<double>;

// One "key = numbers" or "key: numbers" line.
struct Entry {
  int line = 0;
  std::vector<double> values;
  bool numeric = true;
};

// Splits text into keyed entries; comments (#) and blank lines skipped.
std::map<std::string, Entry> ReadEntries(const std::string& text, char separator,
                                         std::vector<std::string>* duplicates) {
  std::map<std::string, Entry> entries;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::size_t hash = raw.find('#');
    if (hash != std::string::npos) raw.resize(hash);
    const std::size_t sep = raw.find(separator);
    if (sep == std::string::npos) continue;
    std::string key = raw.substr(0, sep);
    key.erase(0, key.find_first_not_of(" \t"));
    key.erase(key.find_last_not_of(" \t\r") + 1);
    if (key.empty()) continue;
    if (entries.count(key) != 0 && duplicates != nullptr) duplicates->push_back(key);
    Entry& e = entries[key];
    e.line = line;
    std::istringstream values(raw.substr(sep + 1));
    std::string token;
    while (values >> token) {
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0' || !std::isfinite(v)) {
        e.numeric = false;
        break;
      }
      e.values.push_back(v);
    }
  }
  return entries;
}

// entries[key] with exactly `count` finite numbers, or *error naming file, line and key.
bool Take(const std::map<std::string, Entry>& entries, const std::string& path,
          const std::string& key, std::size_t count, std::vector<double>* values,
          std::string* error) {
  const auto it = entries.find(key);
  if (it == entries.end()) {
    *error = Message(path, 0, key, "missing");
    return false;
  }
  if (!it->second.numeric || it->second.values.size() != count) {
    *error = Message(path, it->second.line, key,
                     "needs " + std::to_string(count) + " finite numbers" +
                         (it->second.numeric ? ", has " + std::to_string(it->second.values.size())
                                             : ", has text that is not a number"));
    return false;
  }
  *values = it->second.values;
  return true;
}

bool ReadEntriesOf(const std::string& path, char separator, std::map<std::string, Entry>* entries,
                   std::string* error) {
  std::string text;
  if (!ReadText(path, &text, error)) return false;
  std::vector<std::string> duplicates;
  *entries = ReadEntries(text, separator, &duplicates);
  if (!duplicates.empty()) {
    *error = Message(path, (*entries)[duplicates[0]].line, duplicates[0], "given twice");
    return false;
  }
  return true;
}

Eigen::Vector3d Vec(const std::vector<double>& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

// A JPL model as read: CAHV always, O and R for CAHVOR, E and L for CAHVORE.
struct JplModel {
  Eigen::Vector3d c, a, h, v;
  Eigen::Vector3d o = Eigen::Vector3d::Zero();
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  double linearity = 1.0;  // L of CAHVORE; 1 = perspective (CAHV, CAHVOR)
  int width = 0;
  int height = 0;
};

// Image of the world direction d (file comment); false behind the camera.
bool ProjectDirection(const JplModel& m, const Eigen::Vector3d& d, Eigen::Vector2d* image) {
  Eigen::Vector3d ray = d;
  if (m.r != Eigen::Vector3d::Zero() || m.linearity != 1.0) {
    const double zeta = d.dot(m.o);
    const Eigen::Vector3d lambda = d - zeta * m.o;
    const double lambda_norm = lambda.norm();
    const double theta = std::atan2(lambda_norm, zeta);
    const double l = m.linearity;
    double chi = theta;
    if (l > 1e-9) chi = std::tan(l * theta) / l;
    if (l < -1e-9) chi = std::sin(l * theta) / l;
    if (l > 1e-9 && l * theta >= M_PI / 2) return false;
    const double chi2 = chi * chi;
    const double chi_distorted = chi * (1.0 + m.r[0] + m.r[1] * chi2 + m.r[2] * chi2 * chi2);
    ray = lambda_norm > 0.0 ? Eigen::Vector3d(m.o + chi_distorted * lambda / lambda_norm) : m.o;
  }
  const double depth = ray.dot(m.a);
  if (!(depth > 0.0)) return false;
  *image = Eigen::Vector2d(ray.dot(m.h) / depth, ray.dot(m.v) / depth);
  return true;
}

bool ReadJplModel(const std::string& path, const ImportOptions& options, JplModel* m,
                  std::string* error) {
  std::map<std::string, Entry> entries;
  if (!ReadEntriesOf(path, '=', &entries, error)) return false;
  std::vector<double> c, a, h, v, dims;
  if (!Take(entries, path, "C", 3, &c, error) || !Take(entries, path, "A", 3, &a, error) ||
      !Take(entries, path, "H", 3, &h, error) || !Take(entries, path, "V", 3, &v, error)) {
    return false;
  }
  m->c = Vec(c);
  m->a = Vec(a);
  m->h = Vec(h);
  m->v = Vec(v);
  const bool has_o = entries.count("O") != 0;
  const bool has_r = entries.count("R") != 0;
  const bool has_e = entries.count("E") != 0;
  if (has_o != has_r || (has_e && !has_o)) {
    *error = Message(path, 0, has_o ? "R" : "O",
                     "missing: CAHVOR needs both O and R, CAHVORE O, R and E");
    return false;
  }
  std::vector<double> o, r, e;
  if (has_o && (!Take(entries, path, "O", 3, &o, error) || !Take(entries, path, "R", 3, &r, error)))
    return false;
  if (has_o) {
    m->o = Vec(o);
    m->r = Vec(r);
  }
  if (has_e) {
    std::vector<double> type;
    if (!Take(entries, path, "E", 3, &e, error) || !Take(entries, path, "T", 1, &type, error))
      return false;
    m->e = Vec(e);
    if (type[0] == 1.0) {
      m->linearity = 1.0;
    } else if (type[0] == 2.0) {
      m->linearity = 0.0;
    } else if (type[0] == 3.0) {
      std::vector<double> p;
      if (!Take(entries, path, "P", 1, &p, error)) return false;
      m->linearity = p[0];
    } else {
      *error = Message(path, entries["T"].line, "T",
                       "CAHVORE model type must be 1 (perspective), 2 (fisheye) or 3 (general)");
      return false;
    }
  }
  if (entries.count("Dimensions") != 0) {
    if (!Take(entries, path, "Dimensions", 2, &dims, error)) return false;
    if (!(dims[0] >= 1 && dims[0] <= 1e6 && dims[1] >= 1 && dims[1] <= 1e6)) {
      *error = Message(path, entries["Dimensions"].line, "Dimensions", "not an image size");
      return false;
    }
    m->width = static_cast<int>(dims[0]);
    m->height = static_cast<int>(dims[1]);
    if (dims[0] != m->width || dims[1] != m->height || m->width < 1 || m->height < 1) {
      *error = Message(path, entries["Dimensions"].line, "Dimensions", "not a whole image size");
      return false;
    }
  } else {
    m->width = options.width;
    m->height = options.height;
  }
  if (m->width <= 0 || m->height <= 0) {
    *error =
        Message(path, 0, "Dimensions", "no image size in the file and none given (--size WxH)");
    return false;
  }
  if (!(m->a.norm() > 0.0) || (has_o && !(m->o.norm() > 0.0))) {
    *error = Message(path, 0, m->a.norm() > 0.0 ? "O" : "A", "is a zero vector");
    return false;
  }
  m->a.normalize();
  if (has_o) m->o.normalize();
  if (has_o && m->o.dot(m->a) < 0.5) {
    *error = Message(path, entries["O"].line, "O", "is more than 60 degrees off the axis A");
    return false;
  }
  return true;
}

// Least-squares radial fit of the model over the image (file comment); the residual's largest
// value in *max_error_px.
bool Linearize(const std::string& path, const JplModel& m, CameraCalibration* cam,
               double* max_error_px, std::string* error) {
  const double hc = m.a.dot(m.h);
  const double hs = m.a.cross(m.h).norm();
  const double vc = m.a.dot(m.v);
  const double vs = m.a.cross(m.v).norm();
  if (!(hs > 0.0 && vs > 0.0)) {
    *error = Message(path, 0, "H", "H or V is parallel to A: no focal length");
    return false;
  }
  const Eigen::Vector3d x_axis = (m.h - hc * m.a) / hs;
  const Eigen::Vector3d v_axis = (m.v - vc * m.a) / vs;
  const Eigen::Vector3d y_axis = m.a.cross(x_axis);
  if (y_axis.dot(v_axis) <= 0.0) {
    *error = Message(path, 0, "V", "points against A x H: a mirrored camera");
    return false;
  }
  std::vector<Eigen::Vector2d> normalized;
  std::vector<Eigen::Vector2d> imaged;
  constexpr int kGrid = 41;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      // Ideal pixels over the image and a quarter beyond each side (barrel distortion pulls
      // directions from outside the ideal field into the image).
      const double u = m.width * (-0.25 + 1.5 * i / (kGrid - 1));
      const double v = m.height * (-0.25 + 1.5 * j / (kGrid - 1));
      const Eigen::Vector2d n((u - hc) / hs, (v - vc) / vs);
      Eigen::Vector2d image;
      if (!ProjectDirection(m, n.x() * x_axis + n.y() * y_axis + m.a, &image)) continue;
      if (image.x() < 0 || image.y() < 0 || image.x() > m.width || image.y() > m.height) continue;
      normalized.push_back(n);
      imaged.push_back(image);
    }
  }
  if (normalized.size() < 16) {
    *error = Message(path, 0, "", "the model images too few directions inside its image");
    return false;
  }
  Eigen::MatrixXd design(2 * normalized.size(), 4);
  Eigen::VectorXd rhs(2 * normalized.size());
  for (std::size_t k = 0; k < normalized.size(); ++k) {
    const double r2 = normalized[k].squaredNorm();
    const Eigen::RowVector4d powers(1.0, r2, r2 * r2, r2 * r2 * r2);
    design.row(2 * k) = hs * normalized[k].x() * powers;
    design.row(2 * k + 1) = vs * normalized[k].y() * powers;
    rhs(2 * k) = imaged[k].x() - hc;
    rhs(2 * k + 1) = imaged[k].y() - vc;
  }
  const Eigen::Vector4d b = design.colPivHouseholderQr().solve(rhs);
  const Eigen::VectorXd residual = design * b - rhs;
  *max_error_px = 0.0;
  for (Eigen::Index k = 0; k + 1 < residual.size(); k += 2) {
    *max_error_px = std::max(*max_error_px, std::hypot(residual(k), residual(k + 1)));
  }
  if (!(b[0] > 0.0) || !b.allFinite()) {
    *error = Message(path, 0, "R", "the radial terms fold the image over (no usable focal length)");
    return false;
  }
  *cam = CameraCalibration{};
  cam->width = m.width;
  cam->height = m.height;
  cam->fx = hs * b[0];
  cam->fy = vs * b[0];
  cam->cx = hc;
  cam->cy = vc;
  cam->k1 = b[1] / b[0];
  cam->k2 = b[2] / b[0];
  cam->k3 = b[3] / b[0];
  Eigen::Matrix3d body_R_camera;
  body_R_camera << x_axis, y_axis, m.a;
  cam->body_T_camera = PoseD{body_R_camera, m.c};
  return true;
}

bool ReadCahvorCamera(const std::string& path, const ImportOptions& options, CameraCalibration* c,
                      double* error_px, std::string* error) {
  JplModel model;
  if (!ReadJplModel(path, options, &model, error) || !Linearize(path, model, c, error_px, error)) {
    return false;
  }
  if (*error_px > options.max_linearization_error_px) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "the model differs from its pinhole + radial linearization by up to %.3g px "
                  "(limit %.3g px): a fisheye lens or an optical axis O far from A",
                  *error_px, options.max_linearization_error_px);
    *error = Message(path, 0, "", text);
    return false;
  }
  return true;
}

}  // namespace

// The lines of `text` that hold something, comments (#) removed.
std::vector<std::string> ContentLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r") != std::string::npos) lines.push_back(line);
  }
  return lines;
}

// KITTI odometry's calib.txt names its lines "P0: ..."; the excerpt in /work/shared/data holds
// the two rows bare. Both are read.
bool LooksLikeKitti(const std::string& text) {
  if (text.rfind("P0:", 0) == 0 || text.find("\nP0:") != std::string::npos) return true;
  const std::vector<std::string> lines = ContentLines(text);
  if (lines.size() != 2) return false;
  for (const std::string& line : lines) {
    std::istringstream in(line);
    double v = 0.0;
    int count = 0;
    while (in >> v) ++count;
    if (count != 12 || !in.eof()) return false;
  }
  return true;
}

bool LooksLikeCahvor(const std::string& text) {
  std::vector<std::string> duplicates;
  const std::map<std::string, Entry> entries = ReadEntries(text, '=', &duplicates);
  return entries.count("C") != 0 && entries.count("A") != 0;
}

// KITTI: P_i = K [I | t_i] of the rectified cameras, so the right camera (P1) sits at
// b = -(P1[0][3] - P0[0][3]) / fx along the left camera's x axis.
bool ReadKitti(const std::string& path, const ImportOptions& options, StereoCalibration* out,
               std::string* error) {
  std::map<std::string, Entry> entries;
  if (!ReadEntriesOf(path, ':', &entries, error)) return false;
  if (entries.empty()) {
    std::string text;
    if (!ReadText(path, &text, error)) return false;
    const std::vector<std::string> lines = ContentLines(text);
    if (lines.size() == 2) {
      entries = ReadEntries("P0: " + lines[0] + "\nP1: " + lines[1] + "\n", ':', nullptr);
    }
  }
  std::vector<double> p0;
  std::vector<double> p1;
  if (!Take(entries, path, "P0", 12, &p0, error) || !Take(entries, path, "P1", 12, &p1, error)) {
    return false;
  }
  const int line1 = entries["P1"].line;
  if (p0[1] != 0.0 || p0[4] != 0.0 || p0[8] != 0.0 || p0[9] != 0.0 || p0[10] != 1.0) {
    *error = Message(path, entries["P0"].line, "P0",
                     "is not K [I | t] with K = [fx 0 cx; 0 fy cy; 0 0 1]");
    return false;
  }
  for (const int i : {0, 1, 2, 4, 5, 6, 8, 9, 10}) {
    if (std::fabs(p1[i] - p0[i]) > 1e-6 * std::max(1.0, std::fabs(p0[i]))) {
      *error = Message(path, line1, "P1", "its K differs from P0's: not a rectified pair");
      return false;
    }
  }
  if (options.width <= 0 || options.height <= 0) {
    *error = Message(path, 0, "", "calib.txt carries no image size: give it (--size WxH)");
    return false;
  }
  const double baseline_m = -(p1[3] - p0[3]) / p0[0];
  for (CameraCalibration* c : {&out->left, &out->right}) {
    *c = CameraCalibration{};
    c->width = options.width;
    c->height = options.height;
    c->fx = p0[0];
    c->fy = p0[5];
    c->cx = p0[2];
    c->cy = p0[6];
  }
  out->right.body_T_camera.t = Eigen::Vector3d(baseline_m, 0.0, 0.0);
  return true;
}

bool ReadCahvorPair(const std::string& left, const std::string& right, const ImportOptions& options,
                    StereoCalibration* out, std::string* error) {
  double left_error_px = 0.0;
  double right_error_px = 0.0;
  if (!ReadCahvorCamera(left, options, &out->left, &left_error_px, error) ||
      !ReadCahvorCamera(right, options, &out->right, &right_error_px, error)) {
    return false;
  }
  out->linearization_error_px = std::max(left_error_px, right_error_px);
  return true;
}

}  // namespace swf::calibration::internal
