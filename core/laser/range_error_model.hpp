#pragma once
// The laser range error model of thesis section 2.2, shared by the simulator and the line
// error estimates:  Δr ≈ r_b + k(r' − r_min) + w|tan β| + b·sin(2π(r' − Q(r'))/q_r) + r_n   (2.8)
#include <cmath>

#include "geometry/pose2.hpp"

namespace polarslam {

struct RangeErrorParams {
  double fixed_bias = 0.0;        ///< r_b, m: identical for all readings, fixed over time
  double scan_bias_sigma = 0.0;   ///< m: std of a bias drawn once per scan (random per scan)
  double growth = 0.0;            ///< k, dimensionless: bias growing with r' − r_min
  double incidence = 0.0;         ///< w, m: bias w·|tan β| with β the incidence angle
  double quantum = 0.0;           ///< q_r, m: truncating quantiser step (0 = none)
  double noise_sigma = 0.0;       ///< σ_n, m: white Gaussian noise before the quantiser
  double max_incidence = deg2rad(80.0);  ///< rad: |β| is clamped here so tan β stays finite
};

/// Truncating quantiser Q(r) = q·floor(r/q)   (2.1)
inline double quantize(double r, double q) { return q > 0.0 ? q * std::floor(r / q) : r; }

/// Mean of Q(r' + n) − r' for n ~ N(0, σ²)   (2.2)–(2.4), summed exactly.
double quantizerMeanError(double true_range, double quantum, double noise_sigma);

/// Variance of Q(r' + n) − r'   (2.5), summed exactly.
double quantizerErrorVariance(double true_range, double quantum, double noise_sigma);

/// Amplitude b of the sinusoidal approximation (2.6) of the quantiser's mean error, found
/// numerically from (2.4) for the given step and noise.
double quantizationBiasAmplitude(double quantum, double noise_sigma);

/// Standard-deviation approximation (2.7): k1·cos(2π(r' − Q(r'))/q) + k2; returns {k1, k2}.
struct QuantizerStdFit { double k1 = 0.0, k2 = 0.0; };
QuantizerStdFit quantizerStdFit(double quantum, double noise_sigma);

/// Quantisation bias term of (2.8): b·sin(2π(r' − Q(r'))/q_r).
double quantizationBias(double true_range, double quantum, double amplitude);

/// Deterministic part of (2.8) for one reading of a line, excluding the per-scan random bias,
/// the quantisation bias and white noise: r_b + k(r' − r_min) + w|tan β|.
double systematicRangeBias(const RangeErrorParams& p, double true_range, double line_min_range,
                           double incidence_angle);

}  // namespace polarslam
