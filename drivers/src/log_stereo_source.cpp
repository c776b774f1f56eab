#include "swf/drivers/log_stereo_source.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "swf/drivers/imu_message.hpp"
#include "swf/drivers/stereo_frame_message.hpp"
#include "swf/messages/checked_decode.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::drivers {

namespace {
constexpr std::uint32_t kLogMagic = 0xEDA1DA01u;
constexpr std::size_t kRecordHeaderBytes = 4 + 8 + 8 + 4 + 4;  // sync, eventnum, time, lengths
constexpr std::int64_t kMaxChannelBytes = 256;                 // LCM's own channel name limit

std::uint32_t Be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}
std::int64_t Be64(const std::uint8_t* p) {
  return static_cast<std::int64_t>((std::uint64_t{Be32(p)} << 32) | Be32(p + 4));
}
}  // namespace

bool LogReader::Open(const std::string& path, std::string* error) {
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!*file || ec || std::filesystem::is_directory(path)) {
    *error = path + ": cannot open the log";
    return false;
  }
  path_ = path;
  in_ = std::move(file);
  size_ = size;
  pos_ = 0;
  index_ = 0;
  return true;
}

void LogReader::OpenBytes(std::string bytes, const std::string& name) {
  path_ = name;
  size_ = bytes.size();
  in_ = std::make_unique<std::istringstream>(std::move(bytes), std::ios::binary);
  pos_ = 0;
  index_ = 0;
}

int LogReader::Next(LogEvent* event, std::string* error) {
  if (in_ == nullptr || pos_ == size_) return 0;
  const std::uint64_t left = size_ - pos_;
  auto fail = [&](const std::string& why) {
    *error = path_ + ": record " + std::to_string(index_) + " at byte " + std::to_string(pos_) +
             ": " + why;
    return -1;
  };
  if (left < kRecordHeaderBytes) {
    return fail("truncated header (" + std::to_string(left) + " of " +
                std::to_string(kRecordHeaderBytes) + " bytes)");
  }
  std::uint8_t header[kRecordHeaderBytes];
  if (!in_->read(reinterpret_cast<char*>(header), sizeof header)) return fail("read error");
  if (Be32(header) != kLogMagic) return fail("bad sync word (corrupt record)");
  const std::int64_t eventnum = Be64(header + 4);
  const std::int64_t timestamp = Be64(header + 12);
  const std::int64_t channel_len = static_cast<std::int32_t>(Be32(header + 20));
  const std::int64_t data_len = static_cast<std::int32_t>(Be32(header + 24));
  if (channel_len <= 0 || channel_len > kMaxChannelBytes) {
    return fail("bad channel length " + std::to_string(channel_len));
  }
  if (data_len < 0) return fail("bad data length " + std::to_string(data_len));
  if (data_len > messages::kMaxEncodedBytes) {
    return fail("data length " + std::to_string(data_len) + " over the largest message (" +
                std::to_string(messages::kMaxEncodedBytes) + " bytes)");
  }
  const std::uint64_t need = kRecordHeaderBytes + static_cast<std::uint64_t>(channel_len) +
                             static_cast<std::uint64_t>(data_len);
  if (need > left) {
    return fail("truncated (" + std::to_string(left) + " of " + std::to_string(need) + " bytes)");
  }
  // Both lengths are now bounded and present in the file.
  event->channel.resize(static_cast<std::size_t>(channel_len));
  event->data.resize(static_cast<std::size_t>(data_len));
  if (!in_->read(event->channel.data(), channel_len) ||
      !in_->read(reinterpret_cast<char*>(event->data.data()), data_len)) {
    return fail("read error");
  }
  event->index = index_;
  event->offset = static_cast<std::int64_t>(pos_);
  event->eventnum = eventnum;
  event->timestamp = timestamp;
  pos_ += need;
  ++index_;
  return 1;
}

bool LogStereoSource::Load(const std::string& path, const std::string& channel,
                           std::string* error) {
  LogReader reader;
  if (!reader.Open(path, error)) return false;
  Load(&reader, channel);
  return true;
}

