#include "euroc_imu.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "input_file.hpp"

namespace swf::eval {
namespace {

std::string Where(const std::string& path, int line) { return path + ":" + std::to_string(line); }

// Splits a csv row into its fields (no quoting in EuRoC files).
std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

// A whole field as a finite double / an integer; surrounding blanks and a '\r' are allowed.
bool ParseDouble(const std::string& text, double* value) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  *value = std::strtod(begin, &end);
  if (end == begin || errno == ERANGE || !std::isfinite(*value)) return false;
  for (; *end != '\0'; ++end)
    if (*end != ' ' && *end != '\t' && *end != '\r') return false;
  return true;
}

bool ParseInt64(const std::string& text, std::int64_t* value) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(begin, &end, 10);
  if (end == begin || errno == ERANGE) return false;
  for (; *end != '\0'; ++end)
    if (*end != ' ' && *end != '\t' && *end != '\r') return false;
  *value = v;
  return true;
}

// "key: value  # comment" -> value (comment and blanks stripped); false if the line is not `key`.
bool ValueOf(const std::string& line, const std::string& key, std::string* value) {
  const std::size_t start = line.find_first_not_of(" \t");
  if (start == std::string::npos || line.compare(start, key.size(), key) != 0) return false;
  std::size_t colon = start + key.size();
  if (colon >= line.size() || line[colon] != ':') return false;
  std::string rest = line.substr(colon + 1);
  const std::size_t hash = rest.find('#');
  if (hash != std::string::npos) rest.resize(hash);
  *value = rest;
  return true;
}

struct ScalarKey {
  const char* key;
  double* target;
  bool non_negative;
  int line = 0;
};

}  // namespace

bool ReadEurocImuCalibration(const std::string& path, EurocImuCalibration* calibration,
                             std::string* error) {
  std::ifstream file;
  if (!OpenInput(path, &file, error)) return false;
  EurocImuCalibration c;
  ScalarKey keys[] = {
      {"gyroscope_noise_density", &c.noise.gyro_noise_density, true},
      {"gyroscope_random_walk", &c.noise.gyro_random_walk, true},
      {"accelerometer_noise_density", &c.noise.accel_noise_density, true},
      {"accelerometer_random_walk", &c.noise.accel_random_walk, true},
      {"rate_hz", &c.rate_hz, true},
  };
  std::string line;
  int number = 0;
  bool in_t_bs = false;
  int t_bs_line = 0;
  std::string t_bs_text;  // the numbers of T_BS.data, possibly over several lines
  bool t_bs_open = false;
  while (std::getline(file, line)) {
    ++number;
    std::string value;
    if (t_bs_open) {
      t_bs_text += " " + line;
      if (line.find(']') != std::string::npos) t_bs_open = false;
      continue;
    }
    if (ValueOf(line, "T_BS", &value)) in_t_bs = true;
    if (in_t_bs && ValueOf(line, "data", &value)) {
      t_bs_line = number;
      t_bs_text = value;
      t_bs_open = value.find(']') == std::string::npos;
      in_t_bs = false;
      continue;
    }
    for (ScalarKey& k : keys) {
      if (!ValueOf(line, k.key, &value)) continue;
      k.line = number;
      if (!ParseDouble(value, k.target) || (k.non_negative && *k.target < 0.0)) {
        *error = Where(path, number) + ": " + k.key + " must be a finite non-negative number";
        return false;
      }
    }
  }
  for (const ScalarKey& k : keys) {
    if (k.line == 0) {
      *error = path + ": no " + std::string(k.key);
      return false;
    }
  }
  if (!(c.rate_hz > 0.0)) {
    *error = path + ": rate_hz must be positive";
    return false;
  }
  if (t_bs_line == 0 || t_bs_open) {
    *error = path + ": no complete T_BS data: [16 numbers]";
    return false;
  }
  const std::size_t open = t_bs_text.find('[');
  const std::size_t close = t_bs_text.find(']');
  std::vector<double> m;
  if (open != std::string::npos && close != std::string::npos && close > open) {
    std::string inside = t_bs_text.substr(open + 1, close - open - 1);
    std::istringstream in(inside);
    std::string field;
    while (std::getline(in, field, ',')) {
      double v = 0.0;
      if (!ParseDouble(field, &v)) {
        m.clear();
        break;
      }
      m.push_back(v);
    }
  }
  if (m.size() != 16) {
    *error = Where(path, t_bs_line) + ": T_BS data must be 16 finite numbers in [ ]";
    return false;
  }
  Eigen::Matrix4d t;
  for (int i = 0; i < 16; ++i) t(i / 4, i % 4) = m[i];
  c.body_T_imu = estimator::Pose<double>::FromMatrix(t);
  if ((c.body_T_imu.R.transpose() * c.body_T_imu.R - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      c.body_T_imu.R.determinant() < 0.0) {
    *error = Where(path, t_bs_line) + ": T_BS rotation is not a rotation";
    return false;
  }
  *calibration = c;
  return true;
}

bool ReadEurocImuSamples(const std::string& path,
                         std::vector<estimator::ImuSample<double>>* samples, std::string* error) {
  std::ifstream file;
  if (!OpenInput(path, &file, error)) return false;
  samples->clear();
  std::string line;
  int number = 0;
  while (std::getline(file, line)) {
    ++number;
    if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos)
      continue;
    const std::vector<std::string> fields = SplitCsv(line);
    estimator::ImuSample<double> s;
    std::int64_t t_ns = 0;
    bool ok = fields.size() == 7 && ParseInt64(fields[0], &t_ns);
    for (int i = 0; ok && i < 3; ++i) ok = ParseDouble(fields[1 + i], &s.gyro_radps(i));
    for (int i = 0; ok && i < 3; ++i) ok = ParseDouble(fields[4 + i], &s.accel_mps2(i));
    if (!ok) {
      *error = Where(path, number) +
               ": expected 7 fields: t_ns, w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s^2], all "
               "finite (got \"" +
               line.substr(0, 120) + "\")";
      return false;
    }
    s.t_us = NsToUs(t_ns);
    s.seq = static_cast<std::int64_t>(samples->size());
    s.flags = estimator::kImuValid;
    samples->push_back(s);
  }
  if (samples->empty()) {
    *error = path + ": no samples";
    return false;
  }
  return true;
}

}  // namespace swf::eval
