#include "kitti.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "euroc.hpp"  // CheckCalibration: the same bounds
#include "input_file.hpp"
#include "report.hpp"
#include "swf/image_io/image_io.hpp"

namespace swf::eval {
namespace {

// Twelve finite numbers of one line, after an optional "label:".
bool ReadTwelve(const std::string& line, const std::string& where, double v[12],
                std::string* error) {
  std::string body = line;
  const std::size_t colon = body.find(':');
  if (colon != std::string::npos) body = body.substr(colon + 1);
  std::istringstream fields(body);
  for (int i = 0; i < 12; ++i) fields >> v[i];
  std::string rest;
  if (!fields || (fields >> rest) ||
      !std::all_of(v, v + 12, [](double x) { return std::isfinite(x); })) {
    *error = where + ": expected 12 finite numbers (a row-major 3x4 matrix)";
    return false;
  }
  return true;
}

bool ReadMatrices(std::istream& file, const std::string& path,
                  std::vector<std::vector<double>>* rows, std::vector<int>* lines,
                  std::string* error) {
  std::string line;
  int number = 0;
  while (std::getline(file, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    double v[12];
    if (!ReadTwelve(line, path + ":" + std::to_string(number), v, error)) return false;
    rows->emplace_back(v, v + 12);
    lines->push_back(number);
  }
  return true;
}

std::string FramePath(const std::string& dir, int camera, int k) {
  char name[32];
  std::snprintf(name, sizeof(name), "/image_%d/%06d.png", camera, k);
  return dir + name;
}

// The image size from the first pair's headers; both must agree (the pipeline refuses any later
// frame of another size, naming it).
bool ImageSize(const std::string& dir, int* width, int* height, std::string* error) {
  int w[2] = {0, 0};
  int h[2] = {0, 0};
  for (int c = 0; c < 2; ++c) {
    if (!image_io::ReadImageSize(FramePath(dir, c, 0), &w[c], &h[c], error)) return false;
  }
  if (w[0] != w[1] || h[0] != h[1]) {
    *error = FramePath(dir, 1, 0) + Format(" is %d x %d px but ", w[1], h[1]) +
             FramePath(dir, 0, 0) + Format(" is %d x %d px: not a rectified pair", w[0], h[0]);
    return false;
  }
  *width = w[0];
  *height = h[0];
  return true;
}

}  // namespace

bool ReadKittiCalibration(const std::string& path, estimator::StereoCamera<double>* camera,
                          std::string* error) {
  return ParseFile(path, ParseKittiCalibration, camera, error);
}

bool ParseKittiCalibration(std::istream& file, const std::string& path,
                           estimator::StereoCamera<double>* camera, std::string* error) {
  std::vector<std::vector<double>> p;
  std::vector<int> lines;
  if (!ReadMatrices(file, path, &p, &lines, error)) return false;
  if (p.size() < 2) {
    *error =
        path + ": expected two projection matrices P0 and P1, found " + std::to_string(p.size());
    return false;
  }
  const std::vector<double>& p0 = p[0];
  const std::vector<double>& p1 = p[1];
  camera->fx = p0[0];
  camera->fy = p0[5];
  camera->cx = p0[2];
  camera->cy = p0[6];
  camera->baseline_m = p1[0] > 0.0 ? -p1[3] / p1[0] : 0.0;
  // The rectified pair shares K; P0 has no translation.
  const bool same_k = p0[0] == p1[0] && p0[2] == p1[2] && p0[5] == p1[5] && p0[6] == p1[6];
  if (!(camera->fx > 0.0 && camera->fy > 0.0) || !same_k || p0[3] != 0.0) {
    *error = path + ":" + std::to_string(lines[1]) +
             ": P0 and P1 are not a rectified pair (positive focal lengths, the same K, P0 "
             "without translation)";
    return false;
  }
  if (!(camera->baseline_m > 0.0)) {
    *error = path + ":" + std::to_string(lines[1]) +
             Format(
                 ": baseline -P1[0,3]/P1[0,0] = %g m, "
                 "must be positive",
                 camera->baseline_m);
    return false;
  }
  return true;
}

bool ReadKittiPoses(const std::string& path, std::vector<PoseD>* poses, std::string* error) {
  return ParseFile(path, ParseKittiPoses, poses, error);
}

bool ParseKittiPoses(std::istream& file, const std::string& path, std::vector<PoseD>* poses,
                     std::string* error) {
  std::vector<std::vector<double>> rows;
  std::vector<int> lines;
  if (!ReadMatrices(file, path, &rows, &lines, error)) return false;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    PoseD p;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) p.R(r, c) = rows[k][4 * r + c];
      p.t[r] = rows[k][4 * r + 3];
    }
    const double orthogonality =
        (p.R.transpose() * p.R - estimator::Mat3<double>::Identity()).norm();
    if (orthogonality > 1e-3 || p.R.determinant() < 0.0) {
      *error = path + ":" + std::to_string(lines[k]) + ": the 3x3 part is not a rotation";
      return false;
    }
    poses->push_back(p);
  }
  if (poses->size() < 3) {
    *error = path + ": fewer than 3 poses";
    return false;
  }
  return true;
}

