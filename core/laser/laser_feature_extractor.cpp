#include "laser/laser_feature_extractor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace polarslam {
namespace {

/// The valid readings of a normalised scan with their beam index and time after beam 0.
struct ValidReadings {
  PolarReadingBuffer buffer;
  std::vector<int> beam;        ///< index in the normalised scan
  std::vector<int> original;    ///< index in the scan as received
  std::vector<double> time;     ///< s after the scan's utime

  PolarReadings view() const { return buffer.view(); }
};

ValidReadings validReadings(const LaserScan& scan) {
  const LaserScan norm = normalizedScan(scan);
  const bool reversed = scan.angle_increment < 0.0;
  const int n = static_cast<int>(norm.size());
  ValidReadings v;
  v.buffer.reserve(norm.size());
  v.beam.reserve(norm.size());
  v.original.reserve(norm.size());
  v.time.reserve(norm.size());
  // cos/sin of the bearings by rotation, re-seeded exactly every 32 beams.
  const double step_cos = std::cos(norm.angle_increment), step_sin = std::sin(norm.angle_increment);
  double c = 1.0, s = 0.0;
  for (int i = 0; i < n; ++i) {
    const double bearing = norm.bearing(static_cast<size_t>(i));
    if (i % 32 == 0) {
      c = std::cos(bearing);
      s = std::sin(bearing);
    } else {
      const double next_c = c * step_cos - s * step_sin;
      s = s * step_cos + c * step_sin;
      c = next_c;
    }
    if (!norm.valid(static_cast<size_t>(i))) continue;
    const int original = reversed ? n - 1 - i : i;
    v.buffer.push_back(bearing, norm.ranges[static_cast<size_t>(i)], c, s);
    v.beam.push_back(i);
    v.original.push_back(original);
    v.time.push_back(original * scan.time_increment);
  }
  return v;
}

/// Drops readings at either end of [first, last] that meet the line (from TLS) at an incidence
/// beyond max_incidence: a wall seen nearly edge-on keeps its well-observed part.
LineSegment trimGrazingEnds(const PolarReadings& r, LineSegment s, double max_incidence) {
  const PolarLine tls = fitLineTotalLeastSquares(r.sub(static_cast<size_t>(s.first), static_cast<size_t>(s.count())));
  if (!std::isfinite(tls.d)) return s;
  auto grazing = [&](int i) { return std::abs(wrapAngle(tls.alpha - r.bearing[static_cast<size_t>(i)])) >= max_incidence; };
  while (s.count() > 0 && grazing(s.first)) ++s.first;
  while (s.count() > 0 && grazing(s.last)) --s.last;
  return s;
}

PolarReadings segmentView(const PolarReadings& r, const LineSegment& s) {
  return r.sub(static_cast<size_t>(s.first), static_cast<size_t>(s.count()));
}
std::span<const double> segmentTimes(const std::vector<double>& t, const LineSegment& s) {
  return std::span<const double>(t).subspan(static_cast<size_t>(s.first), static_cast<size_t>(s.count()));
}

LineFeature toLineFeature(const LineFit& fit, const LineErrorBudget& budget, const ValidReadings& v,
                          const LineSegment& s, double systematic_scale) {
  LineFeature f;
  f.source = FeatureSource::Laser;
  f.alpha = fit.line.alpha;
  f.d = fit.line.d;
  f.cov = budget.filterCov(systematic_scale);
  f.random_cov = budget.randomCov();
  f.systematic_bound = budget.systematic_bound;
  const PolarReadings r = v.view();
  f.endpoint_a = projectOntoLine(fit.line, r.point(static_cast<size_t>(s.first)));
  f.endpoint_b = projectOntoLine(fit.line, r.point(static_cast<size_t>(s.last)));
  f.num_points = s.count();
  const int a = v.original[static_cast<size_t>(s.first)], b = v.original[static_cast<size_t>(s.last)];
  f.first_index = std::min(a, b);
  f.last_index = std::max(a, b);
  return f;
}

struct CornerAttempt {
  CornerFit fit;
  LineSegment arm1, arm2;
};

/// Squared range residual of reading i against a line; +∞ when the beam misses the line.
double squaredResidual(const PolarReadings& r, size_t i, const PolarLine& line) {
  const double c = std::cos(line.alpha - r.bearing[i]);
  if (c <= 0.0) return std::numeric_limits<double>::infinity();
  const double e = r.range[i] - line.d / c;
  return e * e;
}

/// Last reading of arm 1 within ±search of the current junction (a.last) that minimises the
/// corner's squared residuals when the readings up to it belong to arm 1 and the rest to arm 2.
int bestJunction(const PolarReadings& r, const RightAngleCorner& corner, const LineSegment& a, const LineSegment& b,
                 int search) {
  const int lo = std::max(a.last - search, a.first + 2), hi = std::min(a.last + search, b.last - 3);
  if (search <= 0 || lo > hi) return a.last;
  const PolarLine arm1 = corner.arm1(), arm2 = corner.arm2();
  // cost(k) = Σ_{lo<j≤k} e₁(j)² + Σ_{k<j≤hi+1} e₂(j)², evaluated over the window only.
  int best = a.last;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int k = lo; k <= hi; ++k) {
    double cost = 0.0;
    for (int j = lo + 1; j <= hi + 1; ++j)
      cost += j <= k ? squaredResidual(r, static_cast<size_t>(j), arm1) : squaredResidual(r, static_cast<size_t>(j), arm2);
    if (cost < best_cost) {
      best_cost = cost;
      best = k;
    }
  }
  return best;
}

}  // namespace

