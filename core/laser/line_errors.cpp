#include "laser/line_errors.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "laser/error_projection.hpp"

namespace polarslam {
namespace {

constexpr double kHalfPi = std::numbers::pi / 2.0;

/// cos(α − φ_i) and sin(α − φ_i) from the precomputed cos/sin of the bearings.
struct Incidence {
  double c, s;
};
inline Incidence incidence(double ca, double sa, const PolarReadings& r, size_t i) {
  return {ca * r.cos_bearing[i] + sa * r.sin_bearing[i], sa * r.cos_bearing[i] - ca * r.sin_bearing[i]};
}

/// (HᵀH)⁻¹Hᵀξ with ξ_i = xi(i, incidence_i, range_i): one Gauss–Newton step (A.29)–(A.30).
template <typename Xi>
Vec2 projectRangeErrors(const PolarLine& line, const Mat2& normal_inverse, const PolarReadings& r, Xi&& xi) {
  const double ca = std::cos(line.alpha), sa = std::sin(line.alpha);
  Vec2 htx = Vec2::Zero();
  for (size_t i = 0; i < r.size(); ++i) {
    const Incidence inc = incidence(ca, sa, r, i);
    const double range = line.d / inc.c;
    htx += lineRangeJacobian(line, inc.c, inc.s) * xi(i, inc, range);
  }
  return normal_inverse * htx;
}

/// Shortest range of the line over the readings' bearings: d / max cos(α − φ_i).
double lineMinRange(const PolarLine& line, const PolarReadings& r) {
  const double ca = std::cos(line.alpha), sa = std::sin(line.alpha);
  double max_cos = 0.0;
  for (size_t i = 0; i < r.size(); ++i) max_cos = std::max(max_cos, incidence(ca, sa, r, i).c);
  return line.d / max_cos;
}

/// Normalised bearings of the first and last reading, extended by half a beam step each so
/// that integrals over [φ₁, φ_n] approximate the sums over the readings (midpoint rule).
std::pair<double, double> integrationLimits(const PolarLine& line, const PolarReadings& r) {
  double a = normalizedBearing(line, r.bearing.front());
  double b = normalizedBearing(line, r.bearing.back());
  if (a > b) std::swap(a, b);
  const double half_step = r.size() > 1 ? 0.5 * (b - a) / static_cast<double>(r.size() - 1) : 0.0;
  constexpr double kEdge = 1e-6;
  return {std::max(a - half_step, kEdge), std::min(b + half_step, std::numbers::pi - kEdge)};
}

/// Terms A, C, D shared by (A.45)–(A.51) and (A.61)–(A.66) (integrals of 1/sin², cos/sin³, cos²/sin⁴).
struct ClosedFormTerms {
  double A, C, D;
};
ClosedFormTerms closedFormTerms(double phi1, double phin) {
  const double s1 = std::sin(phi1), sn = std::sin(phin);
  const double cot1 = std::cos(phi1) / s1, cotn = std::cos(phin) / sn;
  return {0.5 * (1.0 / (s1 * s1) - 1.0 / (sn * sn)),    // (A.47)
          cot1 - cotn,                                  // (A.48)
          (cot1 * cot1 * cot1 - cotn * cotn * cotn) / 3.0};  // (A.49)
}

}  // namespace

Mat2 lineNormalInverse(const PolarLine& line, const PolarReadings& r) {
  const double ca = std::cos(line.alpha), sa = std::sin(line.alpha);
  Mat2 hth = Mat2::Zero();
  for (size_t i = 0; i < r.size(); ++i) {
    const Incidence inc = incidence(ca, sa, r, i);
    const Vec2 h = lineRangeJacobian(line, inc.c, inc.s);
    hth += h * h.transpose();
  }
  const double det = hth.determinant();
  if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return Mat2::Zero();
  return hth.inverse();
}

Vec2 lineErrorFromRangeErrors(const PolarLine& line, const PolarReadings& r, std::span<const double> xi) {
  return projectRangeErrors(line, lineNormalInverse(line, r), r,
                            [&](size_t i, const Incidence&, double) { return xi[i]; });
}

namespace {

/// Sums over the normalised bearings (2.26) that (2.33), (2.35) and (A.14) are built from.
struct NormalizedBearingSums {
  double n = 0.0, sum_cos = 0.0, sum_sin = 0.0, sum_cot = 0.0, sum_cot2 = 0.0;
};

NormalizedBearingSums normalizedBearingSums(const PolarLine& line, const PolarReadings& r) {
  NormalizedBearingSums s;
  s.n = static_cast<double>(r.size());
  for (size_t i = 0; i < r.size(); ++i) {
    const double phi = normalizedBearing(line, r.bearing[i]);
    const double c = std::cos(phi), cot = c / std::sin(phi);
    s.sum_cos += c;
    s.sum_sin += std::sin(phi);
    s.sum_cot += cot;
    s.sum_cot2 += cot * cot;
  }
  return s;
}

}  // namespace

Vec2 fixedBiasLineError(const PolarLine& line, const PolarReadings& r, double bias) {
  const auto [n, sum_cos, sum_sin, sum_cot, sum_cot2] = normalizedBearingSums(line, r);
  const double slope_error = bias / line.d * (n * sum_cos - sum_cot * sum_sin) / (n * sum_cot2 - sum_cot * sum_cot);  // (2.33)
  const double intercept_error = bias / n * sum_sin - slope_error / n * (bias * sum_cos + line.d * sum_cot);  // (2.35)
  return {slope_error, intercept_error};  // α_e ≈ k_e, d_e ≈ q_e for the normalised line
}

Vec2 fixedBiasLineErrorGeneral(const PolarLine& line, const PolarReadings& r, double bias) {
  return projectRangeErrors(line, lineNormalInverse(line, r), r, [&](size_t, const Incidence&, double) { return bias; });
}

Mat2 scanBiasCovariance(const PolarLine& line, const PolarReadings& r, double bias_sigma) {
  const auto [n, sum_cos, sum_sin, sum_cot, sum_cot2] = normalizedBearingSums(line, r);
  const double A = (n * sum_cos - sum_cot * sum_sin) / (line.d * (n * sum_cot2 - sum_cot * sum_cot));  // (A.14)
  const double B = sum_sin / n;
  const double D = line.d * sum_cot / n;  // D′ of docs/algorithms.md §16.5
  const Vec2 g(A, B - A * D);             // (A.18)–(A.20)
  return bias_sigma * bias_sigma * g * g.transpose();  // (A.21)
}

Mat2 scanBiasCovarianceGeneral(const PolarLine& line, const PolarReadings& r, double bias_sigma) {
  const Vec2 g = fixedBiasLineErrorGeneral(line, r, 1.0);
  return bias_sigma * bias_sigma * g * g.transpose();
}

Vec2 incidenceAngleLineErrorClosedForm(double d, double phi1, double phin, double w) {
  const auto [A, C, D] = closedFormTerms(phi1, phin);
  // Sign of cot φ over the segment: s = 1, t = 1 when the normal falls inside [φ₁, φ_n].
  double s = 1.0, t = 1.0;
  if (phin <= kHalfPi) {
    t = -1.0;
  } else if (phi1 >= kHalfPi) {
    s = -1.0;
    t = -1.0;
  }
  const double s1 = std::sin(phi1), sn = std::sin(phin);
  const double E = -(t + 1.0) + 1.0 / s1 + t / sn;  // (A.50)
  const double F = 0.5 * (std::cos(phi1) / (s1 * s1) + std::log(std::abs(std::tan(phi1 / 2.0)))) +
                   0.5 * t * (std::cos(phin) / (sn * sn) + std::log(std::abs(std::tan(phin / 2.0))));  // (A.51)
  const double den = A * A - D * C;
  return {w * s / d * (E * A - F * C) / den,  // (A.45)
          w * s * (F * A - E * D) / den};     // (A.46)
}

Vec2 incidenceAngleLineErrorClosedForm(const PolarLine& line, const PolarReadings& r, double w) {
  if (r.size() < 2) return Vec2::Zero();
  const auto [phi1, phin] = integrationLimits(line, r);
  return incidenceAngleLineErrorClosedForm(line.d, phi1, phin, w);
}

Vec2 incidenceAngleLineError(const PolarLine& line, const PolarReadings& r, double w, double max_incidence) {
  return projectRangeErrors(line, lineNormalInverse(line, r), r, [&](size_t i, const Incidence&, double) {
    return incidenceAnglePerturbation(line.alpha, r.bearing[i], w, max_incidence);
  });
}

Vec2 distanceGrowthLineErrorClosedForm(double d, double phi1, double phin, double phi_min, double k) {
  const auto [A, C, D] = closedFormTerms(phi1, phin);
  const double B = 1.0 / std::sin(phi1) - 1.0 / std::sin(phin);                   // (A.64)
  const double L = std::log(std::tan(phin / 2.0) / std::tan(phi1 / 2.0));         // Σ 1/sin φ
  const double sm = std::sin(phi_min);
  const double den = A * A - D * C;
  return {k / sm * (B * C - A * L) / den,                                   // (A.61)
          k * d * (A * (A - B / sm) - D * (C - L / sm)) / den};             // (A.62)
}

Vec2 distanceGrowthLineErrorClosedForm(const PolarLine& line, const PolarReadings& r, double k) {
  if (r.size() < 2) return Vec2::Zero();
  const auto [phi1, phin] = integrationLimits(line, r);
  double phi_min = normalizedBearing(line, r.bearing.front());
  for (size_t i = 1; i < r.size(); ++i) {
    const double phi = normalizedBearing(line, r.bearing[i]);
    if (std::abs(phi - kHalfPi) < std::abs(phi_min - kHalfPi)) phi_min = phi;
  }
  return distanceGrowthLineErrorClosedForm(line.d, phi1, phin, phi_min, k);
}

Vec2 distanceGrowthLineError(const PolarLine& line, const PolarReadings& r, double k) {
  const double r_min = lineMinRange(line, r);
  return projectRangeErrors(line, lineNormalInverse(line, r), r, [&](size_t, const Incidence&, double range) {
    return distanceGrowthPerturbation(range, r_min, k);
  });
}

Vec2 quantizationLineError(const PolarLine& line, const PolarReadings& r, double quantum, double amplitude) {
  if (quantum <= 0.0) return Vec2::Zero();
  return projectRangeErrors(line, lineNormalInverse(line, r), r, [&](size_t, const Incidence&, double range) {
    return quantizationPerturbation(range, quantum, amplitude);
  });
}

Vec2 quantizationLineErrorBound(const PolarLine& line, const PolarReadings& r, double quantum, double amplitude) {
  if (quantum <= 0.0) return Vec2::Zero();
  const Mat2 normal_inverse = lineNormalInverse(line, r);
  const Vec2 in_phase = projectRangeErrors(line, normal_inverse, r, [&](size_t, const Incidence&, double range) {
    return quantizationPerturbation(range, quantum, amplitude, 0.0);
  });
  const Vec2 quadrature = projectRangeErrors(line, normal_inverse, r, [&](size_t, const Incidence&, double range) {
    return quantizationPerturbation(range, quantum, amplitude, kHalfPi);
  });
  return (in_phase.array().square() + quadrature.array().square()).sqrt();
}

Vec2 planeTiltLineError(const PolarLine& line, const PolarReadings& r, double tilt, double tilt_axis) {
  if (tilt == 0.0) return Vec2::Zero();
  return projectRangeErrors(line, lineNormalInverse(line, r), r, [&](size_t i, const Incidence&, double range) {
    return planeTiltPerturbation(line.alpha, r.bearing[i], range, tilt, tilt_axis);
  });
}

Vec2 motionLineError(const PolarLine& line, const PolarReadings& r, std::span<const double> times,
                     const SensorMotion& motion) {
  if (times.size() != r.size() || motion.isZero()) return Vec2::Zero();
  return projectRangeErrors(line, lineNormalInverse(line, r), r, [&](size_t i, const Incidence&, double) {
    return motionPerturbation(line.alpha, line.d, r.bearing[i], times[i], motion);
  });
}

Mat2 LineErrorBudget::filterCov(double scale) const {
  const Vec2 s = scale * systematic_bound;
  return randomCov() + s.array().square().matrix().asDiagonal().toDenseMatrix();
}

LineErrorBudget lineErrorBudget(const LineFit& fit, const PolarReadings& r, std::span<const double> times,
                                const LaserErrorModel& model, const SensorMotion& motion) {
  LineErrorBudget b;
  if (!fit.ok()) return b;
  const PolarLine& line = fit.line;
  const bool timed = times.size() == r.size();
  const SensorMotion effective_motion = timed ? motion : SensorMotion{};
  const double r_min = lineMinRange(line, r);
  const double ca = std::cos(line.alpha), sa = std::sin(line.alpha);
  RangeErrorSums<2> sums;
  for (size_t i = 0; i < r.size(); ++i) {  // one pass: Σ h_i ξ_i for every source
    const Incidence inc = incidence(ca, sa, r, i);
    const double range = line.d / inc.c;
    const ReadingGeometry g{line.d, r.cos_bearing[i], r.sin_bearing[i], inc.c, inc.s, range};
    sums.add(lineRangeJacobian(line, inc.c, inc.s),
             readingPerturbations(model, g, r_min, timed ? times[i] : 0.0, effective_motion));
  }
  const SourceErrors<2> e = projectSourceErrors<2, 2>(sums, fit.normal_inverse, Mat2::Identity(), model.params(),
                                                      yawMisalignmentLineError(model.params().yaw_error));
  b.noise_cov = fit.covariance(model.rangeSigma());                   // (2.25)
  b.scan_bias_cov = e.scanBiasCov(model.params().range.scan_bias_sigma);  // (A.21)
  b.fixed_bias = e.fixed_bias;
  b.incidence = e.incidence;
  b.growth = e.growth;
  b.quantization = e.quantization;
  b.plane_tilt = e.plane_tilt;
  b.yaw = e.yaw;
  b.motion = e.motion;
  b.systematic_bound = e.bound();  // §2.3.10
  return b;
}

}  // namespace polarslam
