// bench_features: the laser line and corner error model checked and timed (thesis chapter 2,
// docs/algorithms.md §19.1). Run by scripts/bench-features.
//  1. Monte Carlo: empirical std of the fitted (α, d) over noisy scans / predicted σ_r²(HᵀH)⁻¹.
//  2. Each systematic-error formula / the simulated error of its source alone.
//  3. Per-scan bias covariance (A.21) and the corner covariance / Monte Carlo.
//  4. Polar fit vs Cartesian total least squares on the same points (RMSE).
//  5. Fit throughput (100-point lines) and the median time to extract the features of one
//     361-beam scan (goal: under 100 µs on one core).
//  6. Real scans of the MIT CSAIL log (../shared/data/mit-csail/mit-csail.clf) when present:
//     features per scan and range residual RMS.
#include <CLI/CLI.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "laser/corner_fit.hpp"
#include "laser/laser_feature_extractor.hpp"
#include "laser/line_errors.hpp"
#include "unit/laser/synthetic_scans.hpp"

using namespace polarslam;

namespace {

struct LineCase {
  double alpha_deg, d, offset_deg, extent_deg, step_deg;
  PolarLine line() const { return {deg2rad(alpha_deg), d}; }
  std::vector<double> bearings() const {
    const double centre = deg2rad(alpha_deg + offset_deg);
    const int n = static_cast<int>(std::round(extent_deg / step_deg)) + 1;
    return synthetic::bearings(centre - deg2rad(extent_deg) / 2, centre + deg2rad(extent_deg) / 2, n);
  }
};

const std::vector<LineCase> kLines = {
    {90, 0.5, 0, 90, 1},   {30, 0.5, 40, 60, 0.5},  {-60, 1.0, -20, 40, 1}, {0, 1.0, 0, 120, 0.5},
    {0, 2.0, 0, 20, 0.5},  {170, 2.0, 50, 40, 1},   {-120, 4.0, 10, 10, 0.5}, {45, 4.0, -60, 20, 1},
    {100, 8.0, 0, 5, 0.25}, {-10, 8.0, 30, 15, 0.5},
};

Vec2 fitError(const PolarLine& truth, const std::vector<double>& b, const std::vector<double>& r) {
  const PolarReadingBuffer readings(b, r);
  const LineFit fit = fitLinePolar(readings.view());
  return {wrapAngle(fit.line.alpha - truth.alpha), fit.line.d - truth.d};
}

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

std::string ratioText(double predicted, double simulated) {
  if (std::abs(simulated) < 1e-12) return std::abs(predicted) < 1e-12 ? "   (0)" : "     -";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%6.3f", predicted / simulated);
  return buf;
}

void randomCovariance(int trials) {
  std::printf("\n== 1. Random covariance sigma_r^2 (H^T H)^-1 (2.25) vs Monte Carlo: %d scans each, sigma_r = 1 cm ==\n", trials);
  std::printf("%6s %7s %7s %7s %4s | %12s %12s | %12s %12s\n", "d[m]", "alpha", "offset", "extent", "n",
              "std_a pred", "emp/pred", "std_d pred", "emp/pred");
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 0.01);
  double worst = 0.0;
  for (const LineCase& c : kLines) {
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    std::vector<double> r(b.size());
    Vec2 sum = Vec2::Zero(), sq = Vec2::Zero();
    Mat2 predicted = Mat2::Zero();
    for (int t = 0; t < trials; ++t) {
      for (size_t i = 0; i < b.size(); ++i) r[i] = exact[i] + noise(rng);
      const PolarReadingBuffer readings(b, r);
      const LineFit fit = fitLinePolar(readings.view());
      const Vec2 e(wrapAngle(fit.line.alpha - c.line().alpha), fit.line.d - c.d);
      sum += e;
      sq += e.cwiseProduct(e);
      predicted += fit.covariance(0.01) / trials;
    }
    const Vec2 mean = sum / trials;
    const Vec2 std_emp = ((sq - trials * mean.cwiseProduct(mean)) / (trials - 1)).cwiseSqrt();
    const Vec2 std_pred = predicted.diagonal().cwiseSqrt();
    const Vec2 ratio = std_emp.cwiseQuotient(std_pred);
    worst = std::max(worst, (ratio.array() - 1.0).abs().maxCoeff());
    std::printf("%6.2f %7.1f %7.1f %7.1f %4zu | %12.3e %12.3f | %12.3e %12.3f\n", c.d, c.alpha_deg, c.offset_deg,
                c.extent_deg, b.size(), std_pred.x(), ratio.x(), std_pred.y(), ratio.y());
  }
  std::printf("largest |ratio - 1| = %.3f (test tolerance 0.10)\n", worst);
}

