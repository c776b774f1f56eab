// ChiSquareQuantile: gate thresholds for the estimator's integrity tests, computed at
// configuration time from a probability instead of tabulated.
#pragma once

#include <cmath>

namespace swf::estimator {

// Upper quantile of the chi-square distribution with `dof` degrees of freedom: the x with
// P(chi2_dof <= x) = probability. The CDF is the regularized lower incomplete gamma function
// P(dof/2, x/2), summed as its power series; the quantile by bisection (bounded, configuration
// time only). 0 for a probability outside (0, 1) or dof outside [1, 60].
inline double ChiSquareQuantile(int dof, double probability) {
  if (!(probability > 0.0 && probability < 1.0) || dof < 1 || dof > 60) return 0.0;
  const double a = 0.5 * dof;
  const auto cdf = [a](double x) {
    const double z = 0.5 * x;
    if (z <= 0.0) return 0.0;
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 1000 && term > 1e-17 * sum; ++n) {
      term *= z / (a + n);
      sum += term;
    }
    return std::exp(a * std::log(z) - z - std::lgamma(a)) * sum;
  };
  double lo = 0.0;
  double hi = 400.0;  // CDF(400) = 1 - 1e-60 for dof <= 60
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace swf::estimator
