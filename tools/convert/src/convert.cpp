// The converters of swf-convert (convert.hpp). Datasets are read by swf-eval's own loaders
// (tools/eval: the same pairing, timestamp and calibration checks), so a log holds exactly the
// frames swf-eval runs.
#include "swf/convert/convert.hpp"

#include <lcm/eventlog.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <regex>

#include "euroc.hpp"
#include "kitti.hpp"
#include "swf/calibration/calibration_import.hpp"
#include "swf/drivers/imu_message.hpp"
#include "swf/drivers/log_stereo_source.hpp"
#include "swf/image_io/image_io.hpp"
#include "swf_msgs/imu_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace swf::convert {

namespace {

namespace fs = std::filesystem;
using PoseD = estimator::Pose<double>;

constexpr const char* kStereoChannel = "SWF_STEREO";
constexpr const char* kImuChannel = "SWF_IMU";
constexpr const char* kTruthChannel = "GROUND_TRUTH";

// A file written under a temporary name in its final directory and renamed over the target on
// Commit; dropped (removed) otherwise, so no half-written file is ever left under the name.
class TempFile {
 public:
  explicit TempFile(const std::string& path)
      : path_(path), temp_(path + ".tmp" + std::to_string(::getpid())) {}
  ~TempFile() {
    if (!committed_) std::remove(temp_.c_str());
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& Temp() const { return temp_; }
  bool Prepare(std::string* error) {
    const fs::path parent = fs::path(path_).parent_path();
    std::error_code ec;
    if (!parent.empty()) fs::create_directories(parent, ec);
    if (ec) *error = parent.string() + ": cannot create the directory (" + ec.message() + ")";
    return !ec;
  }
  bool Commit(std::string* error) {
    if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
      *error = path_ + ": cannot write (rename failed)";
      return false;
    }
    committed_ = true;
    return true;
  }

 private:
  std::string path_;
  std::string temp_;
  bool committed_ = false;
};

bool WriteText(const std::string& path, const std::string& text, std::string* error) {
  TempFile file(path);
  if (!file.Prepare(error)) return false;
  std::FILE* f = std::fopen(file.Temp().c_str(), "w");
  if (f == nullptr || std::fwrite(text.data(), 1, text.size(), f) != text.size() ||
      std::fclose(f) != 0) {
    *error = path + ": cannot write";
    return false;
  }
  return file.Commit(error);
}

// An LCM log being written (the C event-log API: the same file format lcm-logger writes).
class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : file_(path), path_(path) {}
  ~LogWriter() {
    if (log_ != nullptr) lcm_eventlog_destroy(log_);
  }
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;
  bool Open(std::string* error) {
    if (!file_.Prepare(error)) return false;
    log_ = lcm_eventlog_create(file_.Temp().c_str(), "w");
    if (log_ == nullptr) *error = path_ + ": cannot create the log";
    return log_ != nullptr;
  }
  template <typename Message>
  bool Write(const char* channel, std::int64_t utime, const Message& msg, std::string* error) {
    buffer_.resize(static_cast<std::size_t>(msg.getEncodedSize()));
    if (msg.encode(buffer_.data(), 0, static_cast<int>(buffer_.size())) < 0) {
      *error = path_ + ": cannot encode a " + channel + " message";
      return false;
    }
    lcm_eventlog_event_t event{};
    event.eventnum = events_++;
    event.timestamp = utime;
    event.channellen = static_cast<std::int32_t>(std::string(channel).size());
    event.datalen = static_cast<std::int32_t>(buffer_.size());
    event.channel = const_cast<char*>(channel);
    event.data = buffer_.data();
    if (lcm_eventlog_write_event(log_, &event) != 0) {
      *error = path_ + ": write failed (disk full?)";
      return false;
    }
    return true;
  }
  bool Commit(std::string* error) {
    lcm_eventlog_destroy(log_);
    log_ = nullptr;
    return file_.Commit(error);
  }

 private:
  TempFile file_;
  std::string path_;
  lcm_eventlog_t* log_ = nullptr;
  std::int64_t events_ = 0;
  std::vector<std::uint8_t> buffer_;
};

void SetQuaternion(const Eigen::Matrix3d& r, double q[4]) {
  const Eigen::Quaterniond quat(r);
  q[0] = quat.w();
  q[1] = quat.x();
  q[2] = quat.y();
  q[3] = quat.z();
}