/// Exact tilted-plane geometry for the misalignment check.
double tiltedRange(const PolarLine& wall, double bearing, double tilt, double axis) {
  const Eigen::Vector3d beam = Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis), std::sin(axis), 0.0)) *
                               Eigen::Vector3d(std::cos(bearing), std::sin(bearing), 0.0);
  return wall.d / Eigen::Vector3d(std::cos(wall.alpha), std::sin(wall.alpha), 0.0).dot(beam);
}

void systematicErrors() {
  std::printf("\n== 2. Systematic errors: formula / simulation with only that source on (alpha, d ratios) ==\n");
  std::printf("%-34s", "source / formula");
  for (const LineCase& c : kLines) std::printf(" | d%.1f e%-3.0f", c.d, c.extent_deg);
  std::printf("\n");
  struct Source {
    const char* name;
    std::function<double(const LineCase&, double bearing, double range, double r_min, double time)> perturb;
    std::function<Vec2(const LineCase&, const PolarReadings&, std::span<const double> times)> formula;
  };
  const SensorMotion motion{0.8, 0.2, -1.0};
  const std::vector<Source> sources = {
      {"fixed bias 1cm (2.33),(2.35)", [](const LineCase&, double, double, double, double) { return 0.01; },
       [](const LineCase& c, const PolarReadings& r, auto) { return fixedBiasLineError(c.line(), r, 0.01); }},
      {"fixed bias 1cm general (A.29)", [](const LineCase&, double, double, double, double) { return 0.01; },
       [](const LineCase& c, const PolarReadings& r, auto) { return fixedBiasLineErrorGeneral(c.line(), r, 0.01); }},
      {"incidence w=1cm closed (A.45)", [](const LineCase& c, double b, double, double, double) {
         return incidenceAnglePerturbation(c.line().alpha, b, 0.01, 1.5); },
       [](const LineCase& c, const PolarReadings& r, auto) { return incidenceAngleLineErrorClosedForm(c.line(), r, 0.01); }},
      {"incidence w=1cm numeric (A.29)", [](const LineCase& c, double b, double, double, double) {
         return incidenceAnglePerturbation(c.line().alpha, b, 0.01, 1.5); },
       [](const LineCase& c, const PolarReadings& r, auto) { return incidenceAngleLineError(c.line(), r, 0.01, 1.5); }},
      {"growth k=0.01 closed (A.61)", [](const LineCase&, double, double range, double r_min, double) {
         return 0.01 * (range - r_min); },
       [](const LineCase& c, const PolarReadings& r, auto) { return distanceGrowthLineErrorClosedForm(c.line(), r, 0.01); }},
      {"growth k=0.01 numeric (A.29)", [](const LineCase&, double, double range, double r_min, double) {
         return 0.01 * (range - r_min); },
       [](const LineCase& c, const PolarReadings& r, auto) { return distanceGrowthLineError(c.line(), r, 0.01); }},
      {"quantisation b=3mm q=1cm", [](const LineCase&, double, double range, double, double) {
         return quantizationPerturbation(range, 0.01, 0.003); },
       [](const LineCase& c, const PolarReadings& r, auto) { return quantizationLineError(c.line(), r, 0.01, 0.003); }},
      {"tilt 2deg axis 37deg (exact 3D)", [](const LineCase& c, double b, double range, double, double) {
         return tiltedRange(c.line(), b, deg2rad(2.0), deg2rad(37.0)) - range; },
       [](const LineCase& c, const PolarReadings& r, auto) {
         return planeTiltLineError(c.line(), r, deg2rad(2.0), deg2rad(37.0)); }},
  };
  for (const Source& s : sources) {
    std::printf("%-34s", s.name);
    for (const LineCase& c : kLines) {
      const std::vector<double> b = c.bearings();
      const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
      const double r_min = *std::min_element(exact.begin(), exact.end());
      std::vector<double> ranges = exact;
      for (size_t i = 0; i < b.size(); ++i) ranges[i] += s.perturb(c, b[i], exact[i], r_min, 0.0);
      const Vec2 simulated = fitError(c.line(), b, ranges);
      const PolarReadingBuffer readings(b, exact);
      const Vec2 predicted = s.formula(c, readings.view(), {});
      std::printf(" | %s %s", ratioText(predicted.x(), simulated.x()).c_str() + 1, ratioText(predicted.y(), simulated.y()).c_str() + 1);
    }
    std::printf("\n");
  }
  // Motion: exact constant-twist motion, 0.1 ms per beam.
  std::printf("%-34s", "motion 0.8,0.2 m/s -1 rad/s");
  for (const LineCase& c : kLines) {
    const std::vector<double> b = c.bearings();
    std::vector<double> times(b.size()), ranges(b.size());
    for (size_t i = 0; i < b.size(); ++i) {
      times[i] = 1e-4 * static_cast<double>(i);
      const double turn = motion.omega * times[i];
      const double sa = std::abs(turn) < 1e-12 ? 1.0 : std::sin(turn) / turn;
      const double ca = std::abs(turn) < 1e-12 ? 0.0 : (1.0 - std::cos(turn)) / turn;
      const double px = times[i] * (sa * motion.vx - ca * motion.vy), py = times[i] * (ca * motion.vx + sa * motion.vy);
      const PolarLine seen{c.line().alpha - turn, c.d - std::cos(c.line().alpha) * px - std::sin(c.line().alpha) * py};
      ranges[i] = lineRange(seen, b[i]);
    }
    const Vec2 simulated = fitError(c.line(), b, ranges);
    const PolarReadingBuffer readings(b, synthetic::lineRanges(c.line(), b));
    const Vec2 predicted = motionLineError(c.line(), readings.view(), times, motion);
    std::printf(" | %s %s", ratioText(predicted.x(), simulated.x()).c_str() + 1, ratioText(predicted.y(), simulated.y()).c_str() + 1);
  }
  std::printf("\n(0) = zero by symmetry in both. (2.33)/(2.35) and (A.21) are slope-intercept regression results:\n"
              "they match the polar fit while the beams stay within about +-60 deg of the normal (d1.0 e120 is at the limit).\n"
              "A small d error of a far oblique segment follows its alpha error (lever arm); see the tests' tolerance.\n");
}