bool LoadKitti(const std::string& dir, const KittiOptions& options, KittiResult* result,
               std::string* error) {
  StereoSequence& s = result->sequence;
  s.name = "KITTI odometry";
  s.dir = dir;
  s.rectify = false;
  s.up_world = Vec3D(0.0, -1.0, 0.0);  // KITTI cameras: y down, mounted level on the car
  if (!ReadKittiCalibration(dir + "/calib.txt", &s.camera, error)) return false;
  std::vector<PoseD> poses;
  if (!ReadKittiPoses(dir + "/poses.txt", &poses, error)) return false;
  if (options.max_frames >= 3 && poses.size() > static_cast<std::size_t>(options.max_frames)) {
    poses.resize(static_cast<std::size_t>(options.max_frames));
  }
  if (!ImageSize(dir, &s.width, &s.height, error)) return false;
  // The rectified pair as calibrations (no distortion left, the right camera at +b along x),
  // held to the same bounds as a EuRoC camera; what a log of this sequence is flown with.
  frontend::CameraCalibration& left = s.calibration[0];
  left.width = s.width;
  left.height = s.height;
  left.fx = s.camera.fx;
  left.fy = s.camera.fy;
  left.cx = s.camera.cx;
  left.cy = s.camera.cy;
  if (!CheckCalibration(left, dir + "/calib.txt", error)) return false;
  if (s.camera.baseline_m > kMaxKittiBaselineM) {
    *error = dir + "/calib.txt" +
             Format(": baseline %g m is beyond %g m (a P1[0,3] in millimetres?)",
                    s.camera.baseline_m, kMaxKittiBaselineM);
    return false;
  }
  s.calibration[1] = left;
  s.calibration[1].body_T_camera.t = Vec3D(s.camera.baseline_m, 0.0, 0.0);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    SequenceFrame f;
    f.left_path = FramePath(dir, 0, static_cast<int>(k));
    f.right_path = FramePath(dir, 1, static_cast<int>(k));
    f.stamp_ns = static_cast<std::int64_t>(k) * 100000000;  // 10 Hz
    f.truth = poses[k];
    f.source = static_cast<int>(k);
    f.record = "poses.txt:" + std::to_string(k + 1);
    s.frames.push_back(f);
    if (k > 0) result->gt_path_length_m += (poses[k].t - poses[k - 1].t).norm();
  }
  return true;
}

bool RunKitti(const std::string& dir, const KittiOptions& options, KittiResult* result,
              std::string* error) {
  return LoadAndRun(&LoadKitti, dir, options, result, error);
}

}  // namespace swf::eval
