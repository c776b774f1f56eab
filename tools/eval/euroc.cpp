#include "euroc.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "euroc_imu.hpp"
#include "input_file.hpp"
#include "report.hpp"
#include "swf/evaluation/statistics.hpp"
#include "swf/frontend/rectify.hpp"
#include "swf/image_io/image_io.hpp"

namespace swf::eval {
namespace {

using evaluation::Median;

// A file name as quoted in a message: at most 120 characters of it (a hostile list may hold a
// line of megabytes).
std::string Quoted(const std::string& name) {
  constexpr std::size_t kMaxQuoted = 120;
  return "'" + (name.size() <= kMaxQuoted ? name : name.substr(0, kMaxQuoted) + "...") + "'";
}

// One data.csv line "timestamp_ns,filename" (already trimmed, not a comment).
bool ParseCsvLine(const std::string& line, const std::string& where, ListedImage* f,
                  std::string* error) {
  const std::size_t comma = line.find(',');
  char* end = nullptr;
  errno = 0;
  f->stamp_ns = std::strtoll(line.c_str(), &end, 10);
  if (comma == std::string::npos || end != line.c_str() + comma || f->stamp_ns <= 0 ||
      errno == ERANGE) {
    *error = where + ": expected: timestamp_ns,filename";
    return false;
  }
  f->name = line.substr(comma + 1);
  while (!f->name.empty() && f->name.front() == ' ') f->name.erase(f->name.begin());
  std::string why;
  if (!CheckImageName(f->name, &why)) {
    *error = where + ": " + why;
    return false;
  }
  // ASL names the image after its timestamp: a name that says otherwise is a shifted list.
  const std::size_t dot = f->name.find('.');
  const std::string stem = f->name.substr(0, dot);
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  if (!stem.empty() && std::all_of(stem.begin(), stem.end(), digit) &&
      stem != std::to_string(f->stamp_ns)) {
    *error = where + ": the image " + Quoted(f->name) + " is listed at timestamp " +
             std::to_string(f->stamp_ns) + " ns (the list is shifted against its files)";
    return false;
  }
  return true;
}

bool ReadCsv(const std::string& path, std::vector<ListedImage>* frames, std::string* error) {
  return ParseFile(path, ParseImageList, frames, error);
}

// A stereo pair is exposed together: line k of cam1's list must carry line k of cam0's
// timestamp.
bool CheckPairs(const std::string& left_csv, const std::vector<ListedImage>& left,
                const std::string& right_csv, const std::vector<ListedImage>& right,
                std::string* error) {
  const std::size_t n = std::min(left.size(), right.size());
  for (std::size_t k = 0; k < n; ++k) {
    if (left[k].stamp_ns != right[k].stamp_ns) {
      *error = right_csv + ":" + std::to_string(right[k].line) + ": timestamp " +
               std::to_string(right[k].stamp_ns) + " ns differs from " + left_csv + ":" +
               std::to_string(left[k].line) + " (" + std::to_string(left[k].stamp_ns) +
               " ns): the left and right image lists do not pair up (shifted by a frame?)";
      return false;
    }
  }
  if (left.size() != right.size()) {
    const bool more_left = left.size() > right.size();
    const ListedImage& extra = more_left ? left[n] : right[n];
    *error = (more_left ? left_csv : right_csv) + ":" + std::to_string(extra.line) +
             ": no matching image in " + (more_left ? right_csv : left_csv) + " (" +
             std::to_string(left.size()) + " left, " + std::to_string(right.size()) +
             " right images)";
    return false;
  }
  return true;
}

bool LoadCameras(const std::string& mav0, StereoSequence* s, std::string* error) {
  for (int c = 0; c < 2; ++c) {
    const std::string yaml = mav0 + "/cam" + std::to_string(c) + "/sensor.yaml";
    if (!image_io::LoadCalibration(yaml, &s->calibration[c], error)) return false;
    if (!CheckCalibration(s->calibration[c], yaml, error)) return false;
  }
  return true;
}

// Configures a rectifier like the pipeline's to learn the rectified camera and where it sits in
// the body frame, and refuses a rig whose rectified image mostly has no source pixel.
bool RectifiedRig(const std::string& mav0, StereoSequence* s, PoseD* body_T_camera,
                  std::string* error) {
  auto rectifier = std::make_unique<frontend::StereoRectifier>();
  frontend::RectifyOptions ro;
  ro.width = s->width;
  ro.height = s->height;
  if (rectifier->Configure(s->calibration[0], s->calibration[1], ro) != core::Status::kOk) {
    *error = mav0 + "/cam0|cam1/sensor.yaml: the rectifier rejected this stereo calibration";
    return false;
  }
  int inside = 0;
  int total = 0;
  for (int cam = 0; cam < 2; ++cam) {
    for (int v = 0; v < s->height; v += 8) {
      for (int u = 0; u < s->width; u += 8) {
        float ru = 0.0f;
        float rv = 0.0f;
        inside += rectifier->TablePixel(cam, u, v, &ru, &rv);
        ++total;
      }
    }
  }
  if (inside < total / 2) {
    char buf[160];
    std::snprintf(buf, sizeof(buf),
                  ": only %.0f%% of the rectified image has a source pixel in the raw images",
                  100.0 * inside / std::max(total, 1));
    *error = mav0 + "/cam0|cam1/sensor.yaml" + buf;
    return false;
  }
  s->camera = rectifier->Camera();
  *body_T_camera = rectifier->RectifiedInBody();
  return true;
}

// The images must have the size the calibration was made for: the first image of each list is
// checked (the pipeline refuses any later frame of another size, naming it).
bool CheckImageSizes(const std::string& mav0, const StereoSequence& s,
                     const std::vector<ListedImage>& left, const std::vector<ListedImage>& right,
                     std::string* error) {
  const ListedImage* first[2] = {&left.front(), &right.front()};
  for (int c = 0; c < 2; ++c) {
    const std::string cam = mav0 + "/cam" + std::to_string(c);
    const std::string image = cam + "/data/" + first[c]->name;
    int w = 0;
    int h = 0;
    if (!image_io::ReadImageSize(image, &w, &h, error)) return false;
    const frontend::CameraCalibration& k = s.calibration[c];
    if (w != k.width || h != k.height) {
      *error = image + Format(" is %d x %d px but ", w, h) + cam +
               Format("/sensor.yaml's resolution is %d x %d", k.width, k.height);
      return false;
    }
  }
  return true;
}

double MedianInterval(const std::vector<ListedImage>& frames) {
  std::vector<double> d;
  for (std::size_t k = 1; k < frames.size(); ++k) {
    d.push_back(static_cast<double>(frames[k].stamp_ns - frames[k - 1].stamp_ns));
  }
  return d.empty() ? 5e7 : Median(d);
}

// The recorded frames that have ground truth within 5 ms (the ground truth may start later or
// end earlier than the images).
void Associate(const std::string& mav0, const std::vector<ListedImage>& left,
               const std::vector<ListedImage>& right, const std::vector<TumPose>& gt,
               const PoseD& body_T_camera, EurocResult* r) {
  for (std::size_t k = 0; k < left.size(); ++k) {
    const double t = static_cast<double>(left[k].stamp_ns) * 1e-9;
    const auto nearest =
        std::min_element(gt.begin(), gt.end(), [t](const TumPose& a, const TumPose& b) {
          return std::fabs(a.stamp_s - t) < std::fabs(b.stamp_s - t);
        });
    if (std::fabs(nearest->stamp_s - t) > 0.005) {
      ++r->skipped_frames;
      continue;
    }
    SequenceFrame f;
    f.left_path = mav0 + "/cam0/data/" + left[k].name;
    f.right_path = mav0 + "/cam1/data/" + right[k].name;
    f.stamp_ns = left[k].stamp_ns;
    f.truth = nearest->pose * body_T_camera;
    f.source = static_cast<int>(r->sequence.frames.size());
    f.record = "cam0/data.csv:" + std::to_string(left[k].line);
    r->sequence.frames.push_back(f);
  }
}

void Loop(double seconds, double interval_ns, StereoSequence* s) {
  const std::vector<SequenceFrame> recorded = s->frames;
  const int total = static_cast<int>(std::lround(seconds * 1e9 / interval_ns));
  s->frames.clear();
  const std::int64_t t0 = recorded.front().stamp_ns;
  const std::vector<int> order = PingPong(static_cast<int>(recorded.size()), total);
  for (std::size_t k = 0; k < order.size(); ++k) {
    SequenceFrame f = recorded[static_cast<std::size_t>(order[k])];
    f.stamp_ns = t0 + static_cast<std::int64_t>(std::llround(static_cast<double>(k) * interval_ns));
    s->frames.push_back(f);
  }
}

void PathStats(EurocResult* r) {
  const std::vector<SequenceFrame>& f = r->sequence.frames;
  for (std::size_t j = 0; j < f.size(); ++j) {
    if (j > 0) r->gt_path_length_m += (f[j].truth.t - f[j - 1].truth.t).norm();
    r->gt_extent_m = std::max(r->gt_extent_m, (f[j].truth.t - f[0].truth.t).norm());
  }
}

}  // namespace

bool ParseImageList(std::istream& csv, const std::string& path, std::vector<ListedImage>* frames,
                    std::string* error) {
  std::string line;
  int number = 0;
  while (std::getline(csv, line)) {
    ++number;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    ListedImage f;
    f.line = number;
    const std::string where = path + ":" + std::to_string(number);
    if (!ParseCsvLine(line, where, &f, error)) return false;
    if (!frames->empty() && f.stamp_ns <= frames->back().stamp_ns) {
      *error = where + ": timestamp " + std::to_string(f.stamp_ns) +
               " ns does not increase (previous line " + std::to_string(frames->back().line) + ")";
      return false;
    }
    frames->push_back(f);
  }
  if (frames->empty()) {
    *error = path + ": no frames";
    return false;
  }
  return true;
}

bool CheckImageName(const std::string& name, std::string* error) {
  if (name.empty()) {
    *error = "empty image file name";
    return false;
  }
  for (char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) {
      *error = "image name contains a control character (refused: not a file name)";
      return false;
    }
  }
  if (name.front() == '/') {
    *error =
        "image name " + Quoted(name) + " is an absolute path (refused: names are inside data/)";
    return false;
  }
  std::stringstream parts(name);
  std::string part;
  while (std::getline(parts, part, '/')) {
    if (part == "..") {
      *error = "image name " + Quoted(name) + " contains '..' (refused: names are inside data/)";
      return false;
    }
  }
  return true;
}