void scanBiasAndCorners(int trials) {
  std::printf("\n== 3. Per-scan random bias (A.21, with d') and corner covariance vs Monte Carlo: %d scans each ==\n", trials);
  std::printf("%6s %7s %7s | %10s %10s | %10s %10s   (empirical std / predicted)\n", "d[m]", "offset", "extent",
              "(A.21) a", "(A.21) d", "general a", "general d");
  std::mt19937_64 rng(2);
  std::normal_distribution<double> bias(0.0, 0.01);
  for (const LineCase& c : kLines) {
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    std::vector<double> r(b.size());
    Vec2 sq = Vec2::Zero();
    for (int t = 0; t < trials; ++t) {
      const double rb = bias(rng);
      for (size_t i = 0; i < b.size(); ++i) r[i] = exact[i] + rb;
      const Vec2 e = fitError(c.line(), b, r);
      sq += e.cwiseProduct(e) / trials;
    }
    const PolarReadingBuffer readings(b, exact);
    const Mat2 thesis = scanBiasCovariance(c.line(), readings.view(), 0.01);
    const Mat2 general = scanBiasCovarianceGeneral(c.line(), readings.view(), 0.01);
    std::printf("%6.2f %7.1f %7.1f | %s %s | %s %s\n", c.d, c.offset_deg, c.extent_deg,
                ratioText(std::sqrt(sq.x()), std::sqrt(thesis(0, 0))).c_str(),
                ratioText(std::sqrt(sq.y()), std::sqrt(thesis(1, 1))).c_str(),
                ratioText(std::sqrt(sq.x()), std::sqrt(general(0, 0))).c_str(),
                ratioText(std::sqrt(sq.y()), std::sqrt(general(1, 1))).c_str());
  }
  std::printf("\ncorner (apex, free-space bisector)   std_x emp/pred  std_y emp/pred  std_gamma emp/pred  (sigma_r = 1 cm)\n");
  struct CornerCase {
    Vec2 apex;
    double gamma_deg;
    bool convex;
    double arm;
  };
  std::normal_distribution<double> noise(0.0, 0.01);
  for (const CornerCase& c : {CornerCase{{2, 2}, 225, false, 2.0}, CornerCase{{3, -1}, 160, false, 1.5},
                              CornerCase{{6, 1}, 200, false, 3.0}, CornerCase{{2, 0}, 180, true, 0.8}}) {
    const double spread = deg2rad(c.convex ? 135.0 : 45.0), g = deg2rad(c.gamma_deg);
    const synthetic::Wall walls[2] = {{c.apex, c.apex + c.arm * Vec2(std::cos(g - spread), std::sin(g - spread))},
                                      {c.apex, c.apex + c.arm * Vec2(std::cos(g + spread), std::sin(g + spread))}};
    std::vector<double> bearings[2], ranges[2];
    for (double b = -std::numbers::pi; b < std::numbers::pi; b += deg2rad(0.5)) {
      const double r0 = synthetic::wallRange(walls[0], b), r1 = synthetic::wallRange(walls[1], b);
      if (!std::isfinite(r0) && !std::isfinite(r1)) continue;
      const int arm = r0 < r1 ? 0 : 1;
      bearings[arm].push_back(b);
      ranges[arm].push_back(std::min(r0, r1));
    }
    Vec3 sq = Vec3::Zero();
    Mat3 predicted = Mat3::Zero();
    std::vector<double> noisy[2] = {ranges[0], ranges[1]};
    for (int t = 0; t < trials; ++t) {
      for (int a = 0; a < 2; ++a)
        for (size_t i = 0; i < noisy[a].size(); ++i) noisy[a][i] = ranges[a][i] + noise(rng);
      const PolarReadingBuffer a1(bearings[0], noisy[0]), a2(bearings[1], noisy[1]);
      const CornerFit fit = fitRightAngleCorner(a1.view(), a2.view());
      const Vec2 apex = fit.corner.apex();
      const Vec3 e(apex.x() - c.apex.x(), apex.y() - c.apex.y(), wrapAngle(fit.corner.gamma() - g));
      sq += e.cwiseProduct(e) / trials;
      predicted += fit.covariance(0.01) / trials;
    }
    std::printf("(%4.1f,%4.1f) g=%4.0f %-8s %14s %15s %19s\n", c.apex.x(), c.apex.y(), c.gamma_deg,
                c.convex ? "convex" : "concave", ratioText(std::sqrt(sq(0)), std::sqrt(predicted(0, 0))).c_str(),
                ratioText(std::sqrt(sq(1)), std::sqrt(predicted(1, 1))).c_str(),
                ratioText(std::sqrt(sq(2)), std::sqrt(predicted(2, 2))).c_str());
  }
}

