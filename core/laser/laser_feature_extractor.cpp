#include "laser/laser_feature_extractor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/chi_squared.hpp"

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
  // A degree of margin: the polar fit's α differs slightly from the TLS α it is judged by here.
  const double limit = max_incidence - deg2rad(1.0);
  auto grazing = [&](int i) { return std::abs(wrapAngle(tls.alpha - r.bearing[static_cast<size_t>(i)])) >= limit; };
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

/// The readings a line was finally fitted to (its segment without outliers), and the fit.
struct FittedLine {
  LineFit fit;
  PolarReadingBuffer readings;
  std::vector<double> times;
  std::vector<int> original;  ///< beam index in the scan as received
};

/// Median of `values`, using `scratch` as work space.
double median(const std::vector<double>& values, std::vector<double>& scratch) {
  scratch.assign(values.begin(), values.end());
  const auto mid = scratch.begin() + static_cast<long>(scratch.size() / 2);
  std::nth_element(scratch.begin(), mid, scratch.end());
  return *mid;
}

/// Indices of the readings that do not belong to the line: standardised deleted residuals
/// (e_i − median)/√(1 − h_ii), h_ii the reading's leverage, beyond `outlier_sigmas` robust
/// standard deviations (at least σ_r), and runs of at least `outlier_run_length` consecutive
/// readings beyond `outlier_run_sigmas` on the same side — small objects on a wall (a door jamb,
/// a pillar) shallower than the split threshold, which would otherwise tilt or shift the line.
/// The leverage term keeps a line's end readings, which pull the fit towards themselves, from
/// hiding.
/// `fit` is either a fit to all the readings (deleted residuals, 1 − h_ii) or, with `predictive`,
/// a fit to their central part (prediction residuals, 1 + h_ii): a neighbouring structure's
/// readings at a segment's end tilt a fit to all readings enough to hide themselves.
std::vector<size_t> outliers(const PolarReadings& r, const LineFit& fit, bool predictive, double range_sigma,
                             const LaserFeatureConfig& c) {
  const PolarLine& line = fit.line;
  const double ca = std::cos(line.alpha), sa = std::sin(line.alpha);
  const double sign = predictive ? 1.0 : -1.0;
  std::vector<double> residual(r.size()), leverage_scale(r.size());
  for (size_t i = 0; i < r.size(); ++i) {
    const double cosi = ca * r.cos_bearing[i] + sa * r.sin_bearing[i];
    const double sini = sa * r.cos_bearing[i] - ca * r.sin_bearing[i];
    if (cosi <= 0.0) return {};  // the line does not face this reading: no test
    const Vec2 h = lineRangeJacobian(line, cosi, sini);
    residual[i] = r.range[i] - line.d / cosi;
    leverage_scale[i] = 1.0 / std::sqrt(std::max(1.0 + sign * h.dot(fit.normal_inverse * h), 1e-3));
  }
  std::vector<double> scratch;
  scratch.reserve(r.size());
  const double centre = median(residual, scratch);
  std::vector<double>& deviation = residual;  // in place: (e_i − median)/√(1 ∓ h_ii)
  for (size_t i = 0; i < r.size(); ++i) deviation[i] = (residual[i] - centre) * leverage_scale[i];
  std::vector<double>& magnitude = leverage_scale;  // in place: |deviation|
  for (size_t i = 0; i < r.size(); ++i) magnitude[i] = std::abs(deviation[i]);
  const double scale = std::max(range_sigma, 1.4826 * median(magnitude, scratch));  // MAD → σ for Gaussian noise
  std::vector<bool> bad(r.size(), false);
  for (size_t i = 0; i < r.size(); ++i) bad[i] = magnitude[i] > c.outlier_sigmas * scale;
  // Runs on one side of the line: anywhere, and shorter ones at the segment's ends, where the
  // neighbouring structure's readings end up when the split threshold could not separate them.
  auto runEnd = [&](size_t i, double sigmas) {
    size_t j = i;
    while (j < r.size() && magnitude[j] > sigmas * scale && deviation[j] * deviation[i] > 0.0) ++j;
    return j;  // first reading after the run
  };
  for (size_t i = 0; i < r.size();) {
    const size_t j = runEnd(i, c.outlier_run_sigmas);
    if (static_cast<int>(j - i) >= c.outlier_run_length)
      for (size_t k = i; k < j; ++k) bad[k] = true;
    i = std::max(j, i + 1);
  }
  const size_t head = r.empty() ? 0 : runEnd(0, c.outlier_end_sigmas);
  if (static_cast<int>(head) >= c.outlier_end_run_length)
    for (size_t k = 0; k < head; ++k) bad[k] = true;
  size_t tail = r.size();  // readings tail..n−1 form the run at the far end
  while (tail > 0 && magnitude[tail - 1] > c.outlier_end_sigmas * scale && deviation[tail - 1] * deviation[r.size() - 1] > 0.0)
    --tail;
  if (static_cast<int>(r.size() - tail) >= c.outlier_end_run_length)
    for (size_t k = tail; k < r.size(); ++k) bad[k] = true;
  std::vector<size_t> out;
  for (size_t i = 0; i < r.size(); ++i)
    if (bad[i]) out.push_back(i);
  return out;
}

