#include "swf/core/median.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace swf::core {
namespace {

// The definition: sort, then the middle value or the mean of the two middle values.
double SortedMedian(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

TEST(Median, OddAndEvenCounts) {
  std::vector<double> odd = {5.0, -1.0, 3.0};
  EXPECT_EQ(MedianInPlace(odd.data(), odd.size()), 3.0);
  std::vector<double> even = {4.0, 1.0, 10.0, 2.0};
  EXPECT_EQ(MedianInPlace(even.data(), even.size()), 3.0);
  std::vector<double> one = {7.5};
  EXPECT_EQ(MedianInPlace(one.data(), one.size()), 7.5);
  std::vector<double> ties = {2.0, 2.0, 1.0, 2.0};
  EXPECT_EQ(MedianInPlace(ties.data(), ties.size()), 2.0);
}

TEST(Median, NoValuesIsNaN) { EXPECT_TRUE(std::isnan(MedianInPlace(nullptr, 0))); }

// Bit for bit what sorting gives (the evaluation's figures depend on it), on random samples of
// every count up to 64, the values reordered but kept.
TEST(Median, EqualsTheSortedDefinitionBitForBit) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal(0.0, 3.0);
  for (std::size_t n = 1; n <= 64; ++n) {
    std::vector<double> v(n);
    for (double& x : v) x = normal(rng);
    std::vector<double> work = v;
    EXPECT_EQ(MedianInPlace(work.data(), work.size()), SortedMedian(v)) << n;
    std::sort(work.begin(), work.end());
    std::sort(v.begin(), v.end());
    EXPECT_EQ(work, v) << n;
  }
}

}  // namespace
}  // namespace swf::core
