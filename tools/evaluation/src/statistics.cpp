#include "swf/evaluation/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "swf/core/median.hpp"

namespace swf::evaluation {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double Median(std::vector<double> values) {
  return core::MedianInPlace(values.data(), values.size());
}

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return kNaN;
  const std::size_t k = std::min(values.size() - 1, static_cast<std::size_t>(q * values.size()));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

double Mean(const std::vector<double>& values) {
  if (values.empty()) return kNaN;
  double sum = 0.0;
  for (const double x : values) sum += x;
  return sum / values.size();
}

double Rms(const std::vector<double>& values) {
  if (values.empty()) return kNaN;
  double sum = 0.0;
  for (const double x : values) sum += x * x;
  return std::sqrt(sum / values.size());
}

double SampleStd(const std::vector<double>& values) {
  if (values.size() < 2) return 0.0;
  const double mean = Mean(values);
  double sum = 0.0;
  for (const double x : values) sum += (x - mean) * (x - mean);
  return std::sqrt(sum / (values.size() - 1));
}

}  // namespace swf::evaluation