// One raw pair from its two image files.
bool FrameMessage(const std::string& left, const std::string& right, std::int64_t seq,
                  std::int64_t utime, std::int32_t dropped_before, swf_msgs::stereo_frame_t* msg,
                  std::string* error) {
  image_io::GrayImage l;
  image_io::GrayImage r;
  if (!image_io::LoadGray(left, &l, error) || !image_io::LoadGray(right, &r, error)) return false;
  if (l.width != r.width || l.height != r.height) {
    *error = right + ": " + std::to_string(r.width) + "x" + std::to_string(r.height) +
             " px, its left image " + left + " is " + std::to_string(l.width) + "x" +
             std::to_string(l.height);
    return false;
  }
  msg->utime = utime;
  msg->seq = seq;
  msg->left_exposure_utime = utime;
  msg->right_exposure_utime = utime;
  msg->dropped_before = dropped_before;
  msg->rectified = false;
  msg->has_motion = false;
  msg->width = l.width;
  msg->height = l.height;
  msg->num_bytes = l.width * l.height;
  msg->left = std::move(l.pixels);
  msg->right = std::move(r.pixels);
  return true;
}

swf_msgs::truth_state_t TruthMessage(const PoseD& world_T_camera, std::int64_t seq,
                                     std::int64_t utime) {
  swf_msgs::truth_state_t t{};
  t.utime = utime;
  t.frame_seq = seq;
  for (int i = 0; i < 3; ++i) t.position_world_m[i] = world_T_camera.t[i];
  SetQuaternion(world_T_camera.R, t.orientation_world_q);
  t.altitude_m = std::nan("");  // unknown: no terrain model
  return t;
}

bool WriteCalibrations(const std::string& dir, const frontend::CameraCalibration& left,
                       const frontend::CameraCalibration& right, std::string* error) {
  if (dir.empty()) return true;
  return WriteText(dir + "/left.yaml", calibration::EurocSensorYaml(left), error) &&
         WriteText(dir + "/right.yaml", calibration::EurocSensorYaml(right), error);
}

// The frames of a loaded sequence (with its IMU and truth) into the log.
bool SequenceToLog(const eval::StereoSequence& s, const LogInputOptions& options,
                   InputSummary* summary, std::string* error) {
  LogWriter log(options.log_path);
  if (!log.Open(error)) return false;
  std::size_t next_imu = 0;
  const std::size_t frames = options.max_frames > 0
                                 ? std::min<std::size_t>(options.max_frames, s.frames.size())
                                 : s.frames.size();
  for (std::size_t j = 0; j < frames; ++j) {
    const eval::SequenceFrame& f = s.frames[j];
    const std::int64_t utime = f.stamp_ns / 1000;
    // The samples up to this exposure go before it, as the flight process records them.
    for (; next_imu < s.imu.size() && s.imu[next_imu].t_us <= utime; ++next_imu) {
      swf_msgs::imu_t m{};
      drivers::ImuMessageOf(s.imu[next_imu], &m);
      if (!log.Write(kImuChannel, s.imu[next_imu].t_us, m, error)) return false;
      ++summary->imu_samples;
    }
    swf_msgs::stereo_frame_t msg;
    if (!FrameMessage(f.left_path, f.right_path, static_cast<std::int64_t>(j), utime, 0, &msg,
                      error) ||
        !log.Write(kStereoChannel, utime, msg, error) ||
        !log.Write(kTruthChannel, utime, TruthMessage(f.truth, msg.seq, utime), error)) {
      return false;
    }
    summary->width = msg.width;
    summary->height = msg.height;
    ++summary->frames;
    ++summary->truth_poses;
  }
  return log.Commit(error);
}

}  // namespace

bool EurocToLog(const std::string& dir, const LogInputOptions& options, InputSummary* summary,
                std::string* error) {
  *summary = InputSummary{};
  eval::EurocResult euroc;
  if (!eval::LoadEuroc(dir, eval::EurocOptions{}, &euroc, error)) return false;
  const eval::StereoSequence& s = euroc.sequence;
  return WriteCalibrations(options.calib_dir, s.calibration[0], s.calibration[1], error) &&
         SequenceToLog(s, options, summary, error);
}

bool KittiToLog(const std::string& dir, const LogInputOptions& options, InputSummary* summary,
                std::string* error) {
  *summary = InputSummary{};
  eval::KittiResult kitti;
  eval::KittiOptions ko;
  ko.max_frames = options.max_frames;
  if (!eval::LoadKitti(dir, ko, &kitti, error)) return false;
  const eval::StereoSequence& s = kitti.sequence;
  // KITTI's frames are 10 Hz; the excerpt's list has no times, so LoadKitti numbers them.
  return WriteCalibrations(options.calib_dir, s.calibration[0], s.calibration[1], error) &&
         SequenceToLog(s, options, summary, error);
}

