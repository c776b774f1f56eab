// Shared pieces of the calibration importers: file reading, message formatting and the per-format
// readers calibration_import.cpp dispatches to.
#pragma once

#include <string>
#include <vector>

#include "swf/calibration/calibration_import.hpp"

namespace swf::calibration::internal {

// Largest calibration file read: a camchain or CAHVORE model is a few kilobytes.
inline constexpr std::size_t kMaxFileBytes = std::size_t{1} << 20;

// The whole file, refused when missing, larger than kMaxFileBytes or holding a NUL byte.
bool ReadText(const std::string& path, std::string* text, std::string* error);

// "path:line: key: what" (line 1-based; 0 = no line).
std::string Message(const std::string& path, int line, const std::string& key,
                    const std::string& what);

// A rotation matrix check: orthonormal within 1e-3 and right-handed.
bool IsRotation(const Eigen::Matrix3d& r);

// The YAML formats; each fills *calibration or sets *error.
bool ReadEurocPair(const std::string& left, const std::string& right, StereoCalibration* out,
                   std::string* error);
bool ReadRosPair(const std::string& left, const std::string& right, StereoCalibration* out,
                 std::string* error);
bool ReadKalibr(const std::string& path, StereoCalibration* out, std::string* error);
bool ReadOpenCv(const std::string& path, const ImportOptions& options, StereoCalibration* out,
                std::string* error);
// What a YAML file looks like: "kalibr", "ros", "euroc", "opencv" or "" (unknown; when the
// file is not valid YAML, *parse_error says where).
std::string YamlKind(const std::string& path, std::string* parse_error);

// The text formats.
bool ReadKitti(const std::string& path, const ImportOptions& options, StereoCalibration* out,
               std::string* error);
bool ReadCahvorPair(const std::string& left, const std::string& right, const ImportOptions& options,
                    StereoCalibration* out, std::string* error);
bool LooksLikeKitti(const std::string& text);
bool LooksLikeCahvor(const std::string& text);

}  // namespace swf::calibration::internal
