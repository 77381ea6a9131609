// bench_scanmatch: the thesis's chapter 4 experiments (docs/algorithms.md §19.4), PSM, PSM-C and ICP side by
// side, against the goals of issue 4:
//   1. the v0.3 simulated room (§15.1);
//   2. accuracy on noisy simulated pairs against ground truth;
//   3. success rates from initial errors up to 0.3 m / 20° and 0.5 m / 30°;
//   4. time per 181-beam match (median, one core);
//   5. convergence maps over initial errors up to ±1 m and ±45° (PNG per method);
//   6. covariance honesty: mean NEES in rooms and in corridors;
//   7. consecutive-scan laser odometry on ../shared/data/mit-csail (relation metric), success
//      rates on its real scan pairs, accuracy on its short relations, time per match.
// "ICP" is the thesis-era point-to-point baseline (§12); "ICP+i" adds the 2007 interpolation.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "eval/error_statistics.hpp"
#include "geometry/covariance.hpp"
#include "eval/relation_metric.hpp"
#include "io/carmen.hpp"
#include "plot/image.hpp"
#include "io/relations.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "scanmatch/laser_odometry.hpp"
#include "scanmatch/scan_matcher.hpp"
#include "unit/scanmatch/scan_fixtures.hpp"

using namespace polarslam;

namespace {

using Clock = std::chrono::steady_clock;
using fixtures::Noise;

struct Options {
  std::string out = "out/bench-scanmatch";
  std::string data = POLARSLAM_SHARED_DATA_DIR;
  int pairs = 500;
  /// Times per pair in sections 2–4: the fastest of this many passes over all pairs. Each pass
  /// goes through every pair before the next, so each match still starts with its scans out of
  /// the cache; the passes only filter out the interruptions of a shared machine.
  int timing_passes = 3;
  uint64_t seed = 1;
  PsmParams psm;  ///< the matcher's parameters: defaults, or a PSM SLAM configuration's psm section
};

// ---------------------------------------------------------------------------------------------
// Methods compared

struct Method {
  std::string name;
  MatchMethod method;
  PsmParams params;
};

std::vector<Method> methods(const PsmParams& base) {
  PsmParams interpolating = base;
  interpolating.icp_interpolate = true;
  return {{"PSM", MatchMethod::Psm, base},
          {"PSM-C", MatchMethod::PsmC, base},
          {"ICP", MatchMethod::Icp, base},
          {"ICP+i", MatchMethod::Icp, interpolating}};
}

/// The thesis-era PSM for reference: exhaustive ±20° search each orientation step, translation
/// first, parabolic interpolation, H = [cos φ, sin φ], no joint refinement.
PsmParams originalPsm() {
  PsmParams p;
  p.initial_search_window = p.search_window;
  p.coarse_search_step = 0.0;
  p.order = IterationOrder::TranslationFirst;
  p.orientation_refinement = OrientationRefinement::Parabola;
  p.surface_jacobian = false;
  p.joint_refinement = false;
  p.step_min_points_fraction = 1.0;
  return p;
}

bool success(const MatchResult& m, const Pose2& truth, double translation = 0.05, double rotation = deg2rad(1.0)) {
  const auto e = fixtures::poseError(m.pose, truth);
  return m.ok() && e.translation <= translation && e.rotation <= rotation;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))];
}

double microsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

const char* pass(bool ok) { return ok ? "PASS" : "FAIL"; }

// ---------------------------------------------------------------------------------------------
// Simulated pairs

struct PairCase {
  PreparedScan ref, cur;
  Pose2 truth, guess;
};