bool GrabToLog(const std::string& dir, const LogInputOptions& options, InputSummary* summary,
               std::string* error) {
  *summary = InputSummary{};
  if (!(options.rate_hz >= 0.001 && options.rate_hz <= 10000.0)) {
    *error = "--rate-hz must be in [0.001, 10000]";
    return false;
  }
  const std::regex name("left_([0-9]{1,12})\\.png");
  std::map<std::int64_t, std::string> lefts;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    std::smatch m;
    const std::string file = entry.path().filename().string();
    if (std::regex_match(file, m, name)) lefts[std::stoll(m[1].str())] = m[1].str();
  }
  if (ec) {
    *error = dir + ": cannot list (" + ec.message() + ")";
    return false;
  }
  if (lefts.empty()) {
    *error = dir + ": no left_NNNNNN.png (swf-grab's output)";
    return false;
  }
  LogWriter log(options.log_path);
  if (!log.Open(error)) return false;
  std::int64_t previous = -1;
  for (const auto& [seq, digits] : lefts) {
    if (options.max_frames > 0 && summary->frames >= options.max_frames) break;
    const std::string left = dir + "/left_" + digits + ".png";
    const std::string right = dir + "/right_" + digits + ".png";
    if (!fs::exists(right)) {
      *error = right + ": missing (its left image " + left + " exists)";
      return false;
    }
    const double utime_us = static_cast<double>(seq) * 1e6 / options.rate_hz;
    if (utime_us > 1e15) {  // ~30 years: beyond any capture, and far inside int64 microseconds
      *error = left + ": sequence number " + std::to_string(seq) + " at " +
               std::to_string(options.rate_hz) + " Hz is beyond any recording's time";
      return false;
    }
    const std::int64_t utime = std::llround(utime_us);
    const auto dropped = static_cast<std::int32_t>(previous < 0 ? 0 : seq - previous - 1);
    swf_msgs::stereo_frame_t msg;
    if (!FrameMessage(left, right, seq, utime, dropped, &msg, error) ||
        !log.Write(kStereoChannel, utime, msg, error)) {
      return false;
    }
    if (summary->frames > 0 && (msg.width != summary->width || msg.height != summary->height)) {
      *error = left + ": size differs from the first pair's";
      return false;
    }
    summary->width = msg.width;
    summary->height = msg.height;
    ++summary->frames;
    previous = seq;
  }
  return log.Commit(error);
}

namespace {

// Calls `each` with every decoded message of type Message on `channel`; stops at a damaged record
// or an undecodable message with *error naming the file and record.
template <typename Message, typename Each>
bool ForEachMessage(const std::string& log_path, const std::string& channel, Each each,
                    std::string* error) {
  return drivers::ForEachLogEvent(
      log_path,
      [&](const drivers::LogEvent& event) {
        if (event.channel != channel) return true;
        Message msg;
        if (msg.decode(event.data.data(), 0, static_cast<int>(event.data.size())) < 0) {
          *error = log_path + ": record " + std::to_string(event.index) + " (" + channel +
                   "): does not decode as " + Message::getTypeName();
          return false;
        }
        return each(msg, event.index, error);
      },
      error);
}

bool WriteGrayPng(const std::string& path, const std::vector<std::uint8_t>& pixels, int width,
                  int height, std::string* error) {
  TempFile file(path);
  if (stbi_write_png(file.Temp().c_str(), width, height, 1, pixels.data(), width) == 0) {
    *error = path + ": cannot write";
    return false;
  }
  return file.Commit(error);
}

// "1403715273.262142" from microseconds, exactly (no rounding through a double).
std::string Seconds(std::int64_t utime) {
  char text[40];
  std::snprintf(text, sizeof text, "%lld.%06lld", static_cast<long long>(utime / 1000000),
                static_cast<long long>(utime % 1000000));
  return text;
}

}  // namespace

