// ChiSquareQuantile and NormalUpperQuantile: the integrity tests' thresholds, computed at
// configuration time from a probability instead of tabulated.
//
// Both come from the regularized incomplete gamma function, written with arithmetic, sqrt, exp
// and log only. Debian's x86-64 and arm64 C libraries give the same bits for exp and log but not
// for lgamma and erfc (docs/aarch64.md), so the thresholds, and every output that depends on
// them, are the same on the host and the flight computer.
#pragma once

#include <cmath>
#include <numbers>

namespace swf::estimator {
namespace detail {

// log Gamma(a) for a = k/2, k = 1..120: Gamma(1/2) = sqrt(pi), Gamma(1) = 1 and
// Gamma(a + 1) = a Gamma(a), multiplied out (exact products of small numbers; at most 1e80).
inline double LogGammaOfHalfInteger(double a) {
  double g = std::fmod(a, 1.0) == 0.0 ? 1.0 : std::sqrt(std::numbers::pi);
  for (double x = std::fmod(a, 1.0) == 0.0 ? 1.0 : 0.5; x < a; x += 1.0) g *= x;
  return std::log(g);
}

// P(a, z) and Q(a, z) = 1 - P(a, z), regularized lower and upper incomplete gamma functions, for
// a = k/2. The power series of P converges fast for z < a + 1; above, the continued fraction of
// Q (evaluated by the modified Lentz method) does, and gives the small upper tails without the
// cancellation of 1 - P.
struct IncompleteGamma {
  double p;
  double q;
};

inline IncompleteGamma RegularizedGamma(double a, double z) {
  if (!(z > 0.0)) return {0.0, 1.0};
  const double prefactor = std::exp(a * std::log(z) - z - LogGammaOfHalfInteger(a));
  if (z < a + 1.0) {
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 1000 && term > 1e-17 * sum; ++n) {
      term *= z / (a + n);
      sum += term;
    }
    const double p = prefactor * sum;
    return {p, 1.0 - p};
  }
  constexpr double kTiny = 1e-300;
  double b = z + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int n = 1; n < 1000; ++n) {
    const double an = -n * (n - a);
    b += 2.0;
    d = an * d + b;
    d = std::fabs(d) < kTiny ? kTiny : d;
    c = b + an / c;
    c = std::fabs(c) < kTiny ? kTiny : c;
    d = 1.0 / d;
    const double step = d * c;
    h *= step;
    if (std::fabs(step - 1.0) < 1e-16) break;
  }
  const double q = prefactor * h;
  return {1.0 - q, q};
}

}  // namespace detail

// Upper quantile of the chi-square distribution with `dof` degrees of freedom: the x with
// P(chi2_dof <= x) = probability, P(dof/2, x/2) by bisection (bounded). 0 for a probability
// outside (0, 1) or dof outside [1, 60].
inline double ChiSquareQuantile(int dof, double probability) {
  if (!(probability > 0.0 && probability < 1.0) || dof < 1 || dof > 60) return 0.0;
  const double a = 0.5 * dof;
  double lo = 0.0;
  double hi = 400.0;  // CDF(400) = 1 - 1e-60 for dof <= 60
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (detail::RegularizedGamma(a, 0.5 * mid).p < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Standard normal upper quantile: the x with P(Z > x) = tail, for tail in (0, 0.5). P(|Z| > x) is
// the chi-square(1) upper tail at x^2, Q(1/2, x^2/2); by bisection (bounded).
inline double NormalUpperQuantile(double tail) {
  double lo = 0.0;
  double hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * detail::RegularizedGamma(0.5, 0.5 * mid * mid).q > tail ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace swf::estimator