namespace {

// The index of the first value whose magnitude exceeds `bound` (or is not a number), or -1.
int FirstBeyond(const double* values, int n, double bound) {
  for (int i = 0; i < n; ++i) {
    if (!(std::fabs(values[i]) <= bound)) return i;
  }
  return -1;
}

// Focal lengths that give a believable lens over the image (see the bounds in euroc.hpp).
bool CheckFocalLengths(const frontend::CameraCalibration& c, const std::string& path,
                       std::string* error) {
  const double fov_deg = 2.0 * std::atan(0.5 * c.width / c.fx) * 180.0 / M_PI;
  const double aspect = c.fx / c.fy;
  if (fov_deg < kMinFieldOfViewDeg || fov_deg > kMaxFieldOfViewDeg) {
    *error = path + Format(
                        ": focal length fx %g px over %d px gives a horizontal field of view of "
                        "%.3g deg, outside %g..%g deg",
                        c.fx, c.width, fov_deg, kMinFieldOfViewDeg, kMaxFieldOfViewDeg);
    return false;
  }
  if (!(aspect <= kMaxPixelAspect && aspect >= 1.0 / kMaxPixelAspect)) {
    *error = path + Format(": focal lengths fx %g and fy %g px differ by more than a factor of %g",
                           c.fx, c.fy, kMaxPixelAspect);
    return false;
  }
  return true;
}

bool CheckDistortionBounds(const frontend::CameraCalibration& c, const std::string& path,
                           std::string* error) {
  static const char* const kRadial[] = {"k1", "k2", "k3"};
  static const char* const kTangential[] = {"p1", "p2"};
  const double radial[] = {c.k1, c.k2, c.k3};
  const double tangential[] = {c.p1, c.p2};
  const int r = FirstBeyond(radial, 3, kMaxRadialCoefficient);
  if (r >= 0) {
    *error = path + Format(": distortion coefficient %s = %g is beyond |%s| <= %g", kRadial[r],
                           radial[r], kRadial[r], kMaxRadialCoefficient);
    return false;
  }
  const int t = FirstBeyond(tangential, 2, kMaxTangentialCoefficient);
  if (t >= 0) {
    *error = path + Format(": distortion coefficient %s = %g is beyond |%s| <= %g", kTangential[t],
                           tangential[t], kTangential[t], kMaxTangentialCoefficient);
    return false;
  }
  return true;
}

}  // namespace