void LogStereoSource::Load(LogReader* reader, const std::string& channel) {
  frames_.clear();
  imu_.clear();
  imu_pending_ = 0;
  load_error_.clear();
  stream_ = LogStreamStats{};
  LogEvent event;
  swf_msgs::stereo_frame_t msg;
  for (;;) {
    std::string why;
    const int r = reader->Next(&event, &why);
    if (r == 0) break;
    if (r < 0) {
      load_error_ = why;
      break;
    }
    if (event.channel != channel && (imu_channel_.empty() || event.channel != imu_channel_))
      continue;
    const std::string where = reader->Path() + ": record " + std::to_string(event.index) + " (" +
                              event.channel + ", event " + std::to_string(event.eventnum) + ")";
    if (event.channel == imu_channel_) {
      load_error_ = AddImuRecord(event.data, where);
      if (!load_error_.empty()) break;
      continue;
    }
    const messages::DecodeError decoded =
        messages::CheckedDecode(event.data.data(), event.data.size(), &msg);
    if (!decoded.Ok()) {
      char what[128];
      messages::Describe(decoded, what, sizeof what);
      load_error_ = where + ": stereo_frame_t does not decode (" + what + ")";
      break;
    }
    char bad[96];
    if (!CheckStereoFrameFields(msg, bad, sizeof bad)) {
      load_error_ = where + ": " + bad;
      break;
    }
    if (!frames_.empty() && (msg.width != width_ || msg.height != height_)) {
      load_error_ = where + ": image size changed within the log";
      break;
    }
    width_ = msg.width;
    height_ = msg.height;
    rectified_ = msg.rectified;
    Frame f;
    f.seq = msg.seq;
    f.left_ns = msg.left_exposure_utime * core::kNsPerUs;  // in range: CheckStereoFrameFields
    f.right_ns = msg.right_exposure_utime * core::kNsPerUs;
    f.dropped_before = msg.dropped_before;
    f.has_motion = msg.has_motion;
    for (int i = 0; i < 3; ++i) {
      f.motion.translation_m[i] = msg.motion_translation_m[i];
      f.motion.rotation_rad[i] = msg.motion_rotation_rad[i];
    }
    f.left = std::move(msg.left);
    f.right = std::move(msg.right);
    Admit(std::move(f));
  }
}

// "" when the record decoded into a sample (kept for the next frame), else why not. The
// sample's values are the stream checker's to judge (ImuStreamChecker), not the reader's.
std::string LogStereoSource::AddImuRecord(const std::vector<std::uint8_t>& data,
                                          const std::string& where) {
  swf_msgs::imu_t msg;
  const messages::DecodeError decoded = messages::CheckedDecode(data.data(), data.size(), &msg);
  if (!decoded.Ok()) {
    char what[128];
    messages::Describe(decoded, what, sizeof what);
    return where + ": imu_t does not decode (" + what + ")";
  }
  imu_.push_back(ImuSampleOf(msg));
  return "";
}

void LogStereoSource::Admit(Frame frame) {
  if (!frames_.empty()) {
    const Frame& last = frames_.back();
    if (frame.seq == last.seq) {
      ++stream_.duplicates;
      return;
    }
    if (frame.seq < last.seq || frame.left_ns <= last.left_ns) {
      ++stream_.out_of_order;
      return;
    }
    // Both sequence numbers are non-negative: the gap cannot overflow. Frames the recorded
    // dropped_before already accounts for were never in the log: only the rest of the gap is
    // missing from it.
    std::int64_t missing = 0;
    frame.dropped_before = static_cast<std::int32_t>(
        PairsLostBefore(frame.seq - last.seq - 1, frame.dropped_before, &missing));
    stream_.frames_missing += missing;
  }
  frame.imu_begin = imu_pending_;
  frame.imu_end = imu_.size();
  imu_pending_ = imu_.size();
  frames_.push_back(std::move(frame));
}

bool LogStereoSource::NextImu(std::int64_t /*until_utime*/, estimator::ImuSample<double>* sample) {
  // The samples recorded before the frame just served (next_ - 1), in their order.
  if (next_ == 0) return false;
  const Frame& f = frames_[next_ - 1];
  imu_next_ = std::max(imu_next_, f.imu_begin);
  if (imu_next_ >= f.imu_end) return false;
  *sample = imu_[imu_next_++];
  return true;
}

bool LogStereoSource::Motion(std::uint64_t seq, MotionInput* input) {
  // Frames are served in order; the one just served is next_ - 1.
  if (next_ == 0 || frames_[next_ - 1].seq != static_cast<std::int64_t>(seq)) return false;
  if (!frames_[next_ - 1].has_motion) return false;
  *input = frames_[next_ - 1].motion;
  return true;
}

core::Status LogStereoSource::Start() {
  next_ = 0;
  imu_next_ = 0;
  stats_ = SourceStats{};
  // Refused while loading; gaps are counted through each pair's dropped_before instead.
  stats_.frames_rejected = static_cast<std::uint64_t>(stream_.Refused());
  return core::Status::kOk;
}

core::Status LogStereoSource::Next(core::TimeNs /*timeout_ns*/, StereoPair* pair) {
  if (next_ >= frames_.size()) return core::Status::kEmpty;
  const Frame& f = frames_[next_];
  pair->left = core::ImageView<const std::uint8_t>{f.left.data(), width_, height_, width_};
  pair->right = core::ImageView<const std::uint8_t>{f.right.data(), width_, height_, width_};
  pair->left_exposure_ns = f.left_ns;
  pair->right_exposure_ns = f.right_ns;
  pair->seq = static_cast<std::uint64_t>(f.seq);
  pair->dropped_before = static_cast<std::uint32_t>(f.dropped_before);
  pair->handle = static_cast<std::int32_t>(next_);
  ++next_;
  ++stats_.pairs_served;
  return core::Status::kOk;
}

}  // namespace swf::drivers
