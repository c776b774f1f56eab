#include "euroc.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "swf/estimator/stereo_model.hpp"
#include "swf/frontend/frontend.hpp"
#include "swf/frontend/rectify.hpp"
#include "swf/image_io/image_io.hpp"

namespace swf::eval {
namespace {

using estimator::Mat3;
using estimator::Mat6;

// Window up to 20 poses, 1024 active landmarks, a front end's worth of measurements per frame,
// 512 landmarks in the prior.
using EurocFilter = estimator::SlidingWindowFilter<estimator::StereoModel<double>, 20, 1024,
                                                   static_cast<int>(frontend::kMaxTracks), 512>;

struct Frame {
  std::int64_t stamp_ns = 0;
  std::string name;
};

bool ReadCsv(const std::string& path, std::vector<Frame>* frames, std::string* error) {
  std::ifstream csv(path);
  if (!csv) {
    *error = path + ": cannot open";
    return false;
  }
  std::string line;
  int number = 0;
  while (std::getline(csv, line)) {
    ++number;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const std::size_t comma = line.find(',');
    Frame f;
    char* end = nullptr;
    f.stamp_ns = std::strtoll(line.c_str(), &end, 10);
    if (comma == std::string::npos || end != line.c_str() + comma || f.stamp_ns <= 0) {
      *error = path + ":" + std::to_string(number) + ": expected: timestamp_ns,filename";
      return false;
    }
    f.name = line.substr(comma + 1);
    while (!f.name.empty() && f.name.front() == ' ') f.name.erase(f.name.begin());
    frames->push_back(f);
  }
  if (frames->empty()) {
    *error = path + ": no frames";
    return false;
  }
  return true;
}

frontend::HarrisOptions DetectorFor(int width, int height) {
  frontend::HarrisOptions o;
  o.bucket_cols = std::max(1, std::min(64, width / 40));
  o.bucket_rows = std::max(1, std::min(64, height / 40));
  return o;
}

struct Inputs {
  frontend::CameraCalibration cal[2];
  std::vector<Frame> left;
  std::vector<std::string> right_names;
  std::vector<TumPose> truth;  // per frame
};

bool RunOne(const std::string& mav0, const Inputs& in, const EurocOptions& options, EurocRun* run,
            std::string* error) {
  auto rectifier = std::make_unique<frontend::StereoRectifier>();
  if (rectifier->Configure(in.cal[0], in.cal[1], frontend::RectifyOptions{}) != core::Status::kOk) {
    *error = mav0 + ": the rectifier rejected cam0/cam1 sensor.yaml";
    return false;
  }
  frontend::FrontendOptions fo;
  fo.camera = rectifier->Camera();
  fo.harris = DetectorFor(rectifier->Width(), rectifier->Height());
  fo.max_tracks = options.max_tracks;
  auto front = std::make_unique<frontend::Frontend>();
  if (front->Configure(fo) != core::Status::kOk) {
    *error = "front end configuration rejected";
    return false;
  }
  auto swf = std::make_unique<EurocFilter>();
  estimator::StereoModel<double> model;
  model.camera = rectifier->Camera();
  estimator::SwfOptions so;
  so.mode = run->mode;
  so.window_size = options.window;
  if (swf->Configure(model, so) != core::Status::kOk) {
    *error = "estimator configuration rejected";
    return false;
  }
  Mat6<double> q_sqrt = Mat6<double>::Zero();
  q_sqrt.diagonal() << Vec3D::Constant(1 / options.motion_sigma_m),
      Vec3D::Constant(1 / options.motion_sigma_rad);
  const Mat3<double> r_sqrt = Mat3<double>::Identity() / options.sigma_px;
  const PoseD camera_T_body = rectifier->RectifiedInBody().Inverse();
  auto out = std::make_unique<frontend::FrameOutput>();
  std::vector<frontend::LandmarkEstimate> estimates;
  estimates.reserve(4096);
  image_io::GrayImage raw[2];
  image_io::GrayImage rect[2];
  rect[0].Resize(rectifier->Width(), rectifier->Height());
  rect[1].Resize(rectifier->Width(), rectifier->Height());
  PoseD previous;
  PoseD last;
  double measurements = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t j = 0; j < in.left.size(); ++j) {
    const std::string paths[2] = {mav0 + "/cam0/data/" + in.left[j].name,
                                  mav0 + "/cam1/data/" + in.right_names[j]};
    for (int c = 0; c < 2; ++c) {
      if (!image_io::LoadGray(paths[c], &raw[c], error)) return false;
    }
    if (rectifier->Rectify(raw[0].View(), raw[1].View(), rect[0].MutableView(),
                           rect[1].MutableView()) != core::Status::kOk) {
      *error = paths[0] + ": cannot rectify (size differs from sensor.yaml?)";
      return false;
    }
    frontend::FramePrediction prediction;
    if (options.predict && j >= 1) {
      // Constant velocity, as AddPoseConstantVelocity will predict it.
      prediction.has_pose = true;
      prediction.world_T_camera = j >= 2 ? last * (previous.Inverse() * last) : last;
      estimates.clear();
      swf->ForEachLandmark([&](std::int64_t id, const Vec3D& p, int) {
        estimates.push_back({static_cast<std::uint32_t>(id), p});
      });
      prediction.landmarks = estimates.data();
      prediction.num_landmarks = estimates.size();
    }
    if (front->ProcessFrame(frontend::StereoFrame{rect[0].View(), rect[1].View()}, prediction,
                            out.get()) != core::Status::kOk) {
      *error = paths[0] + ": front end failed";
      return false;
    }
    if (j == 0 || swf->NumPoses() == 0) {
      (void)swf->AddPose(j == 0 ? PoseD{} : last);
    } else {
      (void)swf->AddPoseConstantVelocity(q_sqrt);
    }
    for (const frontend::StereoMeasurement& m : out->measurements) {
      measurements += swf->AddObservation(m.landmark_id, Vec3D(m.u_left, m.u_right, m.v), r_sqrt) ==
                      core::Status::kOk;
    }
    for (const frontend::NewLandmark& n : out->new_landmarks) {
      measurements += swf->AddObservation(n.landmark_id, Vec3D(n.u_left, n.u_right, n.v), r_sqrt) ==
                      core::Status::kOk;
    }
    const core::Status status = swf->Update();
    if (status != core::Status::kOk && status != core::Status::kNotConverged) {
      ++run->update_failures;
    }
    previous = last;
    if (swf->NumPoses() > 0) last = swf->NewestPose();
    run->estimate.push_back({in.truth[j].stamp_s, last * camera_T_body});
  }
  run->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run->mean_measurements = measurements / static_cast<double>(in.left.size());
  // Align the whole estimated trajectory to the ground truth, then score it.
  std::vector<Vec3D> gt;
  std::vector<Vec3D> est;
  for (std::size_t j = 0; j < in.truth.size(); ++j) {
    gt.push_back(in.truth[j].pose.t);
    est.push_back(run->estimate[j].pose.t);
  }
  const PoseD align = AlignRigid(gt, est);
  double sum = 0.0;
  for (std::size_t j = 0; j < gt.size(); ++j) {
    const double e = (gt[j] - align.Apply(est[j])).norm();
    run->error_m.push_back(e);
    sum += e * e;
    run->ate_max_m = std::max(run->ate_max_m, e);
  }
  run->ate_rmse_m = std::sqrt(sum / static_cast<double>(gt.size()));
  run->final_error_m = run->error_m.back();
  return true;
}

}  // namespace

