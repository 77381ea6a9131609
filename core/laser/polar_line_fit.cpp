#include "laser/polar_line_fit.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <numbers>

namespace polarslam {

PolarReadingBuffer::PolarReadingBuffer(std::span<const double> bearings, std::span<const double> ranges) {
  const size_t n = std::min(bearings.size(), ranges.size());
  reserve(n);
  for (size_t i = 0; i < n; ++i) push_back(bearings[i], ranges[i]);
}

void PolarReadingBuffer::clear() {
  bearing_.clear();
  range_.clear();
  cos_.clear();
  sin_.clear();
}

void PolarReadingBuffer::reserve(size_t n) {
  bearing_.reserve(n);
  range_.reserve(n);
  cos_.reserve(n);
  sin_.reserve(n);
}

void PolarReadingBuffer::push_back(double bearing, double range) {
  push_back(bearing, range, std::cos(bearing), std::sin(bearing));
}

void PolarReadingBuffer::push_back(double bearing, double range, double cos_bearing, double sin_bearing) {
  bearing_.push_back(bearing);
  range_.push_back(range);
  cos_.push_back(cos_bearing);
  sin_.push_back(sin_bearing);
}

const char* toString(LineFitStatus status) {
  switch (status) {
    case LineFitStatus::Ok: return "ok";
    case LineFitStatus::TooFewPoints: return "too few points";
    case LineFitStatus::GrazingBeam: return "beam nearly parallel to the line";
    case LineFitStatus::Singular: return "singular normal matrix";
    case LineFitStatus::Diverged: return "diverged";
  }
  return "?";
}

PolarLine fitLineTotalLeastSquares(const PolarReadings& readings) {
  const size_t n = readings.size();
  if (n < 2) return {0.0, std::numeric_limits<double>::quiet_NaN()};
  // One pass of sums, taken relative to the first point to keep the cancellation harmless.
  const Vec2 origin = readings.point(0);
  double sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double x = readings.range[i] * readings.cos_bearing[i] - origin.x();
    const double y = readings.range[i] * readings.sin_bearing[i] - origin.y();
    sx += x;
    sy += y;
    sxx += x * x;
    syy += y * y;
    sxy += x * y;
  }
  const double inv_n = 1.0 / static_cast<double>(n);
  const double mx = sx * inv_n, my = sy * inv_n;
  const double cxx = sxx - sx * mx, cyy = syy - sy * my, cxy = sxy - sx * my;
  // Normal direction = eigenvector of the scatter matrix with the smaller eigenvalue.
  PolarLine line;
  line.alpha = 0.5 * std::atan2(-2.0 * cxy, cyy - cxx);
  line.d = (mx + origin.x()) * std::cos(line.alpha) + (my + origin.y()) * std::sin(line.alpha);
  if (line.d < 0.0) {
    line.d = -line.d;
    line.alpha += std::numbers::pi;
  }
  line.alpha = wrapAngle(line.alpha);
  return line;
}

Vec2 projectOntoLine(const PolarLine& line, const Vec2& point) {
  const Vec2 n(std::cos(line.alpha), std::sin(line.alpha));
  return point - (n.dot(point) - line.d) * n;
}

namespace {

/// Accumulated normal equations of the linearised polar line (2.17) at one estimate.
struct PolarNormalEquations {
  Mat2 hth = Mat2::Zero();    ///< HᵀH
  Vec2 hte = Vec2::Zero();    ///< Hᵀ(r_m − r_j)
  double sse = 0.0;           ///< Σ (r_m − r_j)²
  double min_cos = 1.0;       ///< smallest cos(α − φ_i)
};

PolarNormalEquations accumulate(const PolarReadings& readings, const PolarLine& line) {
  PolarNormalEquations eq;
  const double ca = std::cos(line.alpha), sa = std::sin(line.alpha);
  double haa = 0.0, had = 0.0, hdd = 0.0, ea = 0.0, ed = 0.0, sse = 0.0, min_cos = 1.0;
  for (size_t i = 0; i < readings.size(); ++i) {
    const double c = ca * readings.cos_bearing[i] + sa * readings.sin_bearing[i];  // cos(α − φ_i)
    const double s = sa * readings.cos_bearing[i] - ca * readings.sin_bearing[i];  // sin(α − φ_i)
    min_cos = std::min(min_cos, c);
    const double inv = 1.0 / c;
    const double h_alpha = line.d * s * inv * inv;  // (2.21), first column
    const double h_d = inv;                         // (2.21), second column
    const double e = readings.range[i] - line.d * inv;  // r_m − r_j (2.20)
    haa += h_alpha * h_alpha;
    had += h_alpha * h_d;
    hdd += h_d * h_d;
    ea += h_alpha * e;
    ed += h_d * e;
    sse += e * e;
  }
  eq.hth << haa, had, had, hdd;
  eq.hte << ea, ed;
  eq.sse = sse;
  eq.min_cos = min_cos;
  return eq;
}

bool invertible(const Mat2& m) {
  const double det = m.determinant();
  return std::isfinite(det) && det > 1e-14 * m(0, 0) * m(1, 1);
}

}  // namespace

LineFit fitLinePolar(const PolarReadings& readings, const LineFitOptions& options) {
  const PolarLine initial = fitLineTotalLeastSquares(readings);
  if (!std::isfinite(initial.d)) return LineFit{};
  return fitLinePolar(readings, initial, options);
}

LineFit fitLinePolar(const PolarReadings& readings, const PolarLine& initial, const LineFitOptions& options) {
  LineFit fit;
  if (readings.size() < 3) return fit;
  const double min_cos = std::cos(options.max_incidence);
  PolarLine line = initial;
  PolarNormalEquations eq;
  for (fit.iterations = 0; fit.iterations < options.max_iterations && !fit.converged; ++fit.iterations) {
    eq = accumulate(readings, line);
    if (!(eq.min_cos > 0.0)) {  // a beam misses the line: no valid linearisation
      fit.status = LineFitStatus::GrazingBeam;
      return fit;
    }
    if (!invertible(eq.hth)) {
      fit.status = LineFitStatus::Singular;
      return fit;
    }
    const Vec2 step = eq.hth.inverse() * eq.hte;  // (2.22)
    line.alpha += step.x();                       // (2.23)
    line.d += step.y();
    fit.converged = std::abs(step.x()) < options.angle_tolerance && std::abs(step.y()) < options.distance_tolerance;
  }
  if (!std::isfinite(line.alpha) || !std::isfinite(line.d)) {
    fit.status = LineFitStatus::Diverged;
    return fit;
  }
  if (line.d < 0.0) {
    line.d = -line.d;
    line.alpha += std::numbers::pi;
    fit.converged = false;  // flipped: the last linearisation no longer applies
  }
  line.alpha = wrapAngle(line.alpha);
  // After a negligible last step the last linearisation is the one at the solution.
  if (!fit.converged) eq = accumulate(readings, line);
  if (eq.min_cos < min_cos) {
    fit.status = LineFitStatus::GrazingBeam;
    return fit;
  }
  if (!invertible(eq.hth)) {
    fit.status = LineFitStatus::Singular;
    return fit;
  }
  fit.line = line;
  fit.normal_inverse = eq.hth.inverse();  // (2.25) without σ_r²
  fit.residual_rms = std::sqrt(eq.sse / static_cast<double>(readings.size()));
  fit.status = LineFitStatus::Ok;
  return fit;
}

}  // namespace polarslam