/// Polar fit of a segment without its outliers. Round 1 judges every reading against a fit to
/// the central 60% of the segment (so that a neighbouring structure's readings at an end cannot
/// hide by tilting the fit); round 2 checks the inliers' own fit. At most `outlier_max_fraction`
/// of the readings go, and at least min_line_points stay. Returns a failed fit when the line
/// does not hold.
FittedLine fitLine(const ValidReadings& v, const LineSegment& s, double range_sigma, const LaserFeatureConfig& c) {
  FittedLine f;
  const PolarReadings r = v.view();
  f.readings.reserve(static_cast<size_t>(s.count()));
  for (int i = s.first; i <= s.last; ++i) {
    const auto k = static_cast<size_t>(i);
    f.readings.push_back(r.bearing[k], r.range[k], r.cos_bearing[k], r.sin_bearing[k]);
    f.times.push_back(v.time[k]);
    f.original.push_back(v.original[k]);
  }
  const size_t n = f.readings.size(), margin = n / 5;
  const bool use_centre = c.outlier_rounds > 0 && n - 2 * margin >= static_cast<size_t>(c.segmentation.min_line_points);
  LineFit reference = use_centre ? fitLinePolar(f.readings.view().sub(margin, n - 2 * margin), c.fit) : LineFit{};
  bool predictive = reference.ok();
  if (!predictive) {
    f.fit = fitLinePolar(f.readings.view(), c.fit);
    reference = f.fit;
  }
  bool fitted = !predictive;  // f.fit holds the fit to f.readings
  for (int round = 0; round < c.outlier_rounds && reference.ok(); ++round) {
    const std::vector<size_t> bad = outliers(f.readings.view(), reference, predictive, range_sigma, c);
    const bool acceptable = !bad.empty() && bad.size() <= c.outlier_max_fraction * static_cast<double>(n) &&
                            static_cast<int>(f.readings.size() - bad.size()) >= c.segmentation.min_line_points;
    if (!acceptable) break;
    FittedLine kept;
    const PolarReadings old = f.readings.view();
    kept.readings.reserve(old.size());
    for (size_t i = 0, b = 0; i < old.size(); ++i) {
      if (b < bad.size() && bad[b] == i) {
        ++b;
        continue;
      }
      kept.readings.push_back(old.bearing[i], old.range[i], old.cos_bearing[i], old.sin_bearing[i]);
      kept.times.push_back(f.times[i]);
      kept.original.push_back(f.original[i]);
    }
    kept.fit = fitLinePolar(kept.readings.view(), reference.line, c.fit);
    if (!kept.fit.ok()) break;
    f = std::move(kept);
    fitted = true;
    reference = f.fit;
    predictive = false;
  }
  if (!fitted) f.fit = fitLinePolar(f.readings.view(), reference.line, c.fit);  // no outliers: fit them all
  return f;
}

