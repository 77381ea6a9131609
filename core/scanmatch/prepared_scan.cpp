#include "scanmatch/prepared_scan.hpp"

#include "scanmatch/vector_kernels.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace polarslam {
namespace {

constexpr float kNoReturn = std::numeric_limits<float>::infinity();

float median3(float a, float b, float c) { return std::max(std::min(a, b), std::min(std::max(a, b), c)); }

float median5(float a, float b, float c, float d, float e) {
  // The smallest and the largest of a, b, c, d cannot be the median: what is left of them is
  // bounded by the two values below, and the median is that of e and those two. Minima and
  // maxima only, so the filter's loop runs four readings at a time.
  return median3(e, std::max(std::min(a, b), std::min(c, d)), std::min(std::max(a, b), std::max(c, d)));
}

/// Ranges with increasing bearings, optionally decimated, invalid readings as +inf.
void orderedRanges(const LaserScan& scan, int decimation, std::vector<float>& out) {
  const size_t n = scan.ranges.size();
  const size_t step = static_cast<size_t>(std::max(1, decimation));
  out.resize((n + step - 1) / step);
  const bool reversed = scan.angle_increment < 0.0;
  for (size_t k = 0; k < out.size(); ++k) {
    const float r = scan.ranges[reversed ? n - 1 - k * step : k * step];
    out[k] = std::isfinite(r) && r > 0.0f && r < scan.range_max ? r : kNoReturn;
  }
}

/// Direction of the segment from point i-1 to point i, folded to [0, π).
double foldedDirection(double dx, double dy) {
  double a = fastAtan2(dy, dx);
  if (a < 0.0) a += std::numbers::pi;
  if (a >= std::numbers::pi) a -= std::numbers::pi;
  return a;
}

double foldAngle(double a) {
  // The usual case, an angle in [0, 2π), without fmod (a tenth of a microsecond each): for a in
  // [π, 2π) the subtraction is exact (Sterbenz), so the result is fmod's.
  if (a >= 0.0 && a < 2.0 * std::numbers::pi) return a >= std::numbers::pi ? a - std::numbers::pi : a;
  a = std::fmod(a, std::numbers::pi);
  return a < 0.0 ? a + std::numbers::pi : a;
}

/// Std of the running 3-median of the angles (§11.2 part 2).
double smoothedSpread(const std::vector<double>& angles, std::vector<double>& smoothed) {
  const size_t n = angles.size();
  smoothed.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (i == 0 || i + 1 == n) {
      smoothed[i] = angles[i];
      continue;
    }
    const double a = angles[i - 1], b = angles[i], c = angles[i + 1];
    smoothed[i] = std::max(std::min(a, b), std::min(std::max(a, b), c));
  }
  double mean = 0.0;
  for (double a : smoothed) mean += a;
  mean /= static_cast<double>(n);
  double var = 0.0;
  for (double a : smoothed) var += (a - mean) * (a - mean);
  return std::sqrt(var / static_cast<double>(n));
}

/// Mean of the directions within ±5° of the fullest 2° bin, averaged across the 0/π wrap (§11.2 part 3).
double corridorDirection(const std::vector<double>& angles) {
  constexpr int kBins = 90;
  const double bin_width = std::numbers::pi / kBins;
  std::array<int, kBins> histogram{};
  for (double a : angles) ++histogram[std::min(kBins - 1, static_cast<int>(a / bin_width))];
  const int peak = static_cast<int>(std::max_element(histogram.begin(), histogram.end()) - histogram.begin());
  const double centre = (peak + 0.5) * bin_width;
  double sum = 0.0;
  int count = 0;
  for (double a : angles) {
    double d = a - centre;  // nearest representative of a modulo π
    if (d > std::numbers::pi / 2) d -= std::numbers::pi;
    if (d < -std::numbers::pi / 2) d += std::numbers::pi;
    if (std::abs(d) <= deg2rad(5.0)) {
      sum += d;
      ++count;
    }
  }
  return foldAngle(centre + (count > 0 ? sum / count : 0.0));
}

