#pragma once
// Random and systematic errors of a polar line fit (thesis §2.3.3–§2.3.10, App. A.3–A.6).
//
// Every systematic source is a small range perturbation ξ_i; its effect on (α, d) is one
// Gauss–Newton step of the polar fit, Δ = (HᵀH)⁻¹Hᵀξ — the general form of (A.29)–(A.30)
// (docs/algorithms.md §16.6). The thesis's closed forms are provided too and tested against simulation; the error
// budget uses the general form, which is exact to first order for the polar fit at any geometry.
//
// "Normalised" bearings are φ − α + π/2 (2.26): the line becomes horizontal, α = π/2, and the
// beams hitting it have normalised bearings in (0, π).
#include <numbers>
#include <span>

#include "geometry/pose2.hpp"
#include "laser/laser_error_model.hpp"
#include "laser/polar_line_fit.hpp"

namespace polarslam {

/// φ − α̂ + π/2   (2.26)
inline double normalizedBearing(const PolarLine& line, double bearing) {
  return wrapAngle(bearing - line.alpha + std::numbers::pi / 2.0);
}

/// (HᵀH)⁻¹ of the polar fit at `line` (zero when singular).
Mat2 lineNormalInverse(const PolarLine& line, const PolarReadings& readings);

/// First-order change of the fitted (α, d) when the ranges carry errors ξ_i: (HᵀH)⁻¹Hᵀξ
/// (A.23)–(A.30), valid for any line orientation (no normalisation needed).
Vec2 lineErrorFromRangeErrors(const PolarLine& line, const PolarReadings& readings, std::span<const double> xi);

// ---- Identical bias in every reading of a line (§2.3.4, App. A.3) -----------------------------

/// Fixed bias r_b: (α_e, d_e) ≈ (k_e, q_e) from (2.33) and (2.35). Derived for slope–intercept
/// regression; it predicts the polar fit's error within 10% while the beams stay within about
/// ±60° of the line normal (beyond that the regressions weight the readings differently).
Vec2 fixedBiasLineError(const PolarLine& line, const PolarReadings& readings, double bias);
/// Fixed bias through the general form (A.29)–(A.30): exact to first order for the polar fit.
Vec2 fixedBiasLineErrorGeneral(const PolarLine& line, const PolarReadings& readings, double bias);

/// Bias drawn once per scan with std σ_rb: covariance (A.21), C_b = σ_rb²·g·gᵀ with
/// g = (A, B − A·D′), D′ = (d/n)·Σcot φ_i (docs/algorithms.md §16.5: the excerpt's D lacks the factor d).
/// Same ±60° validity as (2.33)/(2.35).
Mat2 scanBiasCovariance(const PolarLine& line, const PolarReadings& readings, double bias_sigma);
/// The same covariance through the general form: σ_rb²·g·gᵀ with g = (HᵀH)⁻¹Hᵀ1.
Mat2 scanBiasCovarianceGeneral(const PolarLine& line, const PolarReadings& readings, double bias_sigma);

// ---- Error changing with the incidence angle (§2.3.5, App. A.5) -------------------------------

/// Closed form (A.45)–(A.51) (cleaned in docs/algorithms.md §16.7) for range error w·|tan β| on a line at
/// distance d seen over normalised bearings [phi_first, phi_last] ⊂ (0, π). Sums become
/// integrals, so pass limits extended by half a beam step for the best agreement.
Vec2 incidenceAngleLineErrorClosedForm(double d, double phi_first, double phi_last, double w);
/// The closed form with limits taken from the readings (extended by half a beam step).
Vec2 incidenceAngleLineErrorClosedForm(const PolarLine& line, const PolarReadings& readings, double w);
/// Numerical form (A.29)–(A.30) with ξ_i = w·|tan(α − φ_i)|, |β| clamped at max_incidence.
Vec2 incidenceAngleLineError(const PolarLine& line, const PolarReadings& readings, double w,
                             double max_incidence = 1.4);

// ---- Error growing with distance (§2.3.6, App. A.6) -------------------------------------------

/// Closed form (A.61)–(A.66) (cleaned in docs/algorithms.md §16.8) for range error k·(r − r_min); phi_min is
/// the normalised bearing of the shortest reading.
Vec2 distanceGrowthLineErrorClosedForm(double d, double phi_first, double phi_last, double phi_min, double k);
Vec2 distanceGrowthLineErrorClosedForm(const PolarLine& line, const PolarReadings& readings, double k);
/// Numerical form with ξ_i = k·(r_i − r_min), r_i the line's ranges.
Vec2 distanceGrowthLineError(const PolarLine& line, const PolarReadings& readings, double k);

// ---- Quantisation bias (§2.3.7, reconstructed in docs/algorithms.md §16.10) --------------------------------

/// Error from ξ_i = b·sin(2π(r_i − Q(r_i))/q_r) (2.6) with r_i the line's ranges.
Vec2 quantizationLineError(const PolarLine& line, const PolarReadings& readings, double quantum, double amplitude);
/// Bound of the same error over every phase of the ranges within a quantisation step (the true
/// ranges are known only to within the noise, so the phase is unknown): the error is
/// cos θ·Δ_sin + sin θ·Δ_cos for a phase shift θ, whose maximum is √(Δ_sin² + Δ_cos²).
Vec2 quantizationLineErrorBound(const PolarLine& line, const PolarReadings& readings, double quantum,
                                double amplitude);

// ---- Laser plane misalignment (§2.3.8, reconstructed) ------------------------------------------

/// Scan plane tilted by ε about the in-plane axis at bearing ψ, vertical walls.
Vec2 planeTiltLineError(const PolarLine& line, const PolarReadings& readings, double tilt, double tilt_axis);
/// In-plane mounting yaw δ: the whole line turns, Δα = δ, Δd = 0.
inline Vec2 yawMisalignmentLineError(double yaw) { return {yaw, 0.0}; }

// ---- Motion during the scan (§2.3.9, reconstructed in docs/algorithms.md §16.10) ---------------------------

/// Laser moving with `motion` (laser frame, at the reference time); reading i is taken
/// times[i] seconds after the reference time.
Vec2 motionLineError(const PolarLine& line, const PolarReadings& readings, std::span<const double> times,
                     const SensorMotion& motion);

// ---- Summary (§2.3.10, docs/algorithms.md §16.10–§16.11) ----------------------------------------------------

struct LineErrorBudget {
  Mat2 noise_cov = Mat2::Zero();      ///< σ_r²(HᵀH)⁻¹   (2.25)
  Mat2 scan_bias_cov = Mat2::Zero();  ///< per-scan random bias, (A.21) in the general form
  // Systematic errors (Δα, Δd), one per source:
  Vec2 fixed_bias = Vec2::Zero();     ///< r_b
  Vec2 incidence = Vec2::Zero();      ///< w|tan β|
  Vec2 growth = Vec2::Zero();         ///< k(r − r_min)
  Vec2 quantization = Vec2::Zero();   ///< phase-independent bound of b·sin(...)
  Vec2 plane_tilt = Vec2::Zero();     ///< ε about ψ
  Vec2 yaw = Vec2::Zero();            ///< δ
  Vec2 motion = Vec2::Zero();         ///< motion during the scan
  Vec2 systematic_bound = Vec2::Zero();  ///< Σ|·| over the sources above (§2.3.10)

  /// Random part: σ_r²(HᵀH)⁻¹ + C_b.
  Mat2 randomCov() const { return noise_cov + scan_bias_cov; }
  /// Covariance a Kalman filter should use (docs/algorithms.md §16.11): the random part plus the systematic
  /// bound taken as a standard deviation (scaled), R = σ_r²(HᵀH)⁻¹ + C_b + diag((scale·bound)²).
  Mat2 filterCov(double scale = 1.0) const;
};

/// Every error of one fitted line. `times` (seconds after the scan's reference time, one per
/// reading) may be empty when the beams' timing is unknown; then motion is not counted.
LineErrorBudget lineErrorBudget(const LineFit& fit, const PolarReadings& readings, std::span<const double> times,
                                const LaserErrorModel& model, const SensorMotion& motion = {});

}  // namespace polarslam
