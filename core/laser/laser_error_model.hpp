#pragma once
// The complete laser error model used by line and corner error estimates (thesis §2.2–§2.3.9):
// the range error model (2.8) plus laser-plane misalignment and motion during the scan, as
// per-reading range perturbations ξ_i. Each perturbation is fed through the linearised fit
// (A.29)–(A.30) to give a line (or corner) parameter error; see line_errors.hpp.
#include <span>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/range_error_model.hpp"

namespace polarslam {

/// Everything known about a laser's errors. The systematic terms are magnitudes (bounds): their
/// sign is unknown, and the bound of section 2.3.10 sums absolute values anyway.
struct LaserErrorParams {
  RangeErrorParams range;          ///< (2.8): r_b, per-scan bias σ, k, w, q_r, σ_n
  double output_noise_sigma = 0.0; ///< m: extra white noise after the quantiser (adds to σ_r²)
  double tilt = 0.0;               ///< ε, rad: tilt of the scan plane against the horizontal
  double tilt_axis = 0.0;          ///< ψ, rad: bearing of the in-plane axis the plane is tilted about
  double yaw_error = 0.0;          ///< δ, rad: in-plane mounting yaw uncertainty (adds to α directly)
  double systematic_scale = 1.0;   ///< filter covariance adds (scale·bound)²: 1 = bound taken as 1σ
  double min_range_sigma = 1e-4;   ///< m: floor of σ_r so that a covariance never becomes singular
};

/// Velocity of the laser during a scan, in the laser frame at the scan's reference time (beam 0).
struct SensorMotion {
  double vx = 0.0, vy = 0.0;  ///< m/s
  double omega = 0.0;         ///< rad/s
  bool isZero() const { return vx == 0.0 && vy == 0.0 && omega == 0.0; }
};

/// Laser-frame velocity of a laser mounted at `mount` on a base moving with forward speed v and
/// turn rate ω (differential drive: no sideways speed).
SensorMotion sensorMotionFromBaseTwist(const Pose2& mount, double v, double omega);

/// LaserErrorParams with the quantities derived from them computed once: the random range
/// standard deviation after the quantiser and the quantisation-bias amplitude b of (2.6).
class LaserErrorModel {
 public:
  LaserErrorModel() : LaserErrorModel(LaserErrorParams{}) {}
  explicit LaserErrorModel(const LaserErrorParams& params);

  const LaserErrorParams& params() const { return params_; }
  /// σ_r of the white range noise r_n after the quantiser: the quantiser's output variance (2.5)
  /// averaged over the position of r′ within a step (σ_n² without a quantiser), plus the
  /// variance of any noise added after the quantiser.
  double rangeSigma() const { return range_sigma_; }
  /// b of (2.6), fitted numerically to (2.4).
  double quantizationAmplitude() const { return quantization_amplitude_; }
  /// tan of the incidence clamp, and cos/sin of the tilt axis (for readingPerturbations).
  double maxIncidenceTan() const { return max_incidence_tan_; }
  double tiltAxisCos() const { return tilt_axis_cos_; }
  double tiltAxisSin() const { return tilt_axis_sin_; }

 private:
  LaserErrorParams params_;
  double range_sigma_ = 0.0;
  double quantization_amplitude_ = 0.0;
  double max_incidence_tan_ = 0.0, tilt_axis_cos_ = 1.0, tilt_axis_sin_ = 0.0;
};

// ---- Per-reading range perturbations ξ_i (true range error of one reading, metres) ----------
// Notation: a reading at bearing φ hits a line with normal angle α and distance d; its true range
// is r = d / cos(α − φ) (2.10), and the incidence angle is β = α − φ.

/// Incidence-angle term of (2.8): w·|tan β|, with |β| clamped at max_incidence.
double incidenceAnglePerturbation(double alpha, double bearing, double w, double max_incidence);

/// Distance-growing term of (2.8): k·(r − r_min), r_min the line's shortest range.
double distanceGrowthPerturbation(double range, double line_min_range, double k);

/// Quantisation-bias term of (2.8), b·sin(2π(r − Q(r))/q_r + phase). The phase argument lets the
/// caller build the phase-independent envelope (phase 0 and π/2).
double quantizationPerturbation(double range, double quantum, double amplitude, double phase = 0.0);

/// Laser-plane misalignment (thesis §2.3.8, reconstructed): the scan plane is tilted by ε about
/// the in-plane axis at bearing ψ; against a vertical wall the beam at encoder angle φ travels
///   ξ = r·(ε²/2)·(1 − cos(φ − ψ)·cos(α − ψ)/cos(α − φ))
/// further (second order in ε; exact: d/(cos ε·cos(α−φ) + (1−cos ε)·cos(φ−ψ)·cos(α−ψ)) − r).
/// docs/algorithms.md §16.10 gives r·e²/2 with e = ε·sin(φ−ψ), which omits the change of the beam's
/// azimuth and is wrong by a factor up to 2 (it predicts an error where there is none for a
/// wall whose normal is the tilt axis).
double planeTiltPerturbation(double alpha, double bearing, double range, double tilt, double tilt_axis);

/// Motion during the scan (thesis §2.3.9, docs/algorithms.md §16.10): at time τ after the reference the laser
/// has moved by δp = v·τ and turned by δφ = ω·τ, so to first order
///   ξ = −(n·δp)/cos(α − φ) − d·sin(α − φ)/cos²(α − φ)·δφ,   n = (cos α, sin α).
double motionPerturbation(double alpha, double d, double bearing, double time, const SensorMotion& motion);

/// Every systematic perturbation of one reading (metres), for error budgets that visit each
/// reading once. quantization_sin / _cos are the in-phase and quadrature parts of (2.6).
struct ReadingPerturbations {
  double incidence = 0.0, growth = 0.0, quantization_sin = 0.0, quantization_cos = 0.0, tilt = 0.0, motion = 0.0;
};

/// One reading hitting the line (α, d): cos/sin of its bearing φ and of the incidence α − φ,
/// and its true range d / cos(α − φ).
struct ReadingGeometry {
  double d = 0.0;
  double cos_bearing = 1.0, sin_bearing = 0.0;
  double cos_incidence = 1.0, sin_incidence = 0.0;
  double range = 0.0;
};

/// The perturbations above for one reading, without trigonometric calls (the same values as the
/// per-source functions). `line_min_range` is the line's shortest range, `time` the reading's
/// time after the scan's reference time (ignored when the motion is zero).
ReadingPerturbations readingPerturbations(const LaserErrorModel& model, const ReadingGeometry& g,
                                          double line_min_range, double time, const SensorMotion& motion);

}  // namespace polarslam
