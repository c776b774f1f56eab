// Recording and reading LCM logs: a damaged log stops replay at the damaged record, names it,
// and keeps every frame before it.
#include "swf/app/lcm_io.hpp"

#include <gtest/gtest.h>
#include <lcm/eventlog.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "swf/testing/encode.hpp"
#include "swf_msgs/imu_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"

namespace swf::app {
namespace {

std::string TempPath(const char* name) { return std::string(::testing::TempDir()) + "/" + name; }

// Writes `n` 4x2 stereo frames on SWF_STEREO (and a NAV record between them).
void WriteLog(const std::string& path, int n) {
  lcm_eventlog_t* log = lcm_eventlog_create(path.c_str(), "w");
  ASSERT_NE(log, nullptr);
  for (int i = 0; i < n; ++i) {
    swf_msgs::stereo_frame_t f{};
    f.utime = 1000 * i;
    f.left_exposure_utime = f.utime;  // advancing, as the sequence checks require
    f.right_exposure_utime = f.utime;
    f.seq = i;
    f.rectified = true;
    f.has_motion = i > 0;
    f.motion_translation_m[2] = 1.0;
    f.width = 4;
    f.height = 2;
    f.num_bytes = 8;
    f.left.assign(8, static_cast<std::uint8_t>(i));
    f.right.assign(8, static_cast<std::uint8_t>(i + 1));
    std::vector<std::uint8_t> buf(f.getEncodedSize());
    ASSERT_EQ(f.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
    for (const char* channel : {"SWF_STEREO", "SWF_NAV"}) {
      lcm_eventlog_event_t e{};
      e.timestamp = f.utime;
      e.channellen = static_cast<std::int32_t>(std::strlen(channel));
      e.channel = const_cast<char*>(channel);
      e.datalen = static_cast<std::int32_t>(buf.size());
      e.data = buf.data();
      ASSERT_EQ(lcm_eventlog_write_event(log, &e), 0);
    }
  }
  lcm_eventlog_destroy(log);
}

// Byte offset of record k in a log of WriteLog(n): records alternate SWF_STEREO (10-character
// channel) and SWF_NAV (7), each with a 28-byte header and the same payload.
std::size_t RecordOffset(std::size_t total, int n, int k) {
  const std::size_t payload = (total / n - 2 * 28 - 10 - 7) / 2;
  const std::size_t stereo = 28 + 10 + payload;
  const std::size_t nav = 28 + 7 + payload;
  return static_cast<std::size_t>(k / 2) * (stereo + nav) + (k % 2) * stereo;
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
void Spit(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

TEST(LcmIoTest, ReadsEveryRecordOfAGoodLog) {
  const std::string path = TempPath("good.lcmlog");
  WriteLog(path, 5);
  drivers::LogStereoSource source;
  std::string error;
  ASSERT_TRUE(source.Load(path, "SWF_STEREO", &error)) << error;
  EXPECT_TRUE(source.LoadError().empty()) << source.LoadError();
  ASSERT_EQ(source.NumFrames(), 5u);
  ASSERT_EQ(source.Start(), core::Status::kOk);
  drivers::StereoPair pair;
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(source.Next(0, &pair), core::Status::kOk);
    EXPECT_EQ(pair.seq, static_cast<std::uint64_t>(i));
    EXPECT_EQ(pair.left.data[7], i);
    drivers::MotionInput u;
    EXPECT_EQ(source.Motion(pair.seq, &u), i > 0);
    if (i > 0) EXPECT_DOUBLE_EQ(u.translation_m[2], 1.0);
  }
  EXPECT_EQ(source.Next(0, &pair), core::Status::kEmpty);
}

TEST(LcmIoTest, TruncatedLogNamesTheRecordAndKeepsWhatCameBefore) {
  const std::string path = TempPath("truncated.lcmlog");
  WriteLog(path, 5);
  const std::string bytes = Slurp(path);
  // Cut record 6 (the 4th stereo frame) in the middle.
  Spit(path, bytes.substr(0, RecordOffset(bytes.size(), 5, 6) + 40));
  drivers::LogStereoSource source;
  std::string error;
  ASSERT_TRUE(source.Load(path, "SWF_STEREO", &error));
  EXPECT_EQ(source.NumFrames(), 3u);
  EXPECT_NE(source.LoadError().find("record 6"), std::string::npos) << source.LoadError();
  EXPECT_NE(source.LoadError().find("truncated"), std::string::npos) << source.LoadError();
}

TEST(LcmIoTest, CorruptRecordIsNamedNotSkipped) {
  const std::string path = TempPath("corrupt.lcmlog");
  WriteLog(path, 5);
  std::string bytes = Slurp(path);
  // Break the sync word of record 4 (the 3rd stereo frame).
  bytes[RecordOffset(bytes.size(), 5, 4)] = 0x00;
  Spit(path, bytes);
  drivers::LogStereoSource source;
  std::string error;
  ASSERT_TRUE(source.Load(path, "SWF_STEREO", &error));
  EXPECT_EQ(source.NumFrames(), 2u);
  EXPECT_NE(source.LoadError().find("record 4"), std::string::npos) << source.LoadError();
  EXPECT_NE(source.LoadError().find("bad sync word"), std::string::npos);

  // A payload that is not a stereo_frame_t (the fingerprint does not match) is named too.
  WriteLog(path, 3);
  bytes = Slurp(path);
  bytes[RecordOffset(bytes.size(), 3, 2) + 28 + 10 + 3] ^= 0x5A;  // record 2's fingerprint
  Spit(path, bytes);
  drivers::LogStereoSource second;
  ASSERT_TRUE(second.Load(path, "SWF_STEREO", &error));
  EXPECT_EQ(second.NumFrames(), 1u);
  EXPECT_NE(second.LoadError().find("record 2"), std::string::npos) << second.LoadError();
  EXPECT_NE(second.LoadError().find("does not decode"), std::string::npos);
}

TEST(LcmIoTest, MissingLogIsAnError) {
  drivers::LogStereoSource source;
  std::string error;
  EXPECT_FALSE(source.Load("/nonexistent/x.lcmlog", "SWF_STEREO", &error));
  EXPECT_NE(error.find("/nonexistent/x.lcmlog"), std::string::npos);
}

// ---- sequence and time checks, hostile records ----------------------------------------------

struct FrameSpec {
  std::int64_t seq = 0;
  std::int64_t utime = 0;  // exposure time of both images, microseconds
  const char* channel = "SWF_STEREO";
  std::int32_t dropped_before = 0;  // as the recording loop saw it
};

std::vector<std::uint8_t> EncodeFrame(const FrameSpec& spec) {
  swf_msgs::stereo_frame_t f{};
  f.utime = spec.utime;
  f.seq = spec.seq;
  f.dropped_before = spec.dropped_before;
  f.left_exposure_utime = spec.utime;
  f.right_exposure_utime = spec.utime;
  f.rectified = true;
  f.width = 4;
  f.height = 2;
  f.num_bytes = 8;
  f.left.assign(8, static_cast<std::uint8_t>(spec.seq));
  f.right.assign(8, static_cast<std::uint8_t>(spec.seq + 1));
  return swf::testing::Encode(f);
}

void WriteRecords(const std::string& path, const std::vector<FrameSpec>& specs,
                  const std::vector<std::vector<std::uint8_t>>& payloads) {
  lcm_eventlog_t* log = lcm_eventlog_create(path.c_str(), "w");
  ASSERT_NE(log, nullptr);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    lcm_eventlog_event_t e{};
    e.timestamp = specs[i].utime;
    e.channellen = static_cast<std::int32_t>(std::strlen(specs[i].channel));
    e.channel = const_cast<char*>(specs[i].channel);
    e.datalen = static_cast<std::int32_t>(payloads[i].size());
    e.data = const_cast<std::uint8_t*>(payloads[i].data());
    ASSERT_EQ(lcm_eventlog_write_event(log, &e), 0);
  }
  lcm_eventlog_destroy(log);
}

// A log of 4x2 frames with the given sequence numbers, 100 ms apart unless `utimes` says otherwise.
std::string WriteSequence(const char* name, const std::vector<std::int64_t>& seqs,
                          std::vector<std::int64_t> utimes = {}) {
  std::vector<FrameSpec> specs;
  std::vector<std::vector<std::uint8_t>> payloads;
  for (std::size_t i = 0; i < seqs.size(); ++i) {
    FrameSpec spec;
    spec.seq = seqs[i];
    spec.utime = utimes.empty() ? 100000 * (seqs[i] + 1) : utimes[i];
    specs.push_back(spec);
    payloads.push_back(EncodeFrame(spec));
  }
  const std::string path = TempPath(name);
  WriteRecords(path, specs, payloads);
  return path;
}

struct Served {
  std::vector<std::uint64_t> seqs;
  std::vector<std::uint32_t> dropped_before;
  drivers::SourceStats stats;
};

// Loads the log's frames on SWF_STEREO into *source and serves every one.
Served LoadAndServe(const std::string& path, drivers::LogStereoSource* source) {
  Served out;
  std::string error;
  EXPECT_TRUE(source->Load(path, "SWF_STEREO", &error)) << error;
  EXPECT_EQ(source->Start(), core::Status::kOk);
  drivers::StereoPair pair;
  for (std::size_t i = 0; i < 1000 && source->Next(0, &pair) == core::Status::kOk; ++i) {
    out.seqs.push_back(pair.seq);
    out.dropped_before.push_back(pair.dropped_before);
  }
  out.stats = source->Stats();
  return out;
}

// A replayed stream: the sequence numbers (and exposure times) of the frames a log holds, and
// what the log source must serve of them. Frames are never fused out of order: a refused frame
// (a duplicate or one behind in number or time) is one the source rejected.
struct StreamCase {
  const char* name;
  std::vector<std::int64_t> seqs;
  std::vector<std::int64_t> utimes;  // empty: 100 ms apart by sequence number
  std::vector<std::uint64_t> served;
  std::vector<std::uint32_t> dropped_before;
  std::int64_t frames_missing = 0;
  std::int64_t duplicates = 0;
  std::int64_t out_of_order = 0;
};

class ReplayedStreamTest : public ::testing::TestWithParam<StreamCase> {};

TEST_P(ReplayedStreamTest, IsServedInOrderWithWhatIsMissingOrRefusedCounted) {
  const StreamCase& c = GetParam();
  drivers::LogStereoSource source;
  const std::string name = std::string(c.name) + ".lcmlog";
  const Served s = LoadAndServe(WriteSequence(name.c_str(), c.seqs, c.utimes), &source);
  EXPECT_TRUE(source.LoadError().empty()) << source.LoadError();
  EXPECT_EQ(s.seqs, c.served);
  EXPECT_EQ(s.dropped_before, c.dropped_before);
  EXPECT_EQ(source.StreamStats().frames_missing, c.frames_missing);
  EXPECT_EQ(source.StreamStats().duplicates, c.duplicates);
  EXPECT_EQ(source.StreamStats().out_of_order, c.out_of_order);
  EXPECT_EQ(s.stats.frames_rejected, static_cast<std::uint64_t>(c.duplicates + c.out_of_order));
}

INSTANTIATE_TEST_SUITE_P(
    Logs, ReplayedStreamTest,
    ::testing::Values(
        // Frame 2 missing: the gap reaches the flight loop as dropped_before on the next frame
        // and is counted as missing (it replayed as 0 dropped frames).
        StreamCase{"gap", {0, 1, 3, 4}, {}, {0, 1, 3, 4}, {0, 0, 1, 0}, 1, 0, 0},
        // A frame recorded twice: the second copy is refused as a duplicate.
        StreamCase{"duplicate", {0, 1, 1, 2}, {}, {0, 1, 2}, {0, 0, 0}, 0, 1, 0},
        // Frames 1 and 2 swapped: frame 2 is served with one frame missing before it and frame
        // 1, now behind, is refused.
        StreamCase{"swap", {0, 2, 1, 3}, {}, {0, 2, 3}, {0, 1, 0}, 1, 0, 1},
        // Consecutive numbers whose exposure times go back (frames renumbered after a swap): the
        // frame behind in time is refused, and its number is then missing from what was served.
        StreamCase{"time", {0, 1, 2, 3}, {100, 300, 200, 400}, {0, 1, 3}, {0, 0, 1}, 1, 0, 1}),
    [](const ::testing::TestParamInfo<StreamCase>& info) { return std::string(info.param.name); });

// GIVEN a log of a source that numbers its frames across the camera's losses (the simulator): frame
// 3 recorded with dropped_before 1 after frame 1, and frame 9 with dropped_before 2 after frame 4
// WHEN replayed THEN the gap the camera lost is not missing from the log: only frames 5 and 6 are,
// and each pair carries what was lost before it (camera and log), counted once.
TEST(LcmIoTest, AGapTheCameraRecordedAsDroppedIsNotMissingFromTheLog) {
  std::vector<FrameSpec> specs;
  std::vector<std::vector<std::uint8_t>> payloads;
  const std::int64_t seqs[] = {0, 1, 3, 4, 9};
  const std::int32_t dropped[] = {0, 0, 1, 0, 2};
  for (int i = 0; i < 5; ++i) {
    FrameSpec spec;
    spec.seq = seqs[i];
    spec.utime = 100000 * (seqs[i] + 1);
    spec.dropped_before = dropped[i];
    specs.push_back(spec);
    payloads.push_back(EncodeFrame(spec));
  }
  const std::string path = TempPath("camera_gap.lcmlog");
  WriteRecords(path, specs, payloads);
  drivers::LogStereoSource source;
  const Served s = LoadAndServe(path, &source);
  EXPECT_EQ(s.seqs, (std::vector<std::uint64_t>{0, 1, 3, 4, 9}));
  EXPECT_EQ(s.dropped_before, (std::vector<std::uint32_t>{0, 0, 1, 0, 4}));
  EXPECT_EQ(source.StreamStats().frames_missing, 2);
}

// GIVEN a frame on a misspelled channel WHEN replayed THEN it is not silently skipped: the hole
// it leaves in the sequence is counted.
TEST(LcmIoTest, AFrameOnAMisnamedChannelLeavesACountedGap) {
  std::vector<FrameSpec> specs(3);
  std::vector<std::vector<std::uint8_t>> payloads;
  for (int i = 0; i < 3; ++i) {
    specs[i].seq = i;
    specs[i].utime = 1000 * (i + 1);
  }
  specs[1].channel = "SWF_STEREOO";
  for (const FrameSpec& spec : specs) payloads.push_back(EncodeFrame(spec));
  const std::string path = TempPath("misnamed.lcmlog");
  WriteRecords(path, specs, payloads);
  drivers::LogStereoSource source;
  std::string error;
  ASSERT_TRUE(source.Load(path, "SWF_STEREO", &error));
  EXPECT_EQ(source.NumFrames(), 2u);
  EXPECT_EQ(source.StreamStats().frames_missing, 1);
}

// Overwrites the big-endian int32 / int64 at `offset` of a payload.
void PutBe(std::vector<std::uint8_t>* bytes, std::size_t offset, std::uint64_t value, int width) {
  for (int i = 0; i < width; ++i) {
    (*bytes)[offset + i] = static_cast<std::uint8_t>(value >> (8 * (width - 1 - i)));
  }
}

// Loads a log of three frames whose second payload `corrupt` altered; returns the load error.
template <typename Corrupt>
std::string LoadWithCorruptSecondFrame(const char* name, Corrupt corrupt, std::size_t* frames) {
  std::vector<FrameSpec> specs(3);
  std::vector<std::vector<std::uint8_t>> payloads;
  for (int i = 0; i < 3; ++i) {
    specs[i].seq = i;
    specs[i].utime = 1000 * (i + 1);
    payloads.push_back(EncodeFrame(specs[i]));
  }
  corrupt(&payloads[1]);
  const std::string path = TempPath(name);
  WriteRecords(path, specs, payloads);
  drivers::LogStereoSource source;
  std::string error;
  EXPECT_TRUE(source.Load(path, "SWF_STEREO", &error));
  *frames = source.NumFrames();
  return source.LoadError();
}

// Payload offsets (stereo_frame_t after its 8-byte fingerprint; messages/stereo_frame_t.lcm).
constexpr std::size_t kLeftExposure = 8 + 16;
constexpr std::size_t kWidth = 8 + 86;
constexpr std::size_t kNumBytes = kWidth + 8;

// GIVEN length fields and times a flipped bit or a hostile writer makes (each aborted swf-replay
// with std::length_error, or overflowed) WHEN the log is loaded THEN loading stops at that
// record with an error naming the record and the field, keeping the frame before it.
TEST(LcmIoTest, HostileFieldsStopTheLoadNamingRecordAndField) {
  std::size_t frames = 0;
  std::string e = LoadWithCorruptSecondFrame(
      "neg.lcmlog", [](auto* p) { PutBe(p, kNumBytes, 0xffffffffu, 4); }, &frames);
  EXPECT_EQ(frames, 1u);
  EXPECT_NE(e.find("record 1 (SWF_STEREO"), std::string::npos) << e;
  EXPECT_NE(e.find("num_bytes -1: bad length"), std::string::npos) << e;
  e = LoadWithCorruptSecondFrame(
      "huge.lcmlog", [](auto* p) { PutBe(p, kNumBytes, 0x7fffffffu, 4); }, &frames);
  EXPECT_NE(e.find("num_bytes 2147483647: over the stated limit"), std::string::npos) << e;
  e = LoadWithCorruptSecondFrame(
      "square.lcmlog",
      [](auto* p) {
        PutBe(p, kWidth, 65537, 4);
        PutBe(p, kWidth + 4, 65537, 4);
      },
      &frames);
  EXPECT_NE(e.find("width 65537: over the stated limit"), std::string::npos) << e;
  e = LoadWithCorruptSecondFrame(
      "time.lcmlog", [](auto* p) { PutBe(p, kLeftExposure, 0x7fffffffffffffffu, 8); }, &frames);
  EXPECT_EQ(frames, 1u);
  EXPECT_NE(e.find("exposure time 9223372036854775807 us out of range"), std::string::npos) << e;
  e = LoadWithCorruptSecondFrame(
      "zero.lcmlog",
      [](auto* p) {
        PutBe(p, kWidth, 0, 4);
        PutBe(p, kNumBytes, 0, 4);
        p->resize(p->size() - 16);
      },
      &frames);
  EXPECT_NE(e.find("empty image"), std::string::npos) << e;
}

// GIVEN a record header whose data length is negative or larger than any message WHEN read THEN
// the reader refuses it before allocating, naming the record.
std::vector<std::uint8_t> EncodeImu(std::int64_t seq, std::int64_t utime) {
  swf_msgs::imu_t m{};
  m.utime = utime;
  m.seq = seq;
  m.angular_rate_radps[2] = 0.01 * static_cast<double>(seq);
  m.specific_force_mps2[2] = 9.81;
  m.flags = swf_msgs::imu_t::FLAG_VALID;
  return swf::testing::Encode(m);
}

// Writes the records into the log `name` and loads its frames (SWF_STEREO) and IMU samples
// (SWF_IMU) into *source; the log opens, so what went wrong in it is source->LoadError().
void LoadWithImu(const char* name, const std::vector<FrameSpec>& specs,
                 const std::vector<std::vector<std::uint8_t>>& payloads,
                 drivers::LogStereoSource* source) {
  const std::string path = TempPath(name);
  WriteRecords(path, specs, payloads);
  source->SetImuChannel("SWF_IMU");
  std::string error;
  ASSERT_TRUE(source->Load(path, "SWF_STEREO", &error)) << error;
}

// GIVEN a log with IMU samples recorded between the frames WHEN replayed THEN each frame serves
// exactly the samples recorded before it (after the previous one), in their order, whatever
// their stamps; samples after the last frame are never served.
TEST(LcmIoTest, ReplayServesTheImuSamplesRecordedBeforeEachFrame) {
  std::vector<FrameSpec> specs;
  std::vector<std::vector<std::uint8_t>> payloads;
  std::int64_t imu_seq = 0;
  const auto imu = [&](int n) {
    for (int i = 0; i < n; ++i, ++imu_seq) {
      specs.push_back(FrameSpec{imu_seq, 1000 * imu_seq, "SWF_IMU"});
      payloads.push_back(EncodeImu(imu_seq, 1000 * imu_seq));
    }
  };
  const auto frame = [&](std::int64_t seq) {
    specs.push_back(FrameSpec{seq, 100000 * (seq + 1)});
    payloads.push_back(EncodeFrame(specs.back()));
  };
  imu(2);
  frame(0);
  imu(3);
  frame(1);
  frame(2);
  imu(1);
  drivers::LogStereoSource source;
  ASSERT_NO_FATAL_FAILURE(LoadWithImu("imu.lcmlog", specs, payloads, &source));
  EXPECT_EQ(source.LoadError(), "");
  EXPECT_EQ(source.NumImuSamples(), 6u);
  ASSERT_EQ(source.Start(), core::Status::kOk);
  estimator::ImuSample<double> s;
  EXPECT_FALSE(source.NextImu(0, &s));  // no frame served yet
  std::vector<std::vector<std::int64_t>> served;
  drivers::StereoPair pair;
  while (source.Next(0, &pair) == core::Status::kOk) {
    served.emplace_back();
    while (source.NextImu(0, &s)) served.back().push_back(s.seq);
  }
  ASSERT_EQ(served.size(), 3u);
  EXPECT_EQ(served[0], (std::vector<std::int64_t>{0, 1}));
  EXPECT_EQ(served[1], (std::vector<std::int64_t>{2, 3, 4}));
  EXPECT_TRUE(served[2].empty());
}

// GIVEN an IMU record that does not decode WHEN loaded THEN the load stops there, naming the
// record and the type; the frames before it replay.
TEST(LcmIoTest, AnUndecodableImuRecordStopsTheLoadNamingIt) {
  std::vector<FrameSpec> specs{{0, 100000}, {0, 150000, "SWF_IMU"}, {1, 200000}};
  std::vector<std::vector<std::uint8_t>> payloads{EncodeFrame(specs[0]), EncodeImu(0, 150000),
                                                  EncodeFrame(specs[2])};
  payloads[1].resize(payloads[1].size() / 2);  // truncated message
  drivers::LogStereoSource source;
  ASSERT_NO_FATAL_FAILURE(LoadWithImu("bad_imu.lcmlog", specs, payloads, &source));
  EXPECT_NE(source.LoadError().find("record 1 (SWF_IMU"), std::string::npos) << source.LoadError();
  EXPECT_NE(source.LoadError().find("imu_t does not decode"), std::string::npos);
  EXPECT_EQ(source.NumFrames(), 1u);
}

TEST(LcmIoTest, RecordLengthsAreCheckedBeforeAllocating) {
  const std::string path = WriteSequence("len.lcmlog", {0, 1});
  const std::string bytes = Slurp(path);
  const std::size_t second = bytes.size() / 2;  // two records of the same size
  for (const std::uint32_t len : {0xffffffffu, 0x7fffffffu}) {
    std::string bad = bytes;
    for (int i = 0; i < 4; ++i) bad[second + 24 + i] = static_cast<char>(len >> (24 - 8 * i));
    drivers::LogReader reader;
    reader.OpenBytes(bad, "mem.lcmlog");
    drivers::LogStereoSource source;
    source.Load(&reader, "SWF_STEREO");
    EXPECT_EQ(source.NumFrames(), 1u);
    EXPECT_NE(source.LoadError().find("mem.lcmlog: record 1 at byte"), std::string::npos)
        << source.LoadError();
    EXPECT_NE(
        source.LoadError().find(len == 0xffffffffu ? "bad data length -1" : "over the largest"),
        std::string::npos)
        << source.LoadError();
  }
}

TEST(LcmIoTest, ADirectoryIsNotALog) {
  drivers::LogStereoSource source;
  std::string error;
  EXPECT_FALSE(source.Load(::testing::TempDir(), "SWF_STEREO", &error));
  EXPECT_NE(error.find("cannot open the log"), std::string::npos) << error;
}

}  // namespace
}  // namespace swf::app