/// Random pairs in `world` (poses inside the box, 0.4 m from any wall, in sight of each other):
/// true motion up to 0.3 m / 10°, guess off by up to max_error / max_rotation.
std::vector<PairCase> simulatedPairs(const World& world, const Vec2& lo, const Vec2& hi, int count, uint64_t seed,
                                     double max_error, double max_rotation, const PsmParams& params,
                                     double noise_sigma = 0.01) {
  Noise noise(seed);
  fixtures::ScanSpec spec;
  spec.noise_sigma = noise_sigma;
  std::vector<PairCase> pairs;
  while (static_cast<int>(pairs.size()) < count) {
    const Pose2 a = fixtures::randomPose(noise, lo.x(), lo.y(), hi.x(), hi.y());
    const Pose2 motion = fixtures::randomError(noise, 0.3, deg2rad(10.0));
    const Pose2 b = a * motion;
    if (world.castRay(a.translation(), std::atan2(b.y - a.y, b.x - a.x), motion.translation().norm() + 0.3,
                      Sensor::Laser).hit)
      continue;
    if (fixtures::clearance(world, a.translation()) < 0.4 || fixtures::clearance(world, b.translation()) < 0.4) continue;
    PairCase p;
    p.ref = prepareScan(fixtures::simulateScan(world, a, spec, &noise), params);
    p.cur = prepareScan(fixtures::simulateScan(world, b, spec, &noise), params);
    p.truth = motion;
    p.guess = motion * fixtures::randomError(noise, max_error, max_rotation);
    pairs.push_back(std::move(p));
  }
  return pairs;
}

struct PairStats {
  double success = 0.0;
  std::vector<double> translation, rotation_deg, time_us, nees;
  double iterations = 0.0;
};

PairStats runPairs(const std::vector<PairCase>& pairs, const Method& m, int timing_passes = 1) {
  ScanMatcher matcher(m.params);
  PairStats s;
  int ok = 0;
  for (const PairCase& p : pairs) {
    const auto start = Clock::now();
    const MatchResult r = matcher.match(p.ref, p.cur, p.guess, m.method);
    s.time_us.push_back(microsSince(start));
    const auto e = fixtures::poseError(r.pose, p.truth);
    s.translation.push_back(e.translation);
    s.rotation_deg.push_back(rad2deg(e.rotation));
    s.iterations += r.iterations;
    ok += success(r, p.truth);
    if (r.ok()) s.nees.push_back(fixtures::nees(r.pose, p.truth, r.cov));
  }
  for (int pass = 1; pass < timing_passes; ++pass)
    for (size_t k = 0; k < pairs.size(); ++k) {
      const auto start = Clock::now();
      matcher.match(pairs[k].ref, pairs[k].cur, pairs[k].guess, m.method);
      s.time_us[k] = std::min(s.time_us[k], microsSince(start));
    }
  s.success = static_cast<double>(ok) / static_cast<double>(pairs.size());
  s.iterations /= static_cast<double>(pairs.size());
  return s;
}

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

// ---------------------------------------------------------------------------------------------
// 1. v0.3 simulated room

void simulatedRoom(const Options& o) {
  std::printf("\n== 1. Simulated room (v0.3 unit test, §15.1): ±2 m × ±1.5 m, noise-free, guess (0, 0, 0) ==\n");
  std::printf("   goal (original test): error ≤ 0.5 cm and ≤ 0.5°\n");
  const World room = fixtures::psmTestRoom();
  const std::vector<Pose2> cases{{0, 0, 0}, {0, 0, 0.1}, {0, -0.1, 0}, {0.1, 0, 0}};
  std::printf("   %-6s", "method");
  for (const Pose2& c : cases) std::printf(" | truth (%4.2f,%5.2f,%4.2f): err mm/deg  it", c.x, c.y, c.theta);
  std::printf("\n");
  for (const Method& m : methods(o.psm)) {
    ScanMatcher matcher(m.params);
    const PreparedScan ref = prepareScan(fixtures::simulateScan(room, {}, {}), m.params);
    std::printf("   %-6s", m.name.c_str());
    for (const Pose2& truth : cases) {
      const PreparedScan cur = prepareScan(fixtures::simulateScan(room, truth, {}), m.params);
      const MatchResult r = matcher.match(ref, cur, Pose2{}, m.method);
      const auto e = fixtures::poseError(r.pose, truth);
      std::printf(" |            %6.2f %6.3f %3d %s", 1000 * e.translation, rad2deg(e.rotation), r.iterations,
                  e.translation <= 0.005 && e.rotation <= deg2rad(0.5) ? "ok  " : "MISS");
    }
    std::printf("\n");
  }
}

// ---------------------------------------------------------------------------------------------
// 2–4. Accuracy, basin and time on noisy simulated pairs

struct SimulatedFigures {
  std::map<std::string, PairStats> accuracy, near, far;
};

