#pragma once
// Right-angle corner fitting in the laser's polar coordinates (thesis §2.4; the section is
// missing from the excerpt, reconstruction of docs/algorithms.md §16.10). The two arms share one angle: arm 1
// is the line (α, d₁), arm 2 the line (α + t·π/2, d₂) with t = ±1, and (α, d₁, d₂) is found by
// iterated linear regression on the range residuals exactly as for lines (2.20)–(2.23).
//
// Observation (docs/algorithms.md §17.8): apex (x, y) and orientation γ, the direction of the corner's
// bisector pointing from the apex into free space, with covariance of (x, y, γ).
#include <numbers>
#include <span>

#include "geometry/pose2.hpp"
#include "laser/laser_error_model.hpp"
#include "laser/polar_line_fit.hpp"

namespace polarslam {

struct RightAngleCorner {
  double alpha = 0.0;  ///< normal angle of arm 1
  double d1 = 0.0;     ///< distance of arm 1's line
  double d2 = 0.0;     ///< distance of arm 2's line
  int turn = 1;        ///< arm 2's normal is α + turn·π/2

  double alpha2() const { return alpha + turn * std::numbers::pi / 2.0; }
  PolarLine arm1() const { return {alpha, d1}; }
  PolarLine arm2() const { return {wrapAngle(alpha2()), d2}; }
  /// Intersection of the two lines: d₁·n₁ + d₂·n₂ (n₁ ⊥ n₂).
  Vec2 apex() const;
  /// Bisector pointing from the apex into free space: the direction of −(n₁ + n₂), for concave
  /// and convex corners alike (the occupied quadrant lies along +(n₁ + n₂)).
  double gamma() const { return wrapAngle(alpha + turn * std::numbers::pi / 4.0 + std::numbers::pi); }
  /// ∂(x, y, γ)/∂(α, d₁, d₂).
  Mat3 observationJacobian() const;
};

enum class CornerFitStatus { Ok, TooFewPoints, ArmFitFailed, GrazingBeam, Singular, Diverged };
const char* toString(CornerFitStatus status);

struct CornerFit {
  CornerFitStatus status = CornerFitStatus::TooFewPoints;
  RightAngleCorner corner;
  Mat3 normal_inverse = Mat3::Zero();  ///< (HᵀH)⁻¹ of (α, d₁, d₂)
  double residual_rms = 0.0;           ///< m, over both arms
  int iterations = 0;
  bool converged = false;
  /// Convex (outside, e.g. a pillar's edge) when each arm's readings lie beyond the other arm's
  /// line; concave (inside, e.g. a room corner) when they lie in front of it.
  bool convex = false;

  bool ok() const { return status == CornerFitStatus::Ok; }
  /// σ_r²(HᵀH)⁻¹ of (α, d₁, d₂), as (2.25).
  Mat3 parameterCovariance(double range_sigma) const { return range_sigma * range_sigma * normal_inverse; }
  /// Random covariance of (x, y, γ): J·σ_r²(HᵀH)⁻¹·Jᵀ.
  Mat3 covariance(double range_sigma) const;
};

/// Starting corner from two roughly perpendicular lines: α is the average of arm 1's normal and
/// arm 2's normal turned back by t·π/2.
RightAngleCorner cornerFromArms(const PolarLine& arm1, const PolarLine& arm2);

/// Fits a right-angle corner to two arms of readings, each started from its own polar line fit.
CornerFit fitRightAngleCorner(const PolarReadings& arm1, const PolarReadings& arm2,
                              const LineFitOptions& options = {});
/// Fits from a given starting corner.
CornerFit fitRightAngleCorner(const PolarReadings& arm1, const PolarReadings& arm2, const RightAngleCorner& initial,
                              const LineFitOptions& options = {});

/// Random and systematic errors of a corner, propagated to (x, y, γ) like a line's
/// (LineErrorBudget): each systematic source moves (α, d₁, d₂) by (HᵀH)⁻¹Hᵀξ.
struct CornerErrorBudget {
  Mat3 noise_cov = Mat3::Zero();       ///< J·σ_r²(HᵀH)⁻¹·Jᵀ
  Mat3 scan_bias_cov = Mat3::Zero();   ///< per-scan random bias
  Vec3 systematic_bound = Vec3::Zero();  ///< Σ|Δ(x, y, γ)| over the systematic sources

  Mat3 randomCov() const { return noise_cov + scan_bias_cov; }
  /// Covariance a Kalman filter should use: random part + diag((scale·bound)²).
  Mat3 filterCov(double scale = 1.0) const;
};

/// `times1`/`times2`: reading times after the scan's reference time (may be empty).
CornerErrorBudget cornerErrorBudget(const CornerFit& fit, const PolarReadings& arm1, const PolarReadings& arm2,
                                    std::span<const double> times1, std::span<const double> times2,
                                    const LaserErrorModel& model, const SensorMotion& motion = {});

}  // namespace polarslam
