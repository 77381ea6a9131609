#include "geometry/chi_squared.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace polarslam {
namespace {

constexpr int kMaxTerms = 100000;
constexpr double kEpsilon = 1e-16;

/// Series γ(a, x)/Γ(a) = e^{−x} x^a / Γ(a) · Σ x^n / (a (a+1) … (a+n)); converges fast for x < a + 1.
double lowerGammaSeries(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < kMaxTerms; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * kEpsilon) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

/// Continued fraction for Q(a, x) = 1 − P(a, x) (modified Lentz); converges fast for x ≥ a + 1.
double upperGammaContinuedFraction(double a, double x) {
  constexpr double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < kMaxTerms; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEpsilon) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

void requirePositiveDof(double dof) {
  if (!(dof > 0.0) || !std::isfinite(dof)) throw std::invalid_argument("chi-squared: degrees of freedom must be > 0");
}

}  // namespace

double regularizedLowerGamma(double a, double x) {
  if (!(a > 0.0) || !(x >= 0.0)) throw std::invalid_argument("regularizedLowerGamma: needs a > 0 and x >= 0");
  if (x == 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  return x < a + 1.0 ? lowerGammaSeries(a, x) : 1.0 - upperGammaContinuedFraction(a, x);
}

double chiSquaredCdf(double x, double dof) {
  requirePositiveDof(dof);
  if (std::isnan(x)) return x;
  return x <= 0.0 ? 0.0 : regularizedLowerGamma(0.5 * dof, 0.5 * x);
}

double chiSquaredQuantile(double probability, double dof) {
  requirePositiveDof(dof);
  if (!(probability > 0.0 && probability < 1.0))
    throw std::invalid_argument("chiSquaredQuantile: probability must lie in (0, 1)");
  double low = 0.0, high = dof + 10.0 * std::sqrt(2.0 * dof) + 10.0;
  while (chiSquaredCdf(high, dof) < probability) high *= 2.0;
  // Bisection: 200 halvings reach the spacing of doubles for any bracket we can form.
  for (int i = 0; i < 200 && high - low > 4.0 * std::numeric_limits<double>::epsilon() * high; ++i) {
    const double mid = 0.5 * (low + high);
    (chiSquaredCdf(mid, dof) < probability ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

}  // namespace polarslam