bool CheckCalibration(const frontend::CameraCalibration& c, const std::string& path,
                      std::string* error) {
  if (!(c.fx > 0.0 && c.fy > 0.0) || c.width <= 0 || c.height <= 0) {
    *error = path + Format(": focal lengths (%g, %g) and resolution (%d x %d) must be positive",
                           c.fx, c.fy, c.width, c.height);
    return false;
  }
  if (!CheckFocalLengths(c, path, error)) return false;
  if (!(c.cx >= 0.0 && c.cx < c.width && c.cy >= 0.0 && c.cy < c.height)) {
    *error = path + Format(": principal point (%g, %g) lies outside the %d x %d image", c.cx, c.cy,
                           c.width, c.height);
    return false;
  }
  if (!CheckDistortionBounds(c, path, error)) return false;
  // The distorted radius r (1 + k1 r^2 + k2 r^4 + k3 r^6) must keep growing from the centre
  // until it reaches the farthest image corner, or some pixels have two (or no) undistorted
  // directions and rectification cannot be inverted there.
  const double du = std::max(c.cx, c.width - c.cx) / c.fx;
  const double dv = std::max(c.cy, c.height - c.cy) / c.fy;
  const double corner = std::hypot(du, dv);
  const auto distorted = [&c](double r) {
    const double r2 = r * r;
    return r * (1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3)));
  };
  double previous = 0.0;
  for (double r = 1e-3; r <= 10.0; r += 1e-3) {
    const double d = distorted(r);
    if (!(d > previous)) {
      *error = path + Format(
                          ": the radial distortion (k1 %g, k2 %g, k3 %g) folds back at a "
                          "distorted radius of %.3g, inside the image (corner at %.3g): not a "
                          "usable calibration",
                          c.k1, c.k2, c.k3, previous, corner);
      return false;
    }
    if (d >= corner) return true;
    previous = d;
  }
  *error = path + ": the radial distortion never reaches the image corner";
  return false;
}