SimulatedFigures simulatedPairsExperiments(const Options& o) {
  SimulatedFigures f;
  const World office = fixtures::clutteredOffice();
  const Vec2 lo(-3.8, -2.8), hi(3.8, 2.8);
  const PsmParams& defaults = o.psm;
  const auto accuracy = simulatedPairs(office, lo, hi, o.pairs, o.seed, 0.1, deg2rad(5.0), defaults);
  const auto near = simulatedPairs(office, lo, hi, o.pairs, o.seed + 1, 0.3, deg2rad(20.0), defaults);
  const auto far = simulatedPairs(office, lo, hi, o.pairs, o.seed + 2, 0.5, deg2rad(30.0), defaults);

  std::printf("\n== 2. Accuracy on noisy simulated pairs (9 × 7 m office, σ = 1 cm, 181 beams, motion ≤ 0.3 m / 10°, "
              "guess error ≤ 0.1 m / 5°, %d pairs) ==\n", o.pairs);
  std::printf("   goal: PSM mean error ≤ that of the ICP baseline\n");
  std::printf("   %-13s %8s %9s %9s %9s %9s %9s %7s\n", "method", "success", "mean mm", "med mm", "p95 mm", "mean deg",
              "p95 deg", "iters");
  std::vector<Method> all = methods(o.psm);
  all.push_back({"PSM original", MatchMethod::Psm, originalPsm()});
  for (const Method& m : all) {
    const PairStats s = runPairs(accuracy, m, o.timing_passes);
    f.accuracy[m.name] = s;
    std::printf("   %-13s %7.1f%% %9.2f %9.2f %9.2f %9.3f %9.3f %7.1f\n", m.name.c_str(), 100 * s.success,
                1000 * mean(s.translation), 1000 * median(s.translation), 1000 * percentile(s.translation, 0.95),
                mean(s.rotation_deg), percentile(s.rotation_deg, 0.95), s.iterations);
  }
  const PairStats& psm = f.accuracy["PSM"];
  const PairStats& icp = f.accuracy["ICP"];
  std::printf("   PSM mean %.2f mm / %.3f deg vs ICP %.2f mm / %.3f deg: %s\n", 1000 * mean(psm.translation),
              mean(psm.rotation_deg), 1000 * mean(icp.translation), mean(icp.rotation_deg),
              pass(mean(psm.translation) <= mean(icp.translation) && mean(psm.rotation_deg) <= mean(icp.rotation_deg)));

  std::printf("\n== 3. Success (≤ 5 cm and ≤ 1°) from initial errors (same office, %d pairs each) ==\n", o.pairs);
  std::printf("   goals: ≥ 99 %% up to 0.3 m / 20°, ≥ 95 %% up to 0.5 m / 30° (translation error uniform over the "
              "disc, heading uniform)\n");
  std::printf("   %-13s %16s %16s\n", "method", "0.3 m / 20°", "0.5 m / 30°");
  for (const Method& m : all) {
    f.near[m.name] = runPairs(near, m, o.timing_passes);
    f.far[m.name] = runPairs(far, m, o.timing_passes);
    std::printf("   %-13s %15.1f%% %15.1f%%\n", m.name.c_str(), 100 * f.near[m.name].success, 100 * f.far[m.name].success);
  }
  std::printf("   PSM: %s (%.1f %%), %s (%.1f %%)\n", pass(f.near["PSM"].success >= 0.99), 100 * f.near["PSM"].success,
              pass(f.far["PSM"].success >= 0.95), 100 * f.far["PSM"].success);

  std::printf("\n== 4. Time per 181-beam match (wall clock per match, median over pairs of each pair's fastest of %d "
              "passes; scans prepared beforehand) ==\n", o.timing_passes);
  std::printf("   goals: PSM median ≤ 20 us on one core (the original C code: about 80 us); with the scan's preparation "
              "included ≤ 12 us (issue 19)\n");
  std::printf("   %-13s %12s %12s %12s\n", "method", "guess 0.1/5", "0.3 m/20°", "0.5 m/30°");
  for (const Method& m : all)
    std::printf("   %-13s %10.1f us %10.1f us %10.1f us\n", m.name.c_str(), median(f.accuracy[m.name].time_us),
                median(f.near[m.name].time_us), median(f.far[m.name].time_us));
  // preparation (median filter, segmentation, corridor test) happens once per scan
  Noise noise(o.seed + 7);
  fixtures::ScanSpec spec;
  spec.noise_sigma = 0.01;
  const LaserScan raw = fixtures::simulateScan(office, {0.5, 0.5, 0.3}, spec, &noise);
  std::vector<double> prepare;
  for (int k = 0; k < 2000; ++k) {
    const auto start = Clock::now();
    const PreparedScan p = prepareScan(raw, defaults);
    prepare.push_back(microsSince(start));
  }
  std::printf("   scan preparation (once per scan): %.1f us median\n", median(prepare));
  const double psm_us = median(f.accuracy["PSM"].time_us), prepared_us = psm_us + median(prepare);
  std::printf("   PSM: %s (%.1f us); with preparation: %s (%.1f us)\n", pass(psm_us <= 20.0), psm_us,
              pass(prepared_us <= 12.0), prepared_us);
  return f;
}

