#include "laser/range_error_model.hpp"

#include <algorithm>
#include <numbers>

namespace polarslam {
namespace {

double normalCdf(double x, double sigma) { return 0.5 * std::erfc(-x / (sigma * std::numbers::sqrt2)); }

template <typename F>
void forEachQuantizerOutput(double r, double q, double sigma, F&& f) {
  const long lo = static_cast<long>(std::floor((r - 8.0 * sigma) / q)) - 1;
  const long hi = static_cast<long>(std::floor((r + 8.0 * sigma) / q)) + 1;
  for (long i = lo; i <= hi; ++i) {
    const double p = normalCdf((i + 1) * q - r, sigma) - normalCdf(i * q - r, sigma);  // (2.2)
    f(i * q - r, p);
  }
}

}  // namespace

double quantizerMeanError(double r, double q, double sigma) {
  if (q <= 0.0) return 0.0;
  if (sigma <= 0.0) return quantize(r, q) - r;
  double mean = 0.0;
  forEachQuantizerOutput(r, q, sigma, [&](double e, double p) { mean += e * p; });  // (2.4)
  return mean;
}

double quantizerErrorVariance(double r, double q, double sigma) {
  if (q <= 0.0) return sigma * sigma;
  if (sigma <= 0.0) return 0.0;
  double m1 = 0.0, m2 = 0.0;
  forEachQuantizerOutput(r, q, sigma, [&](double e, double p) { m1 += e * p; m2 += e * e * p; });
  return m2 - m1 * m1;  // (2.5)
}

double quantizationBiasAmplitude(double q, double sigma) {
  if (q <= 0.0) return 0.0;
  // Least-squares fit of mean + q/2 = b·sin(2π r'/q) over one quantisation period.
  constexpr int kSamples = 200;
  double num = 0.0, den = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    const double r = 10.0 * q + q * (i + 0.5) / kSamples;
    const double s = std::sin(2.0 * std::numbers::pi * (r - quantize(r, q)) / q);
    num += (quantizerMeanError(r, q, sigma) + 0.5 * q) * s;
    den += s * s;
  }
  return num / den;
}

QuantizerStdFit quantizerStdFit(double q, double sigma) {
  QuantizerStdFit fit;
  if (q <= 0.0) { fit.k2 = sigma; return fit; }
  constexpr int kSamples = 200;
  double sc = 0.0, cc = 0.0, s1 = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    const double r = 10.0 * q + q * (i + 0.5) / kSamples;
    const double c = std::cos(2.0 * std::numbers::pi * (r - quantize(r, q)) / q);
    const double sd = std::sqrt(quantizerErrorVariance(r, q, sigma));
    sc += sd * c; cc += c * c; s1 += sd;
  }
  fit.k1 = sc / cc;
  fit.k2 = s1 / kSamples;
  return fit;
}

double quantizationBias(double r, double q, double b) {
  if (q <= 0.0) return 0.0;
  return b * std::sin(2.0 * std::numbers::pi * (r - quantize(r, q)) / q);
}

double systematicRangeBias(const RangeErrorParams& p, double r, double r_min, double beta) {
  const double b = std::clamp(std::abs(beta), 0.0, p.max_incidence);
  return p.fixed_bias + p.growth * (r - r_min) + p.incidence * std::abs(std::tan(b));  // (2.8)
}

}  // namespace polarslam
