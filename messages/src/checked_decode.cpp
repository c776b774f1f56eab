#include "swf/messages/checked_decode.hpp"

#include <algorithm>
#include <cstdio>
#include <vector>

namespace swf::messages {
namespace {

// Byte counts of the fixed fields between the fingerprint and each message's first length field,
// and after its arrays, in schema order (messages/*.lcm). messages_test holds them against the
// generated encoder: a schema change that moves a field fails there.
// stereo_frame_t: utime, seq, left/right_exposure_utime (4 x 8), dropped_before (4), rectified,
// has_motion (1 + 1), motion_translation_m, motion_rotation_rad (6 x 8); then width, height,
// num_bytes (3 x 4).
constexpr std::size_t kStereoPrefixBytes = 32 + 4 + 2 + 48;
// landmark_map_t: utime, seq, frame_seq (3 x 8); then num_landmarks. Per landmark: id (8),
// position (3 x 8), covariance (6 x 8), num_observations (4).
constexpr std::size_t kLandmarkPrefixBytes = 24;
constexpr std::int64_t kBytesPerLandmark = 8 + 24 + 48 + 4;
// feature_set_t: utime, seq, frame_seq (3 x 8); then num_features. Per feature: id (8), u_px,
// v_px (2 x 4), status (1).
constexpr std::size_t kFeaturePrefixBytes = 24;
constexpr std::int64_t kBytesPerFeature = 8 + 4 + 4 + 1;
// hazard_map_t: utime, seq, frame_seq (3 x 8), origin_world_m (2 x 8), up_world (3 x 8),
// cell_size_m (8); then rows, cols, num_cells (3 x 4). Per cell: five floats and a class (21).
// After the cells: safe_site_valid (1), safe_site_world_m (2 x 8), safe_site_score (8),
// outliers_rejected, cells_replaced (2 x 8).
constexpr std::size_t kHazardPrefixBytes = 24 + 16 + 24 + 8;
constexpr std::int64_t kBytesPerCell = 5 * 4 + 1;
constexpr std::int64_t kHazardSuffixBytes = 1 + 16 + 8 + 16;
// hazard_truth_t: utime, frame_seq (2 x 8), origin_world_m (2 x 8), cell_size_m (8); then rows,
// cols, num_cells (3 x 4). Per cell: elevation (8), slope (4) and rock_free (1). After the cells:
// max_rock_height_m, footprint_radius_m (2 x 8), then num_rocks. Per rock: centre (2 x 8),
// diameter, height (2 x 8). Last: site_valid (1), site_world_m (2 x 8), site_clearance_m,
// site_search_m (2 x 8).
constexpr std::size_t kHazardTruthPrefixBytes = 16 + 16 + 8;
constexpr std::int64_t kBytesPerTruthCell = 8 + 4 + 1;
constexpr std::int64_t kHazardTruthCriteriaBytes = 2 * 8;
constexpr std::int64_t kBytesPerTruthRock = 16 + 16;
constexpr std::int64_t kHazardTruthSuffixBytes = 1 + 16 + 16;
// health_t: utime .. allocations_after_start (8 x 8), fault_bits (4), estimator_status (1),
// num_features, num_landmarks (2 x 4), frames_valid .. restarts (4 x 8), last_recovery_frames (4),
// measurements_gated .. gate_suspensions (5 x 8); then num_integrity_flags.
constexpr std::size_t kHealthPrefixBytes = 64 + 4 + 1 + 8 + 32 + 4 + 40;
// After the stage times: imu_accepted .. imu_intervals_bridged (7 x 8), camera_missing_packets ..
// camera_timeouts (3 x 8).
constexpr std::int64_t kHealthSuffixBytes = 7 * 8 + 3 * 8;

// Reads big-endian integers from a byte span; every read is bounds-checked.
class WireReader {
 public:
  WireReader(const void* data, std::size_t size)
      : data_(static_cast<const std::uint8_t*>(data)), size_(size) {}
  std::size_t Remaining() const { return size_ - pos_; }
  bool Skip(std::uint64_t n) {
    if (n > Remaining()) return false;
    pos_ += static_cast<std::size_t>(n);
    return true;
  }
  bool ReadInt32(std::int32_t* v) {
    if (Remaining() < 4) return false;
    const std::uint8_t* p = data_ + pos_;
    const std::uint32_t u = (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
                            (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
    *v = static_cast<std::int32_t>(u);
    pos_ += 4;
    return true;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

DecodeError Error(DecodeResult result, const char* field, std::int64_t value) {
  return DecodeError{result, field, value};
}

// A count read from the wire: present, non-negative and within `limit`.
DecodeError ReadCount(WireReader* r, const char* field, std::int32_t limit, std::int32_t* count) {
  if (!r->ReadInt32(count)) return Error(DecodeResult::kTruncated, field, 0);
  if (*count < 0) return Error(DecodeResult::kBadLength, field, *count);
  if (*count > limit) return Error(DecodeResult::kOverLimit, field, *count);
  return {};
}

// The bytes after the last length field: exactly `need` of them.
DecodeError ExpectRemaining(const WireReader& r, const char* field, std::int64_t need) {
  const auto have = static_cast<std::int64_t>(r.Remaining());
  if (have < need) return Error(DecodeResult::kTruncated, field, have);
  if (have > need) return Error(DecodeResult::kTrailingBytes, "message", have - need);
  return {};
}

// Size and fingerprint, common to every type.
template <typename Msg>
DecodeError CheckHeader(WireReader* r, std::size_t size) {
  if (size > static_cast<std::uint64_t>(kMaxEncodedBytes)) {
    return Error(DecodeResult::kOverLimit, "message", static_cast<std::int64_t>(size));
  }
  std::int32_t high = 0;
  std::int32_t low = 0;
  if (!r->ReadInt32(&high) || !r->ReadInt32(&low)) {
    return Error(DecodeResult::kTruncated, "fingerprint", static_cast<std::int64_t>(size));
  }
  const std::uint64_t hash =
      (std::uint64_t{static_cast<std::uint32_t>(high)} << 32) | static_cast<std::uint32_t>(low);
  if (hash != static_cast<std::uint64_t>(Msg::getHash())) {
    return Error(DecodeResult::kWrongType, "fingerprint", static_cast<std::int64_t>(hash));
  }
  return {};
}

// The shape has been checked: the generated decoder now allocates only what the bytes hold.
template <typename Msg>
DecodeError Fill(const void* data, std::size_t size, Msg* msg) {
  const int n = msg->decode(data, 0, static_cast<int>(size));
  if (n < 0) return Error(DecodeResult::kTruncated, "message", static_cast<std::int64_t>(size));
  if (static_cast<std::size_t>(n) != size) {
    return Error(DecodeResult::kTrailingBytes, "message", static_cast<std::int64_t>(size) - n);
  }
  return {};
}

DecodeError CheckStereoShape(WireReader* r, std::int32_t max_width, std::int32_t max_height) {
  if (!r->Skip(kStereoPrefixBytes)) return Error(DecodeResult::kTruncated, "width", 0);
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::int32_t num_bytes = 0;
  DecodeError e = ReadCount(r, "width", std::min(max_width, kMaxImageSidePx), &width);
  if (e.Ok()) e = ReadCount(r, "height", std::min(max_height, kMaxImageSidePx), &height);
  if (e.Ok()) e = ReadCount(r, "num_bytes", kMaxImageBytes, &num_bytes);
  if (!e.Ok()) return e;
  if (std::int64_t{width} * height != num_bytes) {
    return Error(DecodeResult::kBadLength, "num_bytes", num_bytes);  // != width * height
  }
  return ExpectRemaining(*r, "left/right", 2 * std::int64_t{num_bytes});
}

// A message of fixed fields, one count and an array of fixed-size records after it.
DecodeError CheckCountedArrayShape(WireReader* r, std::size_t prefix_bytes, const char* count_field,
                                   std::int32_t limit, const char* array_field,
                                   std::int64_t bytes_per_record) {
  if (!r->Skip(prefix_bytes)) return Error(DecodeResult::kTruncated, count_field, 0);
  std::int32_t n = 0;
  const DecodeError e = ReadCount(r, count_field, limit, &n);
  if (!e.Ok()) return e;
  return ExpectRemaining(*r, array_field, bytes_per_record * n);
}

DecodeError CheckFeatureShape(WireReader* r) {
  return CheckCountedArrayShape(r, kFeaturePrefixBytes, "num_features", kMaxFeatures, "features",
                                kBytesPerFeature);
}

DecodeError CheckLandmarkShape(WireReader* r) {
  return CheckCountedArrayShape(r, kLandmarkPrefixBytes, "num_landmarks", kMaxMapLandmarks,
                                "landmarks", kBytesPerLandmark);
}

// rows, cols and num_cells of a grid: each within its limit, num_cells = rows * cols.
DecodeError ReadGridCells(WireReader* r, std::int32_t* cells) {
  std::int32_t rows = 0;
  std::int32_t cols = 0;
  DecodeError e = ReadCount(r, "rows", kMaxHazardSideCells, &rows);
  if (e.Ok()) e = ReadCount(r, "cols", kMaxHazardSideCells, &cols);
  if (e.Ok()) e = ReadCount(r, "num_cells", kMaxHazardCells, cells);
  if (!e.Ok()) return e;
  if (std::int64_t{rows} * cols != *cells) {
    return Error(DecodeResult::kBadLength, "num_cells", *cells);  // != rows * cols
  }
  return {};
}

DecodeError CheckHazardShape(WireReader* r) {
  if (!r->Skip(kHazardPrefixBytes)) return Error(DecodeResult::kTruncated, "rows", 0);
  std::int32_t cells = 0;
  const DecodeError e = ReadGridCells(r, &cells);
  if (!e.Ok()) return e;
  return ExpectRemaining(*r, "cells", kBytesPerCell * cells + kHazardSuffixBytes);
}

DecodeError CheckHazardTruthShape(WireReader* r) {
  if (!r->Skip(kHazardTruthPrefixBytes)) return Error(DecodeResult::kTruncated, "rows", 0);
  std::int32_t cells = 0;
  DecodeError e = ReadGridCells(r, &cells);
  if (!e.Ok()) return e;
  if (!r->Skip(
          static_cast<std::uint64_t>(kBytesPerTruthCell * cells + kHazardTruthCriteriaBytes))) {
    return Error(DecodeResult::kTruncated, "cells", cells);
  }
  std::int32_t rocks = 0;
  e = ReadCount(r, "num_rocks", kMaxTruthRocks, &rocks);
  if (!e.Ok()) return e;
  return ExpectRemaining(*r, "rocks", kBytesPerTruthRock * rocks + kHazardTruthSuffixBytes);
}

DecodeError CheckHealthShape(WireReader* r) {
  if (!r->Skip(kHealthPrefixBytes)) {
    return Error(DecodeResult::kTruncated, "num_integrity_flags", 0);
  }
  std::int32_t flags = 0;
  DecodeError e = ReadCount(r, "num_integrity_flags", kMaxIntegrityFlags, &flags);
  if (!e.Ok()) return e;
  if (!r->Skip(8 * static_cast<std::uint64_t>(flags))) {
    return Error(DecodeResult::kTruncated, "integrity_flag_counts", flags);
  }
  std::int32_t stages = 0;
  e = ReadCount(r, "num_stages", kMaxStages, &stages);
  if (!e.Ok()) return e;
  for (std::int32_t i = 0; i < stages; ++i) {
    std::int32_t bytes = 0;  // the string's length with its NUL: at least 1
    e = ReadCount(r, "stage_name", kMaxStageNameBytes, &bytes);
    if (!e.Ok()) return e;
    if (bytes == 0) return Error(DecodeResult::kBadLength, "stage_name", bytes);
    if (!r->Skip(static_cast<std::uint64_t>(bytes))) {
      return Error(DecodeResult::kTruncated, "stage_name", bytes);
    }
  }
  return ExpectRemaining(*r, "stage times and IMU counts",
                         3 * 4 * std::int64_t{stages} + kHealthSuffixBytes);
}

// Every value of an enumerated int8 field within [first, last]; the first that is not, named.
DecodeError CheckEnum(const std::vector<std::int8_t>& values, std::int8_t first, std::int8_t last,
                      const char* field) {
  for (const std::int8_t v : values) {
    if (v < first || v > last) return Error(DecodeResult::kBadValue, field, v);
  }
  return DecodeError{};
}

template <typename Msg, typename Shape>
DecodeError Decode(const void* data, std::size_t size, Msg* msg, Shape check_shape) {
  WireReader r(data, size);
  DecodeError e = CheckHeader<Msg>(&r, size);
  if (e.Ok()) e = check_shape(&r);
  if (e.Ok()) e = Fill(data, size, msg);
  return e;
}

}  // namespace

const char* ToString(DecodeResult result) {
  switch (result) {
    case DecodeResult::kOk: return "ok";
    case DecodeResult::kTruncated: return "truncated";
    case DecodeResult::kWrongType: return "wrong type (fingerprint)";
    case DecodeResult::kBadLength: return "bad length";
    case DecodeResult::kOverLimit: return "over the stated limit";
    case DecodeResult::kTrailingBytes: return "trailing bytes";
    case DecodeResult::kBadValue: return "value out of range";
  }
  return "unknown";
}

void Describe(const DecodeError& error, char* out, std::size_t size) {
  if (size == 0) return;
  std::snprintf(out, size, "%s %lld: %s", error.field, static_cast<long long>(error.value),
                ToString(error.result));
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::stereo_frame_t* msg) {
  return Decode(data, size, msg, [](WireReader* r) {
    return CheckStereoShape(r, kMaxImageSidePx, kMaxImageSidePx);
  });
}

DecodeError CheckedDecode(const void* data, std::size_t size, std::int32_t max_width,
                          std::int32_t max_height, swf_msgs::stereo_frame_t* msg) {
  return Decode(data, size, msg, [max_width, max_height](WireReader* r) {
    return CheckStereoShape(r, max_width, max_height);
  });
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::nav_state_t* msg) {
  // Fixed size: nothing to allocate, the generated decoder checks every read.
  return Decode(data, size, msg, [](WireReader*) { return DecodeError{}; });
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::truth_state_t* msg) {
  return Decode(data, size, msg, [](WireReader*) { return DecodeError{}; });
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::landmark_map_t* msg) {
  return Decode(data, size, msg, CheckLandmarkShape);
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::feature_set_t* msg) {
  const DecodeError e = Decode(data, size, msg, CheckFeatureShape);
  if (!e.Ok()) return e;
  return CheckEnum(msg->status, swf_msgs::feature_set_t::STATUS_TRACKED,
                   swf_msgs::feature_set_t::STATUS_GATED, "status");
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::hazard_map_t* msg) {
  const DecodeError e = Decode(data, size, msg, CheckHazardShape);
  if (!e.Ok()) return e;
  return CheckEnum(msg->hazard_class, swf_msgs::hazard_map_t::CLASS_UNKNOWN,
                   swf_msgs::hazard_map_t::CLASS_UNCERTAIN, "hazard_class");
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::hazard_truth_t* msg) {
  const DecodeError e = Decode(data, size, msg, CheckHazardTruthShape);
  if (!e.Ok()) return e;
  return CheckEnum(msg->rock_free, 0, 1, "rock_free");
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::health_t* msg) {
  return Decode(data, size, msg, CheckHealthShape);
}

DecodeError CheckedDecode(const void* data, std::size_t size, swf_msgs::imu_t* msg) {
  // Fixed size: nothing to allocate, the generated decoder checks every read.
  DecodeError e = Decode(data, size, msg, [](WireReader*) { return DecodeError{}; });
  if (!e.Ok()) return e;
  if ((msg->flags & ~kImuKnownFlags) != 0)
    return Error(DecodeResult::kBadValue, "flags", msg->flags);
  return e;
}

}  // namespace swf::messages