bool ReadTum(const std::string& path, std::vector<TumPose>* poses, std::string* error) {
  std::ifstream file;
  if (!OpenInput(path, &file, error)) return false;
  std::string line;
  int number = 0;
  while (std::getline(file, line)) {
    ++number;
    if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos) {
      continue;
    }
    std::istringstream fields(line);
    double v[8];
    for (double& x : v) fields >> x;
    if (!fields || !std::all_of(v, v + 8, [](double x) { return std::isfinite(x); })) {
      *error = path + ":" + std::to_string(number) + ": expected: timestamp tx ty tz qx qy qz qw";
      return false;
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::fabs(q.norm() - 1.0) > 1e-3) {
      *error = path + ":" + std::to_string(number) + ": quaternion is not unit length";
      return false;
    }
    TumPose p;
    p.stamp_s = v[0];
    p.pose.R = q.normalized().toRotationMatrix();
    p.pose.t = Vec3D(v[1], v[2], v[3]);
    poses->push_back(p);
  }
  if (poses->empty()) {
    *error = path + ": no poses";
    return false;
  }
  return true;
}

bool WriteTum(const std::string& path, const std::vector<TumPose>& poses) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  std::fprintf(f, "# timestamp(s) tx ty tz qx qy qz qw\n");
  for (const TumPose& p : poses) {
    const Eigen::Quaterniond q(p.pose.R);
    std::fprintf(f, "%.6f %.6f %.6f %.6f %.7f %.7f %.7f %.7f\n", p.stamp_s, p.pose.t.x(),
                 p.pose.t.y(), p.pose.t.z(), q.x(), q.y(), q.z(), q.w());
  }
  return std::fclose(f) == 0;
}

