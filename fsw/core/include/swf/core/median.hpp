// The median of a sample, taken in place: no allocation (std::nth_element reorders the values
// it is given), so flight code and the flight build's tests can take it too. The evaluation
// tools' swf::evaluation::Median is this one over a copy of their error lists.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

namespace swf::core {

// The median of values[0, n): the middle value, or for an even n the mean of the two middle
// values (the lower one is the largest of those nth_element leaves below the upper one); NaN
// when n is 0. Reorders the values.
inline double MedianInPlace(double* values, std::size_t n) {
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  double* const upper = values + n / 2;
  std::nth_element(values, upper, values + n);
  if (n % 2 == 1) return *upper;
  return 0.5 * (*std::max_element(values, upper) + *upper);
}

}  // namespace swf::core
