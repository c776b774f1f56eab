// Reading the flight process's LCM logs back (swf-replay): records one by one with errors that
// name the record, and the stereo frames of a log as a StereoSource, checked for gaps,
// duplicates and reordering. Depends on messages, drivers' interface and fsw/core only, so the
// fuzz harness (fsw/app/fuzz) builds without the rest of the flight process.
#pragma once

#include <cstdint>
#include <istream>
#include <memory>
#include <string>
#include <vector>

#include "swf/drivers/process_input.hpp"
#include "swf/drivers/stereo_source.hpp"

namespace swf::drivers {

// One event of an LCM log.
struct LogEvent {
  std::int64_t index = 0;   // 0-based record number in the file
  std::int64_t offset = 0;  // byte offset of the record
  std::int64_t eventnum = 0;
  std::int64_t timestamp = 0;  // microseconds
  std::string channel;
  std::vector<std::uint8_t> data;
};

// Reads LCM logs record by record, streaming: a record's length is checked against the bytes left
// in the file and the largest message any type may encode (messages::kMaxEncodedBytes) before its
// buffer is allocated. A damaged record is reported, not skipped.
class LogReader {
 public:
  bool Open(const std::string& path, std::string* error);
  // A log held in memory (tests, fuzzing); `name` stands for the path in messages.
  void OpenBytes(std::string bytes, const std::string& name);
  // 1: an event; 0: clean end of file; -1: damaged record, *error names it.
  int Next(LogEvent* event, std::string* error);
  const std::string& Path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<std::istream> in_;
  std::uint64_t size_ = 0;  // bytes in the log
  std::uint64_t pos_ = 0;   // offset of the next record
  std::int64_t index_ = 0;
};

// Calls each(event) with every event of the log at `path`, in order. False with *error naming
// the file or the damaged record, or when each returns false (having set *error itself).
template <typename Each>
bool ForEachLogEvent(const std::string& path, Each each, std::string* error) {
  LogReader reader;
  if (!reader.Open(path, error)) return false;
  LogEvent event;
  for (;;) {
    const int r = reader.Next(&event, error);
    if (r <= 0) return r == 0;
    if (!each(event)) return false;
  }
}

// The stereo stream of a log, as the sequence and time checks found it. Frames must come with
// consecutive sequence numbers and advancing exposure times: a gap is frames missing from the log
// (served as pair.dropped_before) unless the frame after it recorded them as dropped by the camera
// (its dropped_before: the gap of a source that numbers across its losses, the simulator), a
// repeated number a duplicate and a number or time behind the last one served a reordered frame;
// both of the latter are refused, never fused.
struct LogStreamStats {
  std::int64_t frames_missing = 0;  // sequence gaps (lost, cut or misnamed records)
  std::int64_t duplicates = 0;      // refused: the sequence number of the frame before
  std::int64_t out_of_order = 0;    // refused: a sequence number or exposure time going back
  std::int64_t Refused() const { return duplicates + out_of_order; }
};

// The stereo frames of a log, decoded (swf/messages/checked_decode.hpp) and checked before start
// (replay is a ground tool; no file I/O on the real-time thread). Loading stops at the first
// damaged record, undecodable frame or out-of-range field; the frames before it are replayed and
// the error is kept for the caller to report. Duplicated and reordered frames are refused and
// counted (LogStreamStats, and SourceStats::frames_rejected); gaps reach the flight loop as
// pair.dropped_before. With an IMU channel set, the imu_t samples recorded between two frames
// are served (ImuProvider) with the later frame, as the live run handed them over; a refused
// frame's samples go with the next one served.
class LogStereoSource final : public StereoSource, public MotionProvider, public ImuProvider {
 public:
  // Before Load: the channel of the recorded IMU ("" = none).
  void SetImuChannel(const std::string& channel) { imu_channel_ = channel; }
  // False only when the file cannot be opened; a damaged record sets LoadError().
  bool Load(const std::string& path, const std::string& channel, std::string* error);
  // The same from an opened reader (an in-memory log).
  void Load(LogReader* reader, const std::string& channel);
  const std::string& LoadError() const { return load_error_; }
  std::int32_t Width() const { return width_; }
  std::int32_t Height() const { return height_; }
  bool Rectified() const { return rectified_; }
  std::size_t NumFrames() const { return frames_.size(); }
  const LogStreamStats& StreamStats() const { return stream_; }
  std::size_t NumImuSamples() const { return imu_.size(); }

  core::Status Start() override;
  core::Status Next(core::TimeNs timeout_ns, StereoPair* pair) override;
  void Release(const StereoPair& /*pair*/) override {}
  void Stop() override {}
  SourceStats Stats() const override { return stats_; }
  const char* Name() const override { return "log"; }
  bool Motion(std::uint64_t seq, MotionInput* input) override;
  bool NextImu(std::int64_t until_utime, estimator::ImuSample<double>* sample) override;

 private:
  struct Frame {
    std::int64_t seq = 0;
    std::int64_t left_ns = 0;
    std::int64_t right_ns = 0;
    std::int32_t dropped_before = 0;
    bool has_motion = false;
    MotionInput motion;
    std::vector<std::uint8_t> left;
    std::vector<std::uint8_t> right;
    std::size_t imu_begin = 0;  // its IMU samples: imu_[imu_begin, imu_end)
    std::size_t imu_end = 0;
  };
  // Appends the frame unless the sequence and time checks refuse it.
  void Admit(Frame frame);
  std::string AddImuRecord(const std::vector<std::uint8_t>& data, const std::string& where);
  std::vector<Frame> frames_;
  LogStreamStats stream_;
  std::string load_error_;
  std::int32_t width_ = 0;
  std::int32_t height_ = 0;
  bool rectified_ = true;
  std::size_t next_ = 0;
  SourceStats stats_;
  std::string imu_channel_;
  std::vector<estimator::ImuSample<double>> imu_;
  std::size_t imu_pending_ = 0;  // first sample not yet given to a frame (loading)
  std::size_t imu_next_ = 0;     // next sample to serve
};

}  // namespace swf::drivers