bool LogToPngs(const std::string& log_path, const std::string& channel, const std::string& out_dir,
               std::int64_t* pairs, std::string* error) {
  *pairs = 0;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) {
    *error = out_dir + ": cannot create (" + ec.message() + ")";
    return false;
  }
  const auto write = [&](const swf_msgs::stereo_frame_t& m, std::int64_t record, std::string* e) {
    char name[64];
    if (m.width <= 0 || m.height <= 0 ||
        static_cast<std::int64_t>(m.width) * m.height != m.num_bytes) {
      *e = log_path + ": record " + std::to_string(record) + ": image size does not match";
      return false;
    }
    std::snprintf(name, sizeof name, "/left_%06lld.png", static_cast<long long>(m.seq));
    if (!WriteGrayPng(out_dir + name, m.left, m.width, m.height, e)) return false;
    std::snprintf(name, sizeof name, "/right_%06lld.png", static_cast<long long>(m.seq));
    if (!WriteGrayPng(out_dir + name, m.right, m.width, m.height, e)) return false;
    ++*pairs;
    return true;
  };
  if (!ForEachMessage<swf_msgs::stereo_frame_t>(log_path, channel, write, error)) return false;
  if (*pairs == 0) {
    *error = log_path + ": no " + channel + " records";
    return false;
  }
  return true;
}

bool LogToTrajectory(const std::string& log_path, const std::string& channel,
                     const std::string& tum_path, const std::string& kitti_path, bool anchor_first,
                     std::int64_t* poses, std::string* error) {
  *poses = 0;
  std::string tum = "# timestamp(s) tx ty tz qx qy qz qw (world_T_camera, rectified left camera)\n";
  std::string kitti;
  PoseD first_T_world;
  const auto add = [&](const swf_msgs::nav_state_t& m, std::int64_t record, std::string* e) {
    const double* q = m.orientation_world_q;
    const double* p = m.position_world_m;
    const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
    if (!std::isfinite(quat.norm()) || std::fabs(quat.norm() - 1.0) > 1e-6 ||
        !std::isfinite(p[0] + p[1] + p[2])) {
      *e = log_path + ": record " + std::to_string(record) +
           ": the pose is not finite or its quaternion not unit";
      return false;
    }
    PoseD pose{quat.normalized().toRotationMatrix(), Eigen::Vector3d(p[0], p[1], p[2])};
    if (anchor_first && *poses == 0) first_T_world = pose.Inverse();
    if (anchor_first) pose = first_T_world * pose;
    const Eigen::Matrix3d& r = pose.R;
    const Eigen::Vector3d& t = pose.t;
    const Eigen::Quaterniond out(r);
    char line[400];
    std::snprintf(line, sizeof line, "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n",
                  Seconds(m.utime).c_str(), t[0], t[1], t[2], out.x(), out.y(), out.z(), out.w());
    tum += line;
    std::snprintf(line, sizeof line,
                  "%.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e\n", r(0, 0), r(0, 1),
                  r(0, 2), t[0], r(1, 0), r(1, 1), r(1, 2), t[1], r(2, 0), r(2, 1), r(2, 2), t[2]);
    kitti += line;
    ++*poses;
    return true;
  };
  if (!ForEachMessage<swf_msgs::nav_state_t>(log_path, channel, add, error)) return false;
  if (*poses == 0) {
    *error = log_path + ": no " + channel + " records (a replay's --record holds them)";
    return false;
  }
  return (tum_path.empty() || WriteText(tum_path, tum, error)) &&
         (kitti_path.empty() || WriteText(kitti_path, kitti, error));
}

bool TumAteAgainstEuroc(const std::string& tum_path, const std::string& euroc_dir,
                        AteResult* result, std::string* error) {
  *result = AteResult{};
  std::vector<eval::TumPose> estimate;
  if (!eval::ReadTum(tum_path, &estimate, error)) return false;
  eval::EurocResult euroc;
  if (!eval::LoadEuroc(euroc_dir, eval::EurocOptions{}, &euroc, error)) return false;
  std::vector<PoseD> truth;
  std::vector<PoseD> matched;
  for (const eval::TumPose& p : estimate) {
    for (const eval::SequenceFrame& f : euroc.sequence.frames) {
      if (std::fabs(1e-9 * static_cast<double>(f.stamp_ns) - p.stamp_s) < 1e-3) {
        truth.push_back(f.truth);
        matched.push_back(p.pose);
        break;
      }
    }
  }
  result->matched = static_cast<int>(matched.size());
  if (matched.size() < 3) {
    *error = tum_path + ": fewer than 3 poses match a frame of " + euroc_dir + " (within 1 ms)";
    return false;
  }
  const eval::TrajectoryErrors errors = eval::ScoreTrajectory(truth, matched);
  if (!errors.finite) {
    *error = tum_path + ": " + errors.reason;
    return false;
  }
  result->ate_rmse_m = errors.ate_rmse_m;
  result->ate_max_m = errors.ate_max_m;
  return true;
}

}  // namespace swf::convert
