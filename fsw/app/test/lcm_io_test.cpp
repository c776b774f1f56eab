// Recording and reading LCM logs: a damaged log stops replay at the damaged record, names it,
// and keeps every frame before it.
#include "swf/app/lcm_io.hpp"

#include <gtest/gtest.h>
#include <lcm/eventlog.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

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
  LogStereoSource source;
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
    MotionInput u;
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
  LogStereoSource source;
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
  LogStereoSource source;
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
  LogStereoSource second;
  ASSERT_TRUE(second.Load(path, "SWF_STEREO", &error));
  EXPECT_EQ(second.NumFrames(), 1u);
  EXPECT_NE(second.LoadError().find("record 2"), std::string::npos) << second.LoadError();
  EXPECT_NE(second.LoadError().find("does not decode"), std::string::npos);
}

TEST(LcmIoTest, MissingLogIsAnError) {
  LogStereoSource source;
  std::string error;
  EXPECT_FALSE(source.Load("/nonexistent/x.lcmlog", "SWF_STEREO", &error));
  EXPECT_NE(error.find("/nonexistent/x.lcmlog"), std::string::npos);
}

}  // namespace
}  // namespace swf::app