void polarVersusTls(int trials) {
  std::printf("\n== 4. Polar fit vs Cartesian total least squares, same noisy points (sigma_r = 2 cm, %d scans) ==\n", trials);
  std::printf("%6s %7s %7s %7s | %11s %11s %6s | %11s %11s %6s\n", "d[m]", "alpha", "offset", "extent", "RMSE_a pol",
              "RMSE_a TLS", "gain", "RMSE_d pol", "RMSE_d TLS", "gain");
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (const LineCase& c : kLines) {
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    std::vector<double> r(b.size());
    Vec2 polar = Vec2::Zero(), tls = Vec2::Zero();
    for (int t = 0; t < trials; ++t) {
      for (size_t i = 0; i < b.size(); ++i) r[i] = exact[i] + noise(rng);
      const PolarReadingBuffer readings(b, r);
      const LineFit fit = fitLinePolar(readings.view());
      const PolarLine cart = fitLineTotalLeastSquares(readings.view());
      polar += Vec2(wrapAngle(fit.line.alpha - c.line().alpha), fit.line.d - c.d).cwiseAbs2() / trials;
      tls += Vec2(wrapAngle(cart.alpha - c.line().alpha), cart.d - c.d).cwiseAbs2() / trials;
    }
    polar = polar.cwiseSqrt();
    tls = tls.cwiseSqrt();
    std::printf("%6.2f %7.1f %7.1f %7.1f | %11.3e %11.3e %6.3f | %11.3e %11.3e %6.3f\n", c.d, c.alpha_deg, c.offset_deg,
                c.extent_deg, polar.x(), tls.x(), tls.x() / polar.x(), polar.y(), tls.y(), tls.y() / polar.y());
  }
  std::printf("gain = TLS RMSE / polar RMSE (>= 1: the polar fit is at least as accurate)\n");
}