// ---------------------------------------------------------------------------------------------
// 5. Convergence maps

void convergenceMaps(const Options& o) {
  std::printf("\n== 5. Convergence map: initial position errors on a 21 × 21 grid over ±1 m, headings 0, ±10°, ±20°, "
              "±30°, ±45°; 4 scan pairs per cell; converged = ≤ 1 cm and ≤ 1° ==\n");
  const World office = fixtures::clutteredOffice();
  const std::vector<double> headings{-45, -30, -20, -10, 0, 10, 20, 30, 45};
  constexpr int kCells = 21, kPixels = 8, kGap = 6;
  const int kPairs = 4;
  const PsmParams& defaults = o.psm;
  const auto pairs = simulatedPairs(office, {-3.0, -2.0}, {3.0, 2.0}, kPairs, o.seed + 20, 0.0, 0.0, defaults);
  std::filesystem::create_directories(o.out);
  std::printf("   %-13s", "method");
  for (double h : headings) std::printf(" %6.0f°", h);
  std::printf("   (converged share of the map per heading)\n");
  std::vector<Method> all = methods(o.psm);
  all.push_back({"PSM original", MatchMethod::Psm, originalPsm()});
  for (const Method& m : all) {
    ScanMatcher matcher(m.params);
    const int width = static_cast<int>(headings.size()) * (kCells * kPixels + kGap) + kGap;
    RgbImage image(width, kCells * kPixels + 2 * kGap, Rgb{255, 255, 255});
    std::printf("   %-13s", m.name.c_str());
    for (size_t h = 0; h < headings.size(); ++h) {
      int converged = 0;
      for (int iy = 0; iy < kCells; ++iy) {
        for (int ix = 0; ix < kCells; ++ix) {
          const Pose2 error(-1.0 + 0.1 * ix, 1.0 - 0.1 * iy, deg2rad(headings[h]));
          int ok = 0;
          for (const PairCase& p : pairs) {
            const MatchResult r = matcher.match(p.ref, p.cur, p.truth * error, m.method);
            ok += success(r, p.truth, 0.01, deg2rad(1.0));
          }
          converged += ok;
          const double share = static_cast<double>(ok) / kPairs;
          const Rgb colour{static_cast<uint8_t>(255 * (1.0 - share)), static_cast<uint8_t>(200 * share + 30), 60};
          const int x0 = kGap + static_cast<int>(h) * (kCells * kPixels + kGap) + ix * kPixels, y0 = kGap + iy * kPixels;
          for (int y = 0; y < kPixels - 1; ++y)
            for (int x = 0; x < kPixels - 1; ++x) image.set(x0 + x, y0 + y, colour);
        }
      }
      std::printf(" %6.1f%%", 100.0 * converged / (kCells * kCells * kPairs));
    }
    std::string file = m.name;
    std::replace(file.begin(), file.end(), ' ', '-');
    std::replace(file.begin(), file.end(), '+', 'i');
    const std::string path = (std::filesystem::path(o.out) / ("convergence_" + file + ".png")).string();
    writePng(path, image);
    std::printf("   -> %s\n", path.c_str());
  }
  std::printf("   (each PNG: one panel per heading, left to right; x = initial x error −1..1 m, y = initial y error "
              "1..−1 m; green = all 4 pairs converge, red = none)\n");
}