LineFeature toLineFeature(const FittedLine& f, const LineErrorBudget& budget, double systematic_scale) {
  LineFeature l;
  l.source = FeatureSource::Laser;
  l.alpha = f.fit.line.alpha;
  l.d = f.fit.line.d;
  l.cov = budget.filterCov(systematic_scale);
  l.random_cov = budget.randomCov();
  l.systematic_bound = budget.systematic_bound;
  const PolarReadings r = f.readings.view();
  l.endpoint_a = projectOntoLine(f.fit.line, r.point(0));
  l.endpoint_b = projectOntoLine(f.fit.line, r.point(r.size() - 1));
  l.num_points = static_cast<int>(r.size());
  l.first_index = std::min(f.original.front(), f.original.back());
  l.last_index = std::max(f.original.front(), f.original.back());
  return l;
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
    : config_(config), model_(config.errors) {
  // Φ(z) = gate  ⇔  P(Z² ≤ z²) = 2·gate − 1.
  if (config_.residual_gate > 0.5 && config_.residual_gate < 1.0)
    gate_z_ = std::sqrt(chiSquaredQuantile(2.0 * config_.residual_gate - 1.0, 1.0));
}

double LaserFeatureExtractor::varianceFactor(double residual_rms, int n, int p) const {
  const double k = n - p;
  if (gate_z_ <= 0.0 || k < 1.0) return 1.0;
  const double sigma = model_.rangeSigma();
  const double chi2 = residual_rms * residual_rms * n / (sigma * sigma);
  const double h = 2.0 / (9.0 * k);
  const double quantile = k * std::pow(1.0 - h + gate_z_ * std::sqrt(h), 3);  // Wilson–Hilferty
  return chi2 > quantile ? chi2 / k : 1.0;
}

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
    const FittedLine line = fitLine(v, s, sigma, config_);
    if (!line.fit.ok()) {
      ++out.num_rejected;
      continue;
    }
    segment_fits[k] = line.fit;
    LineErrorBudget budget = lineErrorBudget(line.fit, line.readings.view(), line.times, model_, motion);
    const double factor = varianceFactor(line.fit.residual_rms, static_cast<int>(line.readings.size()), 2);
    budget.noise_cov *= factor;
    out.lines.push_back(toLineFeature(line, budget, config_.errors.systematic_scale));
    d.line_fits.push_back(line.fit);
    d.line_budgets.push_back(budget);
    d.line_variance_factors.push_back(factor);
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
    // ... and its apex must be where the two arms' readings end: within the gap between their
    // last readings (one beam spacing along each wall), not in the air between two objects.
    const Vec2 apex = best.fit.corner.apex();
    const auto e1 = static_cast<size_t>(best.arm1.last), e2 = static_cast<size_t>(best.arm2.first);
    const double gap = std::abs(r.bearing[e2] - r.bearing[e1]);
    auto nearEnd = [&](size_t e, const PolarLine& arm) {
      const double along_wall = r.range[e] * gap / std::max(std::cos(arm.alpha - r.bearing[e]), 0.2);
      return (apex - r.point(e)).norm() <= along_wall + 3.0 * sigma + config_.corner_junction_distance;
    };
    if (!nearEnd(e1, best.fit.corner.arm1()) || !nearEnd(e2, best.fit.corner.arm2())) continue;

    CornerErrorBudget budget =
        cornerErrorBudget(best.fit, segmentView(r, best.arm1), segmentView(r, best.arm2),
                          segmentTimes(v.time, best.arm1), segmentTimes(v.time, best.arm2), model_, motion);
    budget.noise_cov *= varianceFactor(best.fit.residual_rms, best.arm1.count() + best.arm2.count(), 3);
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