void throughput() {
  std::printf("\n== 5. Speed (one core; %s) ==\n", [] {
    std::ifstream load("/proc/loadavg");
    static std::string text;
    std::getline(load, text);
    text = "load average " + text.substr(0, text.find(' ', text.find(' ', text.find(' ') + 1) + 1));
    return text.c_str();
  }());
  std::mt19937_64 rng(4);
  std::normal_distribution<double> noise(0.0, 0.01);
  const std::vector<double> b = synthetic::bearings(0.2, 0.2 + deg2rad(49.5), 100);
  std::vector<double> r = synthetic::lineRanges({0.5, 2.0}, b);
  for (double& x : r) x += noise(rng);
  const PolarReadingBuffer readings(b, r);
  const LaserErrorModel model(defaultLaserErrors());
  constexpr int kFits = 20000;
  double sink = 0.0;
  double t0 = threadCpuSeconds();
  for (int i = 0; i < kFits; ++i) sink += fitLinePolar(readings.view()).line.d;
  const double fit_s = (threadCpuSeconds() - t0) / kFits;
  t0 = threadCpuSeconds();
  for (int i = 0; i < kFits; ++i) {
    const LineFit fit = fitLinePolar(readings.view());
    sink += lineErrorBudget(fit, readings.view(), {}, model).systematic_bound.x();
  }
  const double budget_s = (threadCpuSeconds() - t0) / kFits;
  t0 = threadCpuSeconds();
  for (int i = 0; i < kFits; ++i) sink += fitLineTotalLeastSquares(readings.view()).d;
  const double tls_s = (threadCpuSeconds() - t0) / kFits;
  std::printf("polar line fit, 100 points:          %8.0f lines/s (%.2f us)\n", 1.0 / fit_s, fit_s * 1e6);
  std::printf("  + full error budget:               %8.0f lines/s (%.2f us)\n", 1.0 / budget_s, budget_s * 1e6);
  std::printf("Cartesian TLS fit, 100 points:       %8.0f lines/s (%.2f us)\n", 1.0 / tls_s, tls_s * 1e6);

  // A 361-beam scan of a furnished room: walls, a pillar face, a box turned 45° (lines, two
  // concave room corners, one convex box corner).
  std::vector<synthetic::Wall> walls = synthetic::room(-3.0, -2.5, 6.0, 4.0);
  const std::vector<Vec2> box = {{2.5, 1.0}, {3.0, 1.5}, {3.5, 1.0}, {3.0, 0.5}};
  for (size_t i = 0; i < box.size(); ++i) walls.push_back({box[i], box[(i + 1) % box.size()]});
  walls.push_back({{4.5, -0.6}, {4.5, -0.2}});
  LaserScan scan = synthetic::scanOfWalls(walls, -std::numbers::pi / 2, deg2rad(0.5), 361);
  synthetic::addNoise(scan, 0.01, rng);
  LaserFeatureConfig full;
  full.errors.range.scan_bias_sigma = 0.003;
  full.errors.range.fixed_bias = 0.005;
  full.errors.range.growth = 0.002;
  full.errors.range.incidence = 0.003;
  full.errors.range.quantum = 0.01;
  for (const auto& [label, config] : {std::pair<const char*, LaserFeatureConfig>{"default error model", LaserFeatureConfig{}},
                                      std::pair<const char*, LaserFeatureConfig>{"full error model (2.8)", full}}) {
    const LaserFeatureExtractor extractor(config);
    std::vector<double> wall_us, cpu_us;
    FeatureSet f;
    for (int i = 0; i < 3000; ++i) {
      const double c0 = threadCpuSeconds();
      const auto w0 = std::chrono::steady_clock::now();
      f = extractor.extract(scan);
      wall_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - w0).count());
      cpu_us.push_back((threadCpuSeconds() - c0) * 1e6);
    }
    std::printf("extract one 361-beam scan, %-23s median %6.1f us wall, %6.1f us CPU, fastest %6.1f us (%zu lines, %zu corners; goal < 100 us)\n",
                label, median(wall_us), median(cpu_us), *std::min_element(wall_us.begin(), wall_us.end()),
                f.lines.size(), f.corners.size());
  }
  if (sink == 0.0) std::printf(" ");
}

