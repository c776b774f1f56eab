// Checked decoding of the LCM messages: the one way any program of this project decodes bytes that
// came from outside (the bus, a log). lcm-gen's decode() sizes its vectors from the message's own
// length fields before it knows the bytes are there: a negative count throws std::length_error
// (or aborts without exceptions), a huge one allocates gigabytes first. CheckedDecode walks the
// wire format once, checks every length field against the bytes present and against the type's
// stated limit below, and only then lets the generated decode() fill the message. It never throws
// for any input; the only allocations are the message's own vectors, each at most its limit.
//
// Wire format (LCM): an 8-byte fingerprint, then the fields in schema order, big-endian; a
// variable array is its elements back to back after the field that counts them; a string is an
// int32 length (with its NUL) and the bytes.
#pragma once

#include <cstddef>
#include <cstdint>

#include "swf_msgs/feature_set_t.hpp"
#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/hazard_truth_t.hpp"
#include "swf_msgs/health_t.hpp"
#include "swf_msgs/imu_t.hpp"
#include "swf_msgs/landmark_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

namespace swf::messages {

// Stated limits. Each is far above what the flight software produces (images up to 1408 x 1152,
// 1024 landmarks, 256 x 256 hazard cells, 20 integrity flags, 8 stages) and far below what would
// exhaust memory on the flight computer.
inline constexpr std::int32_t kMaxImageSidePx = 4096;                              // width, height
inline constexpr std::int32_t kMaxImageBytes = kMaxImageSidePx * kMaxImageSidePx;  // per image
inline constexpr std::int32_t kMaxMapLandmarks = 65536;
inline constexpr std::int32_t kMaxFeatures = 65536;        // feature_set_t (a display message)
inline constexpr std::int32_t kMaxHazardSideCells = 1024;  // rows, cols
inline constexpr std::int32_t kMaxHazardCells = kMaxHazardSideCells * kMaxHazardSideCells;
inline constexpr std::int32_t kMaxTruthRocks = 65536;   // hazard_truth_t (a ground message)
inline constexpr std::int32_t kMaxIntegrityFlags = 32;  // one per bit of an int32
inline constexpr std::int32_t kMaxStages = 32;
inline constexpr std::int32_t kMaxStageNameBytes = 64;  // with the terminating NUL
// imu_t.flags: only the schema's bits (FLAG_VALID | FLAG_GYRO_SATURATED | FLAG_ACCEL_SATURATED).
inline constexpr std::int32_t kImuKnownFlags = std::int32_t{swf_msgs::imu_t::FLAG_VALID} |
                                               std::int32_t{swf_msgs::imu_t::FLAG_GYRO_SATURATED} |
                                               std::int32_t{swf_msgs::imu_t::FLAG_ACCEL_SATURATED};
// The longest encoded message of any type (a stereo frame of two kMaxImageBytes images and its
// fixed fields): a bus message or log record longer than this is refused before it is read.
inline constexpr std::int64_t kMaxEncodedBytes = 2 * std::int64_t{kMaxImageBytes} + 4096;

enum class DecodeResult : std::uint8_t {
  kOk = 0,
  kTruncated,      // the bytes end before the message does
  kWrongType,      // the fingerprint is another type's (or the bytes are not a message)
  kBadLength,      // a length field is negative or disagrees with the fields it derives from
  kOverLimit,      // a length field (or the whole message) exceeds the stated limit
  kTrailingBytes,  // bytes are left after the message
  kBadValue,       // a field is outside its schema's range (e.g. an unknown hazard class)
};
const char* ToString(DecodeResult result);

// What was wrong, naming the field: "num_bytes -1: negative length" (see Describe).
struct DecodeError {
  DecodeResult result = DecodeResult::kOk;
  const char* field = "";  // the schema's field name ("message" for the whole buffer)
  std::int64_t value = 0;  // the offending value (a length, an offset, a class)
  bool Ok() const { return result == DecodeResult::kOk; }
};

// Writes a one-line description of `error` into `out` (NUL-terminated, at most `size` bytes).
void Describe(const DecodeError& error, char* out, std::size_t size);

// Decodes `size` bytes at `data` into *msg. Anything but kOk leaves *msg unspecified (but valid to
// destroy or reuse). Exactly one message must fill the bytes.
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::stereo_frame_t* msg);
// The same within a receiver's own, tighter image limits (a live subscriber whose buffers are sized
// to its camera): a frame wider than max_width or taller than max_height px is kOverLimit ("width"
// / "height") before anything is filled, so decoding into a message whose left/right vectors are
// reserved to max_width x max_height bytes never allocates. Limits above kMaxImageSidePx are
// kMaxImageSidePx.
DecodeError CheckedDecode(const void* data, std::size_t size, std::int32_t max_width,
                          std::int32_t max_height, swf_msgs::stereo_frame_t* msg);
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::nav_state_t* msg);
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::landmark_map_t* msg);
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::hazard_map_t* msg);
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::hazard_truth_t* msg);
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::health_t* msg);
// Fixed size; refuses flags outside kImuKnownFlags (kBadValue, "flags"). Times, sequence numbers
// and non-finite values are the stream checker's to judge (estimator/imu_stream.hpp), not the
// decoder's: they are counted there.
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::imu_t* msg);
// Refuses a status outside the schema's STATUS_* (kBadValue, "status").
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::feature_set_t* msg);
// Fixed size (truth channels: a simulator's or a test range's).
DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::truth_state_t* msg);

}  // namespace swf::messages