LaserFeatureExtractor::LaserFeatureExtractor(const LaserFeatureConfig& config)
    : config_(config), model_(config.errors) {}

FeatureSet LaserFeatureExtractor::extract(const LaserScan& scan, std::span<const double> break_bearings,
                                          const SensorMotion& motion, ExtractionDetails* details) const {
  FeatureSet out;
  out.utime = scan.utime;
  out.seq = scan.seq;
  out.frame = "laser";
  out.sensor_pose = scan.laser_pose;
  if (!validateScan(scan).empty()) return out;

  const ValidReadings v = validReadings(scan);
  const PolarReadings r = v.view();
  const double sigma = model_.rangeSigma();
  const Segmentation segmentation = segmentReadings(r, v.beam, break_bearings, sigma, config_.segmentation);
  ExtractionDetails local;
  ExtractionDetails& d = details ? *details : local;
  d = ExtractionDetails{};
  d.valid_readings = static_cast<int>(r.size());
  d.segmentation = segmentation;

  // Lines.
  std::vector<LineFit> segment_fits(segmentation.lines.size());
  for (size_t k = 0; k < segmentation.lines.size(); ++k) {
    const LineSegment s = trimGrazingEnds(r, segmentation.lines[k], config_.fit.max_incidence);
    if (s.count() < config_.segmentation.min_line_points) {
      ++out.num_rejected;
      continue;
    }
    const LineFit fit = fitLinePolar(segmentView(r, s), config_.fit);
    if (!fit.ok()) {
      ++out.num_rejected;
      continue;
    }
    segment_fits[k] = fit;
    const LineErrorBudget budget = lineErrorBudget(fit, segmentView(r, s), segmentTimes(v.time, s), model_, motion);
    out.lines.push_back(toLineFeature(fit, budget, v, s, config_.errors.systematic_scale));
    d.line_fits.push_back(fit);
    d.line_budgets.push_back(budget);
  }
  if (!config_.corners) return out;

  // Corners: perpendicular neighbours, with the junction moved to the best-fitting reading.
  for (const CornerCandidate& c : segmentation.corners) {
    const LineSegment a = segmentation.lines[static_cast<size_t>(c.first)];
    const LineSegment b = segmentation.lines[static_cast<size_t>(c.second)];
    const bool contiguous = a.last + 1 == b.first;
    const int search = contiguous ? config_.corner_split_search : 0;
    const LineFit& fit_a = segment_fits[static_cast<size_t>(c.first)];
    const LineFit& fit_b = segment_fits[static_cast<size_t>(c.second)];
    const PolarLine line_a = fit_a.ok() ? fit_a.line : fitLineTotalLeastSquares(segmentView(r, a));
    const PolarLine line_b = fit_b.ok() ? fit_b.line : fitLineTotalLeastSquares(segmentView(r, b));
    if (!std::isfinite(line_a.d) || !std::isfinite(line_b.d)) continue;
    const RightAngleCorner initial = cornerFromArms(line_a, line_b);
    CornerAttempt best{fitRightAngleCorner(segmentView(r, a), segmentView(r, b), initial, config_.fit), a, b};
    if (!best.fit.ok()) continue;
    const int junction = bestJunction(r, best.fit.corner, a, b, search);
    if (junction != a.last) {
      const LineSegment arm1{a.first, junction}, arm2{junction + 1, b.last};
      const CornerFit moved = fitRightAngleCorner(segmentView(r, arm1), segmentView(r, arm2), best.fit.corner, config_.fit);
      if (moved.ok()) best = {moved, arm1, arm2};
    }
    if (!best.fit.ok()) continue;
    // A right angle must explain the readings about as well as two free lines do ...
    double arm_rms = sigma;
    for (const LineFit* f : {&fit_a, &fit_b})
      if (f->ok()) arm_rms = std::max(arm_rms, f->residual_rms);
    if (best.fit.residual_rms > config_.corner_max_rms_ratio * arm_rms) continue;
    // ... and its apex must be where the two arms meet.
    const Vec2 apex = best.fit.corner.apex();
    const Vec2 end1 = r.point(static_cast<size_t>(best.arm1.last)), end2 = r.point(static_cast<size_t>(best.arm2.first));
    const double spacing = std::abs(r.bearing[static_cast<size_t>(best.arm2.first)] - r.bearing[static_cast<size_t>(best.arm1.last)]);
    const double tolerance = config_.corner_junction_distance + 3.0 * sigma + 2.0 * apex.norm() * spacing;
    if ((apex - end1).norm() > tolerance || (apex - end2).norm() > tolerance) continue;

    const CornerErrorBudget budget =
        cornerErrorBudget(best.fit, segmentView(r, best.arm1), segmentView(r, best.arm2),
                          segmentTimes(v.time, best.arm1), segmentTimes(v.time, best.arm2), model_, motion);
    CornerFeature f;
    f.source = FeatureSource::Laser;
    f.convex = best.fit.convex;
    f.x = apex.x();
    f.y = apex.y();
    f.gamma = best.fit.corner.gamma();
    f.cov = budget.filterCov(config_.errors.systematic_scale);
    f.num_points = best.arm1.count() + best.arm2.count();
    out.corners.push_back(f);
    d.corner_fits.push_back(best.fit);
    d.corner_budgets.push_back(budget);
  }
  return out;
}

}  // namespace polarslam