// ---------------------------------------------------------------------------------------------
// 6. Covariance honesty

void covarianceExperiments(const Options& o) {
  std::printf("\n== 6. Covariance honesty: mean NEES over simulated matches (3 = consistent; σ = 1 cm, guess error "
              "≤ 0.1 m / 5°, %d pairs) ==\n", o.pairs);
  std::printf("   goal: default covariance mean NEES near 3 in rooms and in corridors\n");
  const World office = fixtures::clutteredOffice(), corridor = fixtures::officeCorridor();
  struct Scene {
    const char* name;
    const World* world;
    Vec2 lo, hi;
  };
  const Scene scenes[] = {{"office rooms", &office, {-3.8, -2.8}, {3.8, 2.8}},
                          {"corridor with doors", &corridor, {-12.0, -0.55}, {12.0, 0.55}}};
  struct Model {
    const char* name;
    PsmParams params;
  };
  PsmParams heuristic = o.psm, heuristic_thesis = o.psm;
  heuristic.covariance = heuristic_thesis.covariance = CovarianceModel::Heuristic;
  heuristic_thesis.heuristic = HeuristicCovarianceParams::thesis();
  PsmParams raw_wls = o.psm;
  raw_wls.wls_inflation = 1.0;
  raw_wls.wls_floor_xy = raw_wls.wls_floor_theta = 0.0;
  const Model models[] = {{"WLS (default)", o.psm},
                          {"WLS uncalibrated", raw_wls},
                          {"heuristic 20 cm/4°", heuristic},
                          {"heuristic 10 cm/2°", heuristic_thesis}};
  std::printf("   %-20s", "model");
  for (const Scene& s : scenes) std::printf(" %22s", s.name);
  std::printf("   (mean NEES; median in brackets)\n");
  std::vector<std::vector<PairCase>> scene_pairs;
  for (const Scene& s : scenes)
    scene_pairs.push_back(simulatedPairs(*s.world, s.lo, s.hi, o.pairs, o.seed + 30, 0.1, deg2rad(5.0), o.psm));
  for (const Model& model : models) {
    std::printf("   %-20s", model.name);
    for (const auto& pairs : scene_pairs) {
      const PairStats s = runPairs(pairs, {"PSM", MatchMethod::Psm, model.params});
      std::printf(" %13.2f (%6.2f)", mean(s.nees), median(s.nees));
    }
    std::printf("\n");
  }
  for (double sigma : {0.005, 0.02}) {
    const auto pairs = simulatedPairs(office, {-3.8, -2.8}, {3.8, 2.8}, o.pairs / 2, o.seed + 40, 0.1, deg2rad(5.0),
                                      o.psm, sigma);
    const PairStats s = runPairs(pairs, {"PSM", MatchMethod::Psm, o.psm});
    std::printf("   WLS (default), office, σ = %.1f cm: mean NEES %.2f\n", 100 * sigma, mean(s.nees));
  }
}

// ---------------------------------------------------------------------------------------------
// 7. MIT CSAIL

struct RealScan {
  LaserScan scan;
  std::optional<Pose2> odometry;
};

std::vector<RealScan> readMitScans(const std::string& path) {
  const CarmenLog log = readCarmenLogFile(path);
  std::vector<RealScan> scans;
  std::optional<Pose2> last_odometry;
  for (const CarmenEvent& e : log.events) {
    if (!e.isLaser()) {
      last_odometry = e.odometry().pose;
      continue;
    }
    scans.push_back({e.laser(), last_odometry});
  }
  return scans;
}

/// Relation-metric error of a trajectory over relations spanning less than 30 s ("local").
RelationMetric localRelations(const std::vector<PoseStamped>& trajectory, const std::vector<Relation>& relations) {
  std::vector<Relation> local;
  for (const Relation& r : relations)
    if (std::llabs(r.t2 - r.t1) < 30'000'000) local.push_back(r);
  return evaluateRelations(trajectory, local);
}