/// Minimal FLASER reader (core/io/carmen.hpp had not landed when this was written).
std::vector<LaserScan> readFlaser(const std::string& path, int max_scans) {
  std::vector<LaserScan> scans;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && static_cast<int>(scans.size()) < max_scans) {
    if (line.rfind("FLASER ", 0) != 0) continue;
    std::istringstream s(line.substr(7));
    int n = 0;
    if (!(s >> n) || n < 2 || n > 2000) continue;
    LaserScan scan;
    // FOV by beam count (docs/algorithms.md §20.3): 180 → 1° from −90°, 181 → −90..90, 360/361 → 0.5°.
    scan.angle_increment = deg2rad(n >= 360 ? 0.5 : 1.0);
    scan.angle_min = -std::numbers::pi / 2;
    scan.range_max = 80.0;  // 81.83 / 81.91 = no return
    scan.ranges.resize(static_cast<size_t>(n));
    bool ok = true;
    for (float& r : scan.ranges) ok = ok && static_cast<bool>(s >> r);
    double x, y, th, ox, oy, oth, ts;
    if (!ok || !(s >> x >> y >> th >> ox >> oy >> oth >> ts)) continue;
    scan.utime = static_cast<int64_t>(std::llround(ts * 1e6));
    scan.seq = static_cast<int64_t>(scans.size());
    scans.push_back(std::move(scan));
  }
  return scans;
}

void realScans(const std::string& path, int max_scans) {
  std::printf("\n== 6. Real scans: %s ==\n", path.c_str());
  if (!std::filesystem::exists(path)) {
    std::printf("skipped: %s not found (the shared data sets are not part of the repository)\n", path.c_str());
    return;
  }
  const std::vector<LaserScan> scans = readFlaser(path, max_scans);
  const LaserFeatureExtractor extractor;  // SICK LMS: sigma_r = 1 cm
  long lines = 0, corners = 0, valid = 0, in_lines = 0, rejected = 0;
  std::vector<double> rms, cpu_us;
  double sse = 0.0;
  long residuals = 0;
  for (const LaserScan& scan : scans) {
    ExtractionDetails d;
    const double c0 = threadCpuSeconds();
    const FeatureSet f = extractor.extract(scan, {}, {}, &d);
    cpu_us.push_back((threadCpuSeconds() - c0) * 1e6);
    lines += static_cast<long>(f.lines.size());
    corners += static_cast<long>(f.corners.size());
    rejected += f.num_rejected;
    valid += d.valid_readings;
    for (size_t k = 0; k < f.lines.size(); ++k) {
      in_lines += f.lines[k].num_points;
      rms.push_back(d.line_fits[k].residual_rms);
      sse += d.line_fits[k].residual_rms * d.line_fits[k].residual_rms * f.lines[k].num_points;
      residuals += f.lines[k].num_points;
    }
  }
  const double n = std::max<double>(1.0, static_cast<double>(scans.size()));
  std::printf("%zu scans (%d beams): %.2f lines/scan, %.2f corners/scan, %.2f rejected fits/scan\n", scans.size(),
              scans.empty() ? 0 : static_cast<int>(scans.front().size()), lines / n, corners / n, rejected / n);
  std::printf("%.1f%% of valid readings lie on lines; range residual RMS per line: median %.2f cm, pooled %.2f cm\n",
              100.0 * static_cast<double>(in_lines) / std::max(1L, valid), 100.0 * median(rms),
              100.0 * std::sqrt(sse / std::max(1L, residuals)));
  std::printf("extraction time per real scan: median %.1f us CPU\n", median(cpu_us));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_features: laser line/corner error model checks, accuracy and speed"};
  int trials = 2000, max_scans = 100000;
  std::string clf = std::string(POLARSLAM_SHARED_DATA_DIR) + "/mit-csail/mit-csail.clf";
  app.add_option("--trials", trials, "Monte Carlo scans per case")->capture_default_str();
  app.add_option("--clf", clf, "CARMEN log with FLASER lines")->capture_default_str();
  app.add_option("--max-scans", max_scans, "real scans to use at most")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::printf("bench_features: polar line and right-angle corner features (thesis chapter 2)\n");
  randomCovariance(trials);
  systematicErrors();
  scanBiasAndCorners(trials);
  polarVersusTls(trials);
  throughput();
  realScans(clf, max_scans);
  return 0;
}
