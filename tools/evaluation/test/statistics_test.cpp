// The summary statistics on lists whose answers are known by hand.
#include "swf/evaluation/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace swf::evaluation {
namespace {

TEST(Statistics, MedianAveragesTheTwoMiddleValuesOfAnEvenCount) {
  EXPECT_EQ(Median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(Median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_TRUE(std::isnan(Median({})));
}

TEST(Statistics, QuantileIsTheNearestRank) {
  const std::vector<double> v = {5.0, 1.0, 4.0, 2.0, 3.0, 0.0, 9.0, 8.0, 7.0, 6.0};
  EXPECT_EQ(Quantile(v, 0.0), 0.0);
  EXPECT_EQ(Quantile(v, 0.5), 5.0);  // the upper median of an even count
  EXPECT_EQ(Quantile(v, 0.9), 9.0);
  EXPECT_EQ(Quantile(v, 1.0), 9.0);
  EXPECT_TRUE(std::isnan(Quantile({}, 0.5)));
}

TEST(Statistics, MeanRmsAndSampleStd) {
  EXPECT_EQ(Mean({1.0, 2.0, 6.0}), 3.0);
  EXPECT_EQ(Rms({3.0, -4.0}), std::sqrt(12.5));
  EXPECT_EQ(SampleStd({1.0, 3.0}), std::sqrt(2.0));
  EXPECT_EQ(SampleStd({7.0}), 0.0);
  EXPECT_TRUE(std::isnan(Mean({})));
  EXPECT_TRUE(std::isnan(Rms({})));
}

}  // namespace
}  // namespace swf::evaluation