/// Slope of the range profile, dr/dj, at each reading inside a segment: a least-squares line
/// through readings i−k…i+k of its segment (σ_slope = σ_r·√(3/(k(k+1)(2k+1))) per beam), k at
/// least 2 and covering `half_span` of arc, at most 12, fewer at segment ends; NaN at the ends.
/// Noisy slopes would give the matcher information it does not have, e.g. along a corridor.
void fitSlopes(PreparedScan& out, double half_span, double increment, VectorKernels kernels) {
  const size_t n = out.size();
  out.slope.assign(n, std::numeric_limits<float>::quiet_NaN());
  out.slope_variance.assign(n, std::numeric_limits<float>::quiet_NaN());
  if (n < 3) return;
  auto same = [&](size_t a, size_t b) { return out.segment[a] != 0 && out.segment[a] == out.segment[b]; };
  // Prefix sums of r and j·r: the slope over a symmetric window is then one difference. Scratch
  // space kept per thread: a scan's preparation then allocates only what it returns.
  thread_local std::vector<double> sum_r, sum_jr, moment, denominator;
  thread_local std::vector<int> left, right;  // readings of the same segment before and after
  sum_r.assign(n + 1, 0.0);
  sum_jr.assign(n + 1, 0.0);
  moment.assign(n, 0.0);
  denominator.assign(n, 0.0);  // 0: no slope
  left.assign(n, 0);
  right.assign(n, 0);
  // The running values stay in registers (through the arrays, each step would wait for the
  // previous one's store).
  double running_r = 0.0, running_jr = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double r = out.segment[i] != 0 ? out.range[i] : 0.0;
    running_r += r;
    running_jr += static_cast<double>(i) * r;
    sum_r[i + 1] = running_r;
    sum_jr[i + 1] = running_jr;
  }
  for (int i = 1, run = 0; i < static_cast<int>(n); ++i) left[i] = run = same(i, i - 1) ? run + 1 : 0;
  for (int i = static_cast<int>(n) - 2, run = 0; i >= 0; --i) right[i] = run = same(i, i + 1) ? run + 1 : 0;
  constexpr int kMinHalf = 2, kMaxHalf = 12;
  std::array<double, kMaxHalf + 1> sum_j2{};  // Σ j² over −k…k
  std::array<float, kMaxHalf + 1> slope_variance{};
  for (int k = 1; k <= kMaxHalf; ++k) {
    const double kd = k;
    sum_j2[static_cast<size_t>(k)] = kd * (kd + 1.0) * (2.0 * kd + 1.0) / 3.0;
    slope_variance[static_cast<size_t>(k)] = static_cast<float>(1.0 / sum_j2[static_cast<size_t>(k)]);
  }
  for (size_t i = 1; i + 1 < n; ++i) {
    int wanted = kMinHalf;
    if (half_span != 0.0) {
      const double arc = out.range[i] * increment;
      wanted = static_cast<int>(std::clamp(arc > 0.0 ? std::round(half_span / arc) : 0.0, double{kMinHalf}, double{kMaxHalf}));
    }
    const int k = std::min({wanted, left[i], right[i]});
    if (k < 1) continue;
    const size_t a = i - static_cast<size_t>(k), b = i + static_cast<size_t>(k) + 1;
    moment[i] = (sum_jr[b] - sum_jr[a]) - static_cast<double>(i) * (sum_r[b] - sum_r[a]);
    denominator[i] = sum_j2[static_cast<size_t>(k)];
    out.slope_variance[i] = slope_variance[static_cast<size_t>(k)];
  }
  detail::divideSlopes(moment.data(), denominator.data(), n, out.slope.data(), kernels);
}

/// What PSM's joint system needs of the reference alone, so that each match iteration only adds
/// the pose-dependent part; NaN where a bearing is unusable.
void computeSurfaceTerms(PreparedScan& scan, VectorKernels kernels) {
  const size_t n = scan.size();
  const BeamGeometry& g = *scan.geometry;
  auto& s = scan.surface;
  auto terms = {&s.rho, &s.cos_beta, &s.normal_x, &s.normal_y, &s.rho_cos_beta, &s.beta_variance};
  for (auto* v : terms) v->resize((n + 3) / 4 * 4);  // whole blocks; the spare entries are cut off below
  detail::surfaceTerms({scan.slope.data(), scan.range.data(), scan.slope_variance.data(), g.cos_table.data(),
                        g.sin_table.data(), scan.flags.data(), n, g.angle_increment},
                       {s.rho.data(), s.cos_beta.data(), s.normal_x.data(), s.normal_y.data(), s.rho_cos_beta.data(),
                        s.beta_variance.data()},
                       kernels);
  for (auto* v : terms) v->resize(n);
}

}  // namespace

void medianFilter5(const std::vector<float>& in, std::vector<float>& out) {
  const size_t n = in.size();
  out.resize(n);
  if (n == 0) return;
  auto at = [&](std::ptrdiff_t i) { return in[static_cast<size_t>(std::clamp<std::ptrdiff_t>(i, 0, static_cast<std::ptrdiff_t>(n) - 1))]; };
  auto clamped = [&](size_t k) {
    const auto i = static_cast<std::ptrdiff_t>(k);
    out[k] = median5(at(i - 2), at(i - 1), at(i), at(i + 1), at(i + 2));
  };
  for (size_t k = 0; k < std::min<size_t>(2, n); ++k) clamped(k);
  const float* p = in.data();
  for (size_t k = 2; k + 2 < n; ++k) out[k] = median5(p[k - 2], p[k - 1], p[k], p[k + 1], p[k + 2]);
  for (size_t k = std::max<size_t>(2, n >= 2 ? n - 2 : 0); k < n; ++k) clamped(k);
}