PoseD AlignRigid(const std::vector<Vec3D>& a, const std::vector<Vec3D>& b) {
  PoseD out;
  const std::size_t n = std::min(a.size(), b.size());
  if (n == 0) return out;
  Vec3D mean_a = Vec3D::Zero();
  Vec3D mean_b = Vec3D::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean_a += a[i] / static_cast<double>(n);
    mean_b += b[i] / static_cast<double>(n);
  }
  Mat3<double> cross = Mat3<double>::Zero();  // sum (a - mean_a)(b - mean_b)^T
  for (std::size_t i = 0; i < n; ++i) cross += (a[i] - mean_a) * (b[i] - mean_b).transpose();
  const Eigen::JacobiSVD<Mat3<double>> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3<double> sign = Mat3<double>::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) sign(2, 2) = -1.0;
  out.R = svd.matrixU() * sign * svd.matrixV().transpose();
  out.t = mean_a - out.R * mean_b;
  return out;
}

bool ReadTum(const std::string& path, std::vector<TumPose>* poses, std::string* error) {
  std::ifstream file(path);
  if (!file) {
    *error = path + ": cannot open";
    return false;
  }
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

bool RunEuroc(const std::string& dir, const EurocOptions& options, EurocResult* result,
              std::string* error) {
  const std::string mav0 = dir + "/mav0";
  Inputs in;
  for (int c = 0; c < 2; ++c) {
    const std::string yaml = mav0 + "/cam" + std::to_string(c) + "/sensor.yaml";
    if (!image_io::LoadCalibration(yaml, &in.cal[c], error)) return false;
  }
  std::vector<Frame> left;
  std::vector<Frame> right;
  if (!ReadCsv(mav0 + "/cam0/data.csv", &left, error)) return false;
  if (!ReadCsv(mav0 + "/cam1/data.csv", &right, error)) return false;
  std::vector<TumPose> gt;
  if (!ReadTum(dir + "/groundtruth_tum.txt", &gt, error)) return false;
  std::map<std::int64_t, std::string> right_by_stamp;
  for (const Frame& f : right) right_by_stamp[f.stamp_ns] = f.name;
  // Frames with a right image and a ground-truth pose within 5 ms.
  for (const Frame& f : left) {
    const auto r = right_by_stamp.find(f.stamp_ns);
    if (r == right_by_stamp.end()) continue;
    const double t = static_cast<double>(f.stamp_ns) * 1e-9;
    const auto nearest =
        std::min_element(gt.begin(), gt.end(), [t](const TumPose& a, const TumPose& b) {
          return std::fabs(a.stamp_s - t) < std::fabs(b.stamp_s - t);
        });
    if (std::fabs(nearest->stamp_s - t) > 0.005) continue;
    in.left.push_back(f);
    in.right_names.push_back(r->second);
    in.truth.push_back({t, nearest->pose});
  }
  if (in.left.size() < 3) {
    *error = dir + ": fewer than 3 frames with both images and ground truth";
    return false;
  }
  result->frames = static_cast<int>(in.left.size());
  result->ground_truth = in.truth;
  for (std::size_t j = 0; j < in.truth.size(); ++j) {
    if (j > 0) result->gt_path_length_m += (in.truth[j].pose.t - in.truth[j - 1].pose.t).norm();
    result->gt_extent_m =
        std::max(result->gt_extent_m, (in.truth[j].pose.t - in.truth[0].pose.t).norm());
  }
  const std::string k = std::to_string(options.window);
  result->runs.clear();
  for (const auto mode :
       {estimator::SwfMode::kSlidingWindow, estimator::SwfMode::kVisualOdometry}) {
    EurocRun run;
    run.mode = mode;
    run.name = (mode == estimator::SwfMode::kSlidingWindow ? "SWF(" : "VO(") + k + ")";
    if (!RunOne(mav0, in, options, &run, error)) return false;
    result->runs.push_back(run);
  }
  {
    auto rectifier = std::make_unique<frontend::StereoRectifier>();
    (void)rectifier->Configure(in.cal[0], in.cal[1], frontend::RectifyOptions{});
    result->focal_px = rectifier->Camera().fx;
    result->baseline_m = rectifier->Camera().baseline_m;
  }
  return true;
}

}  // namespace swf::eval
