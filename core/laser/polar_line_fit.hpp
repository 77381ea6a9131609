#pragma once
// Line fitting in the laser's own polar coordinates (thesis §2.3.1–§2.3.3): iterated linear
// regression on the linearised polar line (2.16)–(2.23), started from a total-least-squares fit,
// with the random covariance σ_r²(HᵀH)⁻¹ (2.25).
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

/// Line x cos α + y sin α = d with d ≥ 0 (2.9); in polar coordinates r = d / cos(α − φ) (2.10).
struct PolarLine {
  double alpha = 0.0, d = 0.0;
};

/// Range at bearing φ of the line (2.10).
inline double lineRange(const PolarLine& line, double bearing) { return line.d / std::cos(line.alpha - bearing); }

/// Read-only view of n laser readings: bearings, ranges and the bearings' cosines and sines
/// (precomputed once per scan so that fits need no trigonometry per reading).
struct PolarReadings {
  std::span<const double> bearing, range, cos_bearing, sin_bearing;

  size_t size() const { return bearing.size(); }
  bool empty() const { return bearing.empty(); }
  PolarReadings sub(size_t first, size_t count) const {
    return {bearing.subspan(first, count), range.subspan(first, count), cos_bearing.subspan(first, count),
            sin_bearing.subspan(first, count)};
  }
  Vec2 point(size_t i) const { return {range[i] * cos_bearing[i], range[i] * sin_bearing[i]}; }
};

/// Owning storage behind a PolarReadings view.
class PolarReadingBuffer {
 public:
  PolarReadingBuffer() = default;
  PolarReadingBuffer(std::span<const double> bearings, std::span<const double> ranges);
  void clear();
  void push_back(double bearing, double range);
  /// With the bearing's cosine and sine already known.
  void push_back(double bearing, double range, double cos_bearing, double sin_bearing);
  void reserve(size_t n);
  size_t size() const { return bearing_.size(); }
  PolarReadings view() const { return {bearing_, range_, cos_, sin_}; }

 private:
  std::vector<double> bearing_, range_, cos_, sin_;
};

/// Total-least-squares (perpendicular distance) fit of the readings' Cartesian points — the
/// starting point of the polar fit, and the "Cartesian TLS" baseline it is compared against.
/// Needs at least two points; otherwise returns d = NaN.
PolarLine fitLineTotalLeastSquares(const PolarReadings& readings);

struct LineFitOptions {
  int max_iterations = 20;
  double angle_tolerance = 1e-6;      ///< rad: stop when |Δα| and |Δd| are both below tolerance
  double distance_tolerance = 1e-6;   ///< m (docs/algorithms.md §16.3; the step taken then leaves ~1e-12)
  double max_incidence = deg2rad(80.0);  ///< rad: fail if a beam meets the line at a larger |α − φ|
};

enum class LineFitStatus { Ok, TooFewPoints, GrazingBeam, Singular, Diverged };
const char* toString(LineFitStatus status);

struct LineFit {
  LineFitStatus status = LineFitStatus::TooFewPoints;
  PolarLine line;
  Mat2 normal_inverse = Mat2::Zero();  ///< (HᵀH)⁻¹ at the solution (2.25)
  double residual_rms = 0.0;           ///< m, RMS of the range residuals r_m − r̂
  int iterations = 0;
  bool converged = false;

  bool ok() const { return status == LineFitStatus::Ok; }
  /// Random covariance of (α, d) for white range noise of std σ_r: σ_r²(HᵀH)⁻¹   (2.25)
  Mat2 covariance(double range_sigma) const { return range_sigma * range_sigma * normal_inverse; }
};

/// Polar fit started from the TLS fit (2.20)–(2.23).
LineFit fitLinePolar(const PolarReadings& readings, const LineFitOptions& options = {});
/// Polar fit started from a given line.
LineFit fitLinePolar(const PolarReadings& readings, const PolarLine& initial, const LineFitOptions& options = {});

/// Jacobian row of (2.16)/(2.21) for one reading: ∂r/∂α, ∂r/∂d at the line.
inline Vec2 lineRangeJacobian(const PolarLine& line, double cos_incidence, double sin_incidence) {
  const double inv = 1.0 / cos_incidence;
  return {line.d * sin_incidence * inv * inv, inv};
}

/// Endpoint of the segment: the reading's point projected onto the line.
Vec2 projectOntoLine(const PolarLine& line, const Vec2& point);

}  // namespace polarslam