void segmentScan(const std::vector<float>& range, const std::vector<uint8_t>& flags, double max_distance,
                 std::vector<int32_t>& segment) {
  const size_t n = range.size();
  segment.assign(n, 0);
  int32_t current = 0, next_id = 1;  // current = 0: no segment open
  int count = 0;
  auto closeLone = [&](size_t last) {  // a segment of one reading is an isolated point
    if (count == 1) segment[last] = 0;
  };
  for (size_t i = 0; i < n; ++i) {
    if (flags[i]) {  // a bad reading breaks the segment; the next good one opens a new one
      if (current != 0 && i > 0) closeLone(i - 1);
      current = 0;
      count = 0;
      continue;
    }
    if (current == 0) {
      current = next_id++;
      segment[i] = current;
      count = 1;
      continue;
    }
    const double step = std::abs(static_cast<double>(range[i]) - range[i - 1]);
    const bool have_two = i >= 2 && !flags[i - 2];
    const double extrapolation_error =
        have_two ? std::abs(static_cast<double>(range[i]) - (2.0 * range[i - 1] - range[i - 2])) : kNoReturn;
    // The extrapolation test keeps walls seen at grazing incidence in one piece.
    const bool stays = step < max_distance ||
                       (have_two && segment[i - 2] != 0 && segment[i - 1] == segment[i - 2] &&
                        extrapolation_error < max_distance);
    if (stays) {
      segment[i] = current;
      ++count;
    } else if (count == 1) {
      if (have_two && segment[i - 2] == 0 && extrapolation_error < max_distance) {
        // three collinear readings "by coincidence": keep them together
        segment[i - 2] = segment[i - 1] = segment[i] = current;
        count = 3;
      } else {
        segment[i - 1] = 0;
        segment[i] = current;
        count = 1;
      }
    } else {
      current = next_id++;
      segment[i] = current;
      count = 1;
    }
  }
  if (current != 0 && n > 0) closeLone(n - 1);
}

CorridorInfo detectCorridor(const PreparedScan& scan, double threshold) {
  std::vector<double> angles;
  angles.reserve(scan.size());
  for (size_t i = 1; i < scan.size(); ++i)
    if (scan.segment[i] != 0 && scan.segment[i] == scan.segment[i - 1] && !scan.bad(i) && !scan.bad(i - 1))
      angles.push_back(foldedDirection(scan.x[i] - scan.x[i - 1], scan.y[i] - scan.y[i - 1]));
  CorridorInfo info;
  if (angles.size() < 3) return info;
  std::vector<double> smoothed, rotated(angles.size());
  const double spread0 = smoothedSpread(angles, smoothed);
  // Second pass rotated by 36° so that a corridor near 0°/180° is not split by the fold.
  for (size_t i = 0; i < angles.size(); ++i) rotated[i] = foldAngle(angles[i] + std::numbers::pi / 5.0);
  const double spread1 = smoothedSpread(rotated, smoothed);
  info.spread = std::min(spread0, spread1);
  info.is_corridor = info.spread < threshold;
  info.angle = corridorDirection(angles);
  return info;
}

PreparedScan prepareScan(const LaserScan& scan, const PsmParams& params) {
  const std::string why = validateScan(scan);
  if (!why.empty()) throw std::invalid_argument("prepareScan: " + why);
  PreparedScan out;
  out.utime = scan.utime;
  const int step = std::max(1, params.decimation);
  thread_local std::vector<float> raw;
  orderedRanges(scan, step, params.median_filter ? raw : out.range);
  const size_t n = params.median_filter ? raw.size() : out.range.size();
  const double increment = std::abs(scan.angle_increment) * step;
  const double first = scan.angle_increment < 0.0 ? scan.bearing(scan.size() - 1) : scan.angle_min;
  out.geometry = beamGeometry(n, first, increment);

  if (params.median_filter) {
    medianFilter5(raw, out.range);
    if (params.median_replace_threshold > 0.0)
      for (size_t i = 0; i < n; ++i)
        if (!(std::abs(out.range[i] - raw[i]) > params.median_replace_threshold)) out.range[i] = raw[i];
  }

  out.flags.assign(n, 0);
  out.x.assign(n, 0.0);
  out.y.assign(n, 0.0);
  out.masked_range.assign(n, 0.0f);
  out.mask.assign(n, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    const float r = out.range[i];
    if (!(r <= params.max_range) || r < params.min_range) {
      out.flags[i] = kFlagRange;
      continue;
    }
    out.x[i] = r * out.geometry->cos_table[i];
    out.y[i] = r * out.geometry->sin_table[i];
    out.masked_range[i] = r;
    out.mask[i] = 1.0f;
    ++out.valid_count;
  }
  const size_t padded = (n + kSimdWidth - 1) / kSimdWidth * kSimdWidth;
  out.xf.assign(padded, 0.0f);
  out.yf.assign(padded, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    out.xf[i] = static_cast<float>(out.x[i]);
    out.yf[i] = static_cast<float>(out.y[i]);
  }
  segmentScan(out.range, out.flags, params.segment_max_distance, out.segment);
  out.pair_mask.assign(padded, 0);
  for (size_t i = 1; i < n; ++i)
    if (out.segment[i] != 0 && out.segment[i] == out.segment[i - 1]) out.pair_mask[i] = -1;
  static const VectorKernels kernels = widestVectorKernels();
  fitSlopes(out, params.slope_half_span, increment, kernels);
  computeSurfaceTerms(out, kernels);
  return out;
}

}  // namespace polarslam
