// Summary statistics of error lists, the one place the evaluation tools (swf-eval, swf-hazard,
// the benchmarks and the tools' tests) take medians, quantiles, means and RMS from, so that a
// figure named the same is computed the same in every report.
#pragma once

#include <vector>

namespace swf::evaluation {

// The middle value; for an even count the mean of the two middle values. NaN for an empty list.
double Median(std::vector<double> values);

// Nearest rank: the value at index floor(q n) of the sorted list (the largest for q >= 1), so
// Quantile(v, 0.5) is the upper median of an even count. NaN for an empty list.
double Quantile(std::vector<double> values, double q);

double Mean(const std::vector<double>& values);  // NaN for an empty list
double Rms(const std::vector<double>& values);   // sqrt(mean of squares); NaN for an empty list

// Sample standard deviation (n - 1); 0 for fewer than two values (no spread observed), so a
// single Monte Carlo run still reports a number.
double SampleStd(const std::vector<double>& values);

}  // namespace swf::evaluation