void mitExperiments(const Options& o) {
  const std::string clf = o.data + "/mit-csail/mit-csail.clf", rel = o.data + "/mit-csail/mit-csail.relations";
  std::printf("\n== 7. MIT CSAIL (real SICK LMS, 361 beams at 0.5°; matched at 1°: every 2nd beam, as the thesis) ==\n");
  if (!std::filesystem::exists(clf) || !std::filesystem::exists(rel)) {
    std::printf("   SKIPPED: %s or its relations not found (shared data absent)\n", clf.c_str());
    return;
  }
  const std::vector<RealScan> scans = readMitScans(clf);
  const std::vector<Relation> relations = readRelations(rel);
  std::map<int64_t, size_t> by_time;
  for (size_t k = 0; k < scans.size(); ++k) by_time[scans[k].scan.utime] = k;

  std::printf("   a) laser odometry against keyframes (wheel odometry as prior), relation metric over relations "
              "< 30 s apart\n");
  std::printf("      reference (docs/algorithms.md appendix, original PSM v0.3 chained: 0.056 m; CSM PLICP chained: 0.030 m); "
              "wheel odometry below\n");
  std::printf("      %-16s %10s %10s %10s %9s %10s %10s\n", "method", "trans m", "std m", "rot deg", "failed", "us/scan",
              "us/match");
  {
    std::vector<PoseStamped> wheels;
    Pose2 origin_inverse;
    for (size_t k = 0; k < scans.size(); ++k) {
      if (!scans[k].odometry) continue;
      if (wheels.empty()) origin_inverse = scans[k].odometry->inverse();
      wheels.push_back({scans[k].scan.utime, origin_inverse * *scans[k].odometry, Mat3::Zero()});
    }
    const RelationMetric w = localRelations(wheels, relations);
    std::printf("      %-16s %10.4f %10.4f %10.3f %9s %10s %10s  (%zu relations)\n", "wheel odometry", w.translation.mean,
                w.translation.std, w.rotation_deg.mean, "-", "-", "-", w.evaluated);
  }
  std::vector<Method> all = methods(o.psm);
  for (Method& m : all) m.params.decimation = 2;
  Method full{"PSM 361 beams", MatchMethod::Psm, o.psm};
  full.params.min_valid_points = 80;
  all.push_back(full);
  for (const Method& m : all) {
    LaserOdometryParams lo_params;
    lo_params.method = m.method;
    LaserOdometry odometry(lo_params, m.params);
    std::vector<double> per_scan;
    for (const RealScan& s : scans) {
      if (s.odometry) {
        OdometryReading r;
        r.utime = s.scan.utime;
        r.pose = *s.odometry;
        odometry.addOdometry(r);
      }
      const LaserOdometryUpdate u = odometry.addScan(s.scan);
      per_scan.push_back(u.match_time_us);
    }
    const RelationMetric r = localRelations(odometry.trajectory(), relations);
    // per-match time alone: consecutive pairs, prepared beforehand
    ScanMatcher matcher(m.params);
    std::vector<double> match_times;
    PreparedScan previous = prepareScan(scans.front().scan, m.params);
    for (size_t k = 1; k < scans.size(); ++k) {
      PreparedScan current = prepareScan(scans[k].scan, m.params);
      Pose2 guess;
      if (scans[k].odometry && scans[k - 1].odometry) guess = between(*scans[k - 1].odometry, *scans[k].odometry);
      const auto start = Clock::now();
      matcher.match(previous, current, guess, m.method);
      match_times.push_back(microsSince(start));
      previous = std::move(current);
    }
    std::printf("      %-16s %10.4f %10.4f %10.3f %9lld %10.1f %10.1f\n", m.name.c_str(), r.translation.mean,
                r.translation.std, r.rotation_deg.mean, static_cast<long long>(odometry.failedMatches()),
                median(per_scan), median(match_times));
  }

  // b) success rates on real consecutive pairs
  std::printf("   b) success (≤ 5 cm, ≤ 1°) on real consecutive pairs from perturbed guesses; reference pose = PSM from the "
              "odometry guess where ICP+i agrees (≤ 2 cm, ≤ 0.5°)\n");
  std::printf("      goals: ≥ 99 %% up to 0.3 m / 20°, ≥ 97 %% up to 0.5 m / 30°\n");
  {
    PsmParams p181 = o.psm;
    p181.decimation = 2;
    PsmParams p181i = p181;
    p181i.icp_interpolate = true;
    ScanMatcher matcher(p181), checker(p181i);
    struct RealPair {
      PreparedScan ref, cur;
      Pose2 truth;
      bool determined;  ///< the scans fix the reference pose to within the success bound (its 3σ)
    };
    std::vector<RealPair> pairs;
    for (size_t k = 1; k < scans.size(); k += 4) {
      PreparedScan a = prepareScan(scans[k - 1].scan, p181), b = prepareScan(scans[k].scan, p181);
      Pose2 guess;
      if (scans[k].odometry && scans[k - 1].odometry) guess = between(*scans[k - 1].odometry, *scans[k].odometry);
      const MatchResult psm = matcher.match(a, b, guess);
      const MatchResult icp = checker.match(a, b, guess, MatchMethod::Icp);
      if (!psm.ok() || !icp.ok()) continue;
      const auto d = fixtures::poseError(psm.pose, icp.pose);
      if (d.translation > 0.02 || d.rotation > deg2rad(0.5)) continue;
      const bool determined = 3.0 * largestPositionSigma(psm.cov) <= 0.05 && 3.0 * std::sqrt(psm.cov(2, 2)) <= deg2rad(1.0);
      pairs.push_back({std::move(a), std::move(b), psm.pose, determined});
    }
    // A failure is one of three kinds: the matcher refused (a status other than ok); its answer
    // is off only where its own covariance says it does not know (3σ covers the error: along a
    // corridor no reading constrains, the reference pose there is the odometry's, PSM and ICP+i
    // both keeping the guess along that axis); or it is wrong and claims to be right.
    enum class Failure { Refused, Covered, Wrong };
    auto failureKind = [](const MatchResult& m, const RealPair& p) {
      if (!m.ok()) return Failure::Refused;
      const Vec2 error = m.pose.translation() - p.truth.translation();
      const bool covered = error.dot(m.cov.topLeftCorner<2, 2>().ldlt().solve(error)) <= 9.0 &&
                           fixtures::poseError(m.pose, p.truth).rotation <= std::max(deg2rad(1.0), 3.0 * std::sqrt(m.cov(2, 2)));
      return covered ? Failure::Covered : Failure::Wrong;
    };
    // Where the scans leave a direction open (σ of metres along a featureless corridor), the
    // reference pose along it is the odometry's, not a measurement, and no matcher can be judged
    // against it. The goals are read on the pairs whose reference the scans fix to within the
    // success bound; the figure over all pairs is printed above them.
    const auto determined_pairs = std::count_if(pairs.begin(), pairs.end(), [](const RealPair& p) { return p.determined; });
    struct Tally {
      int ok = 0, total = 0;
      std::array<int, 3> failures{};  ///< by Failure
      void add(std::optional<Failure> failure) {
        ++total;
        if (failure) ++failures[static_cast<size_t>(*failure)];
        else ++ok;
      }
      double percent(int count) const { return 100.0 * count / std::max(1, total); }
      double successPercent() const { return percent(ok); }
      void print() const {
        std::printf(" %7.1f%% (%4.1f/%4.1f/%4.1f)", successPercent(), percent(failures[0]), percent(failures[1]),
                    percent(failures[2]));
      }
    };
    std::printf("      %-13s %25s %25s   (%zu pairs × 5 guesses; failures: refused / covered by the match's 3σ / wrong)\n",
                "method", "0.3 m / 20°", "0.5 m / 30°", pairs.size());
    Tally psm_determined[2];
    for (Method m : methods(o.psm)) {
      m.params.decimation = 2;
      ScanMatcher mm(m.params);
      const double limits[2][2] = {{0.3, deg2rad(20.0)}, {0.5, deg2rad(30.0)}};
      Tally all[2], determined[2];
      for (int l = 0; l < 2; ++l) {
        Noise n(o.seed + 60 + l);
        for (const RealPair& p : pairs) {
          for (int g = 0; g < 5; ++g) {
            const Pose2 guess = p.truth * fixtures::randomError(n, limits[l][0], limits[l][1]);
            const MatchResult result = mm.match(p.ref, p.cur, guess, m.method);
            const std::optional<Failure> failure =
                success(result, p.truth) ? std::nullopt : std::optional<Failure>(failureKind(result, p));
            all[l].add(failure);
            if (p.determined) determined[l].add(failure);
          }
        }
      }
      std::printf("      %-13s", m.name.c_str());
      all[0].print();
      all[1].print();
      std::printf("\n      %-13s", "  determined");
      determined[0].print();
      determined[1].print();
      std::printf("\n");
      if (m.method == MatchMethod::Psm) std::copy(std::begin(determined), std::end(determined), std::begin(psm_determined));
    }
    std::printf("      \"determined\": the %td of %zu pairs whose reference pose the scans fix (its 3σ within 5 cm and 1°)\n",
                determined_pairs, pairs.size());
    std::printf("      PSM on them: %s (%.1f %%), %s (%.1f %%)\n", pass(psm_determined[0].successPercent() >= 99.0),
                psm_determined[0].successPercent(), pass(psm_determined[1].successPercent() >= 97.0),
                psm_determined[1].successPercent());
  }

  // c) direct matches on short relations
  std::printf("   c) direct matches of the two scans of each relation shorter than 2 s (odometry guess) against the "
              "relation\n");
  std::printf("      %-13s %9s %10s %10s %10s %12s %12s\n", "method", "pairs", "mean mm", "median mm", "mean deg",
              "NEES rooms", "NEES corr.");
  for (Method m : methods(o.psm)) {
    m.params.decimation = 2;
    ScanMatcher matcher(m.params);
    std::vector<double> t, r, nees_room, nees_corridor;
    for (const Relation& rel_k : relations) {
      if (std::llabs(rel_k.t2 - rel_k.t1) > 2'000'000) continue;
      const auto a = by_time.find(rel_k.t1), b = by_time.find(rel_k.t2);
      if (a == by_time.end() || b == by_time.end()) continue;
      const RealScan& sa = scans[a->second];
      const RealScan& sb = scans[b->second];
      Pose2 guess;
      if (sa.odometry && sb.odometry) guess = between(*sa.odometry, *sb.odometry);
      const PreparedScan pa = prepareScan(sa.scan, m.params), pb = prepareScan(sb.scan, m.params);
      const MatchResult res = matcher.match(pa, pb, guess, m.method);
      if (!res.ok()) continue;
      const auto e = fixtures::poseError(res.pose, rel_k.motion());
      t.push_back(e.translation);
      r.push_back(rad2deg(e.rotation));
      (detectCorridor(pa, m.params.corridor_threshold).is_corridor ? nees_corridor : nees_room).push_back(fixtures::nees(res.pose, rel_k.motion(), res.cov));
    }
    std::printf("      %-13s %9zu %10.2f %10.2f %10.3f %12.2f %12.2f\n", m.name.c_str(), t.size(), 1000 * mean(t),
                1000 * median(t), mean(r), mean(nees_room), mean(nees_corridor));
  }
  std::printf("      (relations are themselves estimates, accurate to about a centimetre: errors and NEES here include "
              "theirs)\n");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_scanmatch: PSM, PSM-C and ICP, the thesis's chapter 4 experiments"};
  Options o;
  app.add_option("--out", o.out, "folder for the convergence-map PNGs")->capture_default_str();
  app.add_option("--data", o.data, "shared data folder (mit-csail/)")->capture_default_str();
  app.add_option("--pairs", o.pairs, "simulated pairs per experiment")->capture_default_str();
  app.add_option("--seed", o.seed)->capture_default_str();
  app.add_option("--timing-passes", o.timing_passes,
                 "time each simulated pair as the fastest of this many passes over all pairs")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  std::string config;
  app.add_option("--psm-config", config, "PSM SLAM configuration (YAML) whose psm section the matchers use")
      ->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);
  try {
    if (!config.empty()) o.psm = loadPsmSlamEstimatorConfig(config).slam.psm;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_scanmatch: %s\n", e.what());
    return 1;
  }
  std::printf("bench_scanmatch: times are wall clock on one thread; run on an idle machine for representative times\n");
  simulatedRoom(o);
  simulatedPairsExperiments(o);
  convergenceMaps(o);
  covarianceExperiments(o);
  mitExperiments(o);
  std::printf("\nconvergence maps written to %s\n", std::filesystem::absolute(o.out).string().c_str());
  return 0;
}
