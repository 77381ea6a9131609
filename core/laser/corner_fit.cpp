#include "laser/corner_fit.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "laser/error_projection.hpp"

namespace polarslam {
namespace {

using Vec3Row = Eigen::Matrix<double, 3, 1>;

/// Normal equations of the linearised corner at one estimate: rows of H are
///   arm 1: [d₁ sin(α − φ)/cos²(α − φ), 1/cos(α − φ), 0]
///   arm 2: [d₂ sin(α₂ − φ)/cos²(α₂ − φ), 0, 1/cos(α₂ − φ)]      (docs/algorithms.md §16.10, cf. (2.21))
struct CornerNormalEquations {
  Mat3 hth = Mat3::Zero();
  Vec3 hte = Vec3::Zero();
  double sse = 0.0;
  double min_cos = 1.0;
};

/// Jacobian row of one reading on arm `arm` (0 or 1) with cos/sin of its incidence angle.
Vec3Row cornerRow(const RightAngleCorner& corner, int arm, double c, double s) {
  const double inv = 1.0 / c;
  const double d = arm == 0 ? corner.d1 : corner.d2;
  Vec3Row h = Vec3Row::Zero();
  h(0) = d * s * inv * inv;
  h(1 + arm) = inv;
  return h;
}

template <typename Visit>
void forEachReading(const RightAngleCorner& corner, const PolarReadings& arm1, const PolarReadings& arm2,
                    Visit&& visit) {
  const PolarReadings* arms[2] = {&arm1, &arm2};
  const double alphas[2] = {corner.alpha, corner.alpha2()};
  const double ds[2] = {corner.d1, corner.d2};
  for (int arm = 0; arm < 2; ++arm) {
    const PolarReadings& r = *arms[arm];
    const double ca = std::cos(alphas[arm]), sa = std::sin(alphas[arm]);
    for (size_t i = 0; i < r.size(); ++i) {
      const double c = ca * r.cos_bearing[i] + sa * r.sin_bearing[i];  // cos(α_k − φ_i)
      const double s = sa * r.cos_bearing[i] - ca * r.sin_bearing[i];  // sin(α_k − φ_i)
      visit(arm, i, alphas[arm], ds[arm], c, s);
    }
  }
}

CornerNormalEquations accumulate(const RightAngleCorner& corner, const PolarReadings& arm1, const PolarReadings& arm2) {
  // Arm-1 rows have no d₂ entry and arm-2 rows no d₁ entry, so HᵀH has a zero (d₁, d₂) element.
  double aa = 0.0, ad1 = 0.0, ad2 = 0.0, d1d1 = 0.0, d2d2 = 0.0, ea = 0.0, ed1 = 0.0, ed2 = 0.0, sse = 0.0;
  double min_cos = 1.0;
  const PolarReadings* arms[2] = {&arm1, &arm2};
  const double alphas[2] = {corner.alpha, corner.alpha2()};
  const double ds[2] = {corner.d1, corner.d2};
  for (int arm = 0; arm < 2; ++arm) {
    const PolarReadings& r = *arms[arm];
    const double ca = std::cos(alphas[arm]), sa = std::sin(alphas[arm]), d = ds[arm];
    double a_d = 0.0, d_d = 0.0, e_d = 0.0;
    for (size_t i = 0; i < r.size(); ++i) {
      const double c = ca * r.cos_bearing[i] + sa * r.sin_bearing[i];  // cos(α_k − φ_i)
      const double s = sa * r.cos_bearing[i] - ca * r.sin_bearing[i];  // sin(α_k − φ_i)
      min_cos = std::min(min_cos, c);
      const double inv = 1.0 / c;
      const double h_alpha = d * s * inv * inv, h_d = inv;
      const double e = r.range[i] - d * inv;  // r_m − r̂
      aa += h_alpha * h_alpha;
      a_d += h_alpha * h_d;
      d_d += h_d * h_d;
      ea += h_alpha * e;
      e_d += h_d * e;
      sse += e * e;
    }
    (arm == 0 ? ad1 : ad2) = a_d;
    (arm == 0 ? d1d1 : d2d2) = d_d;
    (arm == 0 ? ed1 : ed2) = e_d;
  }
  CornerNormalEquations eq;
  eq.hth << aa, ad1, ad2, ad1, d1d1, 0.0, ad2, 0.0, d2d2;
  eq.hte << ea, ed1, ed2;
  eq.sse = sse;
  eq.min_cos = min_cos;
  return eq;
}

bool invertible(const Mat3& m) {
  const double det = m.determinant();
  return std::isfinite(det) && det > 1e-14 * m(0, 0) * m(1, 1) * m(2, 2);
}

/// Mean signed distance of one arm's readings beyond the other arm's line.
double meanBeyond(const PolarReadings& r, const PolarLine& other) {
  const Vec2 n(std::cos(other.alpha), std::sin(other.alpha));
  double sum = 0.0;
  for (size_t i = 0; i < r.size(); ++i) sum += n.dot(r.point(i)) - other.d;
  return r.empty() ? 0.0 : sum / static_cast<double>(r.size());
}

}  // namespace

const char* toString(CornerFitStatus status) {
  switch (status) {
    case CornerFitStatus::Ok: return "ok";
    case CornerFitStatus::TooFewPoints: return "too few points";
    case CornerFitStatus::ArmFitFailed: return "an arm's line fit failed";
    case CornerFitStatus::GrazingBeam: return "beam nearly parallel to an arm";
    case CornerFitStatus::Singular: return "singular normal matrix";
    case CornerFitStatus::Diverged: return "diverged";
  }
  return "?";
}

Vec2 RightAngleCorner::apex() const {
  const double a2 = alpha2();
  return {d1 * std::cos(alpha) + d2 * std::cos(a2), d1 * std::sin(alpha) + d2 * std::sin(a2)};
}

Mat3 RightAngleCorner::observationJacobian() const {
  const double a2 = alpha2();
  Mat3 j = Mat3::Zero();
  j(0, 0) = -d1 * std::sin(alpha) - d2 * std::sin(a2);  // ∂x/∂α
  j(1, 0) = d1 * std::cos(alpha) + d2 * std::cos(a2);   // ∂y/∂α
  j(0, 1) = std::cos(alpha);
  j(1, 1) = std::sin(alpha);
  j(0, 2) = std::cos(a2);
  j(1, 2) = std::sin(a2);
  j(2, 0) = 1.0;  // γ = α + t·π/4 + π
  return j;
}

Mat3 CornerFit::covariance(double range_sigma) const {
  const Mat3 j = corner.observationJacobian();
  return j * parameterCovariance(range_sigma) * j.transpose();
}

RightAngleCorner cornerFromArms(const PolarLine& arm1, const PolarLine& arm2) {
  RightAngleCorner corner;
  corner.turn = wrapAngle(arm2.alpha - arm1.alpha) >= 0.0 ? 1 : -1;
  // Both arms vote for α: arm 2's normal turned back by t·π/2.
  const double from_arm2 = arm2.alpha - corner.turn * std::numbers::pi / 2.0;
  corner.alpha = wrapAngle(arm1.alpha + 0.5 * wrapAngle(from_arm2 - arm1.alpha));
  corner.d1 = arm1.d;
  corner.d2 = arm2.d;
  return corner;
}

CornerFit fitRightAngleCorner(const PolarReadings& arm1, const PolarReadings& arm2, const LineFitOptions& options) {
  CornerFit fit;
  if (arm1.size() < 3 || arm2.size() < 3) return fit;
  const LineFit line1 = fitLinePolar(arm1, options), line2 = fitLinePolar(arm2, options);
  if (!line1.ok() || !line2.ok()) {
    fit.status = CornerFitStatus::ArmFitFailed;
    return fit;
  }
  return fitRightAngleCorner(arm1, arm2, cornerFromArms(line1.line, line2.line), options);
}

CornerFit fitRightAngleCorner(const PolarReadings& arm1, const PolarReadings& arm2, const RightAngleCorner& initial,
                              const LineFitOptions& options) {
  CornerFit fit;
  if (arm1.size() < 2 || arm2.size() < 2 || arm1.size() + arm2.size() < 4) return fit;
  RightAngleCorner corner = initial;
  CornerNormalEquations eq;
  for (fit.iterations = 0; fit.iterations < options.max_iterations && !fit.converged; ++fit.iterations) {
    eq = accumulate(corner, arm1, arm2);
    if (!(eq.min_cos > 0.0)) {
      fit.status = CornerFitStatus::GrazingBeam;
      return fit;
    }
    if (!invertible(eq.hth)) {
      fit.status = CornerFitStatus::Singular;
      return fit;
    }
    const Vec3 step = eq.hth.inverse() * eq.hte;  // (2.22) for (α, d₁, d₂)
    corner.alpha += step(0);                      // (2.23)
    corner.d1 += step(1);
    corner.d2 += step(2);
    fit.converged = std::abs(step(0)) < options.angle_tolerance && std::abs(step(1)) < options.distance_tolerance &&
                    std::abs(step(2)) < options.distance_tolerance;
  }
  if (!std::isfinite(corner.alpha) || !std::isfinite(corner.d1) || !std::isfinite(corner.d2) || corner.d1 <= 0.0 ||
      corner.d2 <= 0.0) {
    fit.status = CornerFitStatus::Diverged;
    return fit;
  }
  corner.alpha = wrapAngle(corner.alpha);
  if (!fit.converged) eq = accumulate(corner, arm1, arm2);  // else the last one is at the solution
  if (eq.min_cos < std::cos(options.max_incidence)) {
    fit.status = CornerFitStatus::GrazingBeam;
    return fit;
  }
  if (!invertible(eq.hth)) {
    fit.status = CornerFitStatus::Singular;
    return fit;
  }
  fit.corner = corner;
  fit.normal_inverse = eq.hth.inverse();
  fit.residual_rms = std::sqrt(eq.sse / static_cast<double>(arm1.size() + arm2.size()));
  fit.convex = meanBeyond(arm1, corner.arm2()) + meanBeyond(arm2, corner.arm1()) > 0.0;
  fit.status = CornerFitStatus::Ok;
  return fit;
}

Mat3 CornerErrorBudget::filterCov(double scale) const {
  const Vec3 s = scale * systematic_bound;
  return randomCov() + Mat3(s.array().square().matrix().asDiagonal());
}

CornerErrorBudget cornerErrorBudget(const CornerFit& fit, const PolarReadings& arm1, const PolarReadings& arm2,
                                    std::span<const double> times1, std::span<const double> times2,
                                    const LaserErrorModel& model, const SensorMotion& motion) {
  CornerErrorBudget b;
  if (!fit.ok()) return b;
  const RightAngleCorner& corner = fit.corner;
  const bool timed = times1.size() == arm1.size() && times2.size() == arm2.size();
  const SensorMotion effective_motion = timed ? motion : SensorMotion{};
  const std::span<const double> times[2] = {times1, times2};
  // Shortest range over the whole corner: the reference of the distance-growing error.
  double r_min = std::numeric_limits<double>::infinity();
  if (model.params().range.growth != 0.0)
    forEachReading(corner, arm1, arm2, [&](int, size_t, double, double d, double c, double) { r_min = std::min(r_min, d / c); });
  RangeErrorSums<3> sums;
  forEachReading(corner, arm1, arm2, [&](int arm, size_t i, double, double d, double c, double s) {
    const PolarReadings& r = arm == 0 ? arm1 : arm2;
    const ReadingGeometry g{d, r.cos_bearing[i], r.sin_bearing[i], c, s, d / c};
    sums.add(cornerRow(corner, arm, c, s),
             readingPerturbations(model, g, r_min, timed ? times[arm][i] : 0.0, effective_motion));
  });
  const Mat3 j = corner.observationJacobian();
  const SourceErrors<3> e = projectSourceErrors<3, 3>(sums, fit.normal_inverse, j, model.params(),
                                                      Vec3(model.params().yaw_error, 0.0, 0.0));
  b.noise_cov = fit.covariance(model.rangeSigma());
  b.scan_bias_cov = e.scanBiasCov(model.params().range.scan_bias_sigma);
  b.systematic_bound = e.bound();
  return b;
}

}  // namespace polarslam