namespace {

// Gravity at the recording site (Zurich, about 9.807 m/s^2); its direction comes from the truth.
constexpr double kEarthGravityMps2 = 9.807;

// mav0/imu0 when it is there: samples, noise, the camera in the IMU frame; gravity and the
// IMU's velocity at the first frame in the estimate's world (the first camera's frame) from the
// ground truth (EuRoC's world z is up), standing in for the state guidance hands over.
bool LoadImu(const std::string& mav0, const PoseD& body_T_camera, StereoSequence* s,
             std::string* error) {
  const std::string csv = mav0 + "/imu0/data.csv";
  if (!std::filesystem::exists(csv)) return true;
  EurocImuCalibration calibration;
  if (!ReadEurocImuCalibration(mav0 + "/imu0/sensor.yaml", &calibration, error) ||
      !ReadEurocImuSamples(csv, &s->imu, error)) {
    return false;
  }
  s->imu_noise = calibration.noise;
  s->imu_period_us = std::llround(1e6 / calibration.rate_hz);
  s->imu_T_camera = calibration.body_T_imu.Inverse() * body_T_camera;
  const PoseD& first = s->frames[0].truth;
  s->gravity_world_mps2 = first.R.transpose() * Vec3D(0.0, 0.0, -kEarthGravityMps2);
  const double dt_s = 1e-9 * static_cast<double>(s->frames[1].stamp_ns - s->frames[0].stamp_ns);
  s->initial_velocity_mps = (first.Inverse() * s->frames[1].truth).t / dt_s;
  return true;
}

}  // namespace

bool LoadEuroc(const std::string& dir, const EurocOptions& options, EurocResult* result,
               std::string* error) {
  const std::string mav0 = dir + "/mav0";
  StereoSequence& s = result->sequence;
  s.name = "EuRoC";
  s.dir = dir;
  s.rectify = true;
  if (!LoadCameras(mav0, &s, error)) return false;
  s.width = s.calibration[0].width;
  s.height = s.calibration[0].height;
  PoseD body_T_camera;
  if (!RectifiedRig(mav0, &s, &body_T_camera, error)) return false;
  std::vector<ListedImage> left;
  std::vector<ListedImage> right;
  const std::string left_csv = mav0 + "/cam0/data.csv";
  const std::string right_csv = mav0 + "/cam1/data.csv";
  if (!ReadCsv(left_csv, &left, error) || !ReadCsv(right_csv, &right, error)) return false;
  if (!CheckPairs(left_csv, left, right_csv, right, error) ||
      !CheckImageSizes(mav0, s, left, right, error))
    return false;
  std::vector<TumPose> gt;
  if (!ReadTum(dir + "/groundtruth_tum.txt", &gt, error)) return false;
  Associate(mav0, left, right, gt, body_T_camera, result);
  result->recorded_frames = static_cast<int>(s.frames.size());
  // EuRoC's world z is up (gravity): the vertical in the first camera's frame.
  if (!s.frames.empty()) s.up_world = s.frames[0].truth.R.transpose() * Vec3D::UnitZ();
  if (result->recorded_frames < 3) {
    *error = dir + "/groundtruth_tum.txt: fewer than 3 of the " + std::to_string(left.size()) +
             " listed frames have a ground-truth pose within 5 ms";
    return false;
  }
  const double interval_ns = MedianInterval(left);
  result->frame_interval_s = interval_ns * 1e-9;
  PathStats(result);
  if (options.loop_seconds > 0.0) {
    Loop(options.loop_seconds, interval_ns, &s);  // the IMU does not loop with the images
  } else if (!LoadImu(mav0, body_T_camera, &s, error)) {
    return false;
  }
  return true;
}

bool RunEuroc(const std::string& dir, const EurocOptions& options, EurocResult* result,
              std::string* error) {
  return LoadAndRun(&LoadEuroc, dir, options, result, error);
}

}  // namespace swf::eval
