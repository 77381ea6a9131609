// bench_slam: EKF feature SLAM with laser only, sonar only and fused (thesis §3.8, docs/algorithms.md §19.2).
//  1. The thesis's claim: in a world with glass walls, sound-absorbing partitions and a long
//     corridor with only small features, each seed's simulated run is fed to the three
//     configurations at once (same sensor data); ATE, maximum error, map size and whether the run
//     succeeded (bounded error and a closed loop) are printed per configuration, and the seeds
//     where fused succeeds while a single-sensor run fails are counted. PSM SLAM (laser and
//     odometry) runs on the same data: its ATE stands next to the EKF's.
//  2. Filter consistency: the average NEES of the robot pose of the fused runs against the 95% χ²
//     bounds of an average over that many Monte Carlo runs.
//  3. Speed: time per EKF update (association + update) with 100, 300 and 1000 map features, and
//     each configuration's whole-run speed as a multiple of real time.
//  --psm-only: PSM SLAM alone (no EKF, no speed table) over many seeds, for issue 19's "no wrong
//     loop closure, ever": runs whose maximum error exceeds 1 m, the worst maximum error, the
//     mean ATE and the loop closures accepted and refused, each next to its goal; a loop edge is
//     counted wrong when it disagrees with the true relative pose of its two reference scans
//     (0.3 m or 5 deg, and beyond its own covariance).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>
#include <random>
#include <sstream>

#include "estimator_sim_sink.hpp"
#include "eval/ate.hpp"
#include "eval/nees.hpp"
#include "eval/trajectory_lookup.hpp"
#include "io/tum.hpp"
#include "sim/simulator.hpp"
#include "pipeline/feature_slam_estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"

using namespace polarslam;

namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::vector<std::string> worlds = {std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/office.yaml",
                                     std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/glass-partition-loop.yaml"};
  std::string robot = std::string(POLARSLAM_SOURCE_DIR) + "/config/robots/default.yaml";
  int seeds = 20;
  uint64_t first_seed = 1;
  double seconds = 0.0;           ///< 0 = until the path ends
  double max_error_limit = 0.5;   ///< m: a run whose position error ever exceeds this failed
  std::string out;
  std::string nees_trace;  ///< CSV of per-second NEES of every configuration (first seed)
  std::string psm_config;  ///< PSM SLAM parameters (YAML), default parameters when empty
  bool claim = true, speed = true;
  bool psm_only = false;
};

/// One estimator fed from the simulator, with the wall time spent inside it.
struct TimedEstimator {
  SlamSensors sensors;
  std::unique_ptr<FeatureSlamEstimator> estimator;
  double seconds = 0.0;
};

/// PSM SLAM (laser and odometry only) on the same data, for the side-by-side ATE.
struct TimedPsmSlam {
  PsmSlamEstimator estimator;
  double seconds = 0.0;
};

class Fanout : public SimSink {
 public:
  Fanout(std::vector<TimedEstimator>& estimators, TimedPsmSlam& psm) : estimators_(estimators), psm_(psm) {}
  void onLaser(const LaserScan& scan) override {
    each([&](Estimator& e) { e.onLaser(scan); });
  }
  void onSonar(const SonarScan& scan) override {
    each([&](Estimator& e) { e.onSonar(scan); });
  }
  void onOdometry(const OdometryReading& odometry) override {
    each([&](Estimator& e) { e.onOdometry(odometry); });
  }
  void onGroundTruth(const PoseStamped& pose) override { truth.push_back(pose); }
  std::vector<PoseStamped> truth;

 private:
  template <typename Call>
  void each(Call&& call) {
    for (TimedEstimator& t : estimators_) {
      const auto start = Clock::now();
      call(*t.estimator);
      t.seconds += std::chrono::duration<double>(Clock::now() - start).count();
    }
    const auto start = Clock::now();
    call(psm_.estimator);
    psm_.seconds += std::chrono::duration<double>(Clock::now() - start).count();
  }
  std::vector<TimedEstimator>& estimators_;
  TimedPsmSlam& psm_;
};

struct RunResult {
  double ate_rmse = 0.0, max_error = 0.0, final_error = 0.0;
  size_t map_size = 0;
  bool loop_closed = false;
  bool success = false;
  double realtime_factor = 0.0;
  std::vector<double> nees;  ///< robot pose NEES at 1 Hz
  std::vector<std::string> trace;  ///< per second: error (robot frame) and std, for --nees-trace
};

RunResult evaluate(FeatureSlamEstimator& e, const std::vector<PoseStamped>& truth, double run_seconds,
                   double wall_seconds, const Options& o) {
  RunResult r;
  const auto& estimate = e.filterPoses();  // the filter itself: its NEES, its ATE
  const AteResult ate = evaluateAte(estimate, truth);
  r.ate_rmse = ate.raw_translation.rmse;
  r.max_error = ate.raw_translation.max;
  const TrajectoryLookup lookup(truth);
  if (!estimate.empty())
    if (const auto end = lookup.interpolate(estimate.back().utime, 100000))
      r.final_error = (end->translation() - estimate.back().pose.translation()).norm();
  r.map_size = e.slam().map().features.size();
  // Loop closed: a feature seen early in the run is matched again in its last fifth.
  const int64_t t0 = truth.front().utime, t1 = truth.back().utime;
  for (const auto& [utime, id] : e.revisits())
    if (utime >= t1 - (t1 - t0) / 5) r.loop_closed = true;
  r.success = r.loop_closed && r.max_error <= o.max_error_limit;
  r.realtime_factor = wall_seconds > 0 ? run_seconds / wall_seconds : 0.0;
  int64_t next = t0 + 1'000'000;
  for (const PoseStamped& p : estimate) {
    if (p.utime < next) continue;
    next += 1'000'000;
    if (const auto t = lookup.interpolate(p.utime, 30000)) {
      try {
        r.nees.push_back(poseNees(p.pose, p.cov, *t));
        const Pose2 error = between(*t, p.pose);
        const Mat3 cov = rotateCovariance(p.cov, -t->theta);
        char line[256];
        std::snprintf(line, sizeof line, "%.4f,%.4f,%.5f,%.4f,%.4f,%.5f", error.x, error.y, error.theta,
                      std::sqrt(cov(0, 0)), std::sqrt(cov(1, 1)), std::sqrt(cov(2, 2)));
        r.trace.push_back(line);
      } catch (const std::invalid_argument&) {
      }
    }
  }
  return r;
}

struct Row {
  std::vector<RunResult> runs;
};

double mean(const std::vector<double>& v) { return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / v.size(); }
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void runClaim(const Options& o, const std::string& world_path) {
  const World world = loadWorld(world_path);
  const RobotDescription robot = loadRobotDescription(o.robot);
  const std::vector<SlamSensors> configs = {SlamSensors::Laser, SlamSensors::Sonar, SlamSensors::Fused};
  std::map<SlamSensors, Row> rows;
  int fused_wins = 0;
  std::printf("\n=== world %s, robot %s, %d seeds from %llu\n", world_path.c_str(), o.robot.c_str(), o.seeds,
              static_cast<unsigned long long>(o.first_seed));
  std::printf("%6s %8s | %-28s | %-28s | %-28s | %-13s\n", "seed", "seconds", "laser: ATE max map loop",
              "sonar: ATE max map loop", "fused: ATE max map loop", "psm-slam: ATE max");
  std::vector<double> psm_ate, psm_max, psm_speed;
  for (int k = 0; k < o.seeds; ++k) {
    const uint64_t seed = o.first_seed + static_cast<uint64_t>(k);
    std::vector<TimedEstimator> estimators;
    for (SlamSensors s : configs)
      estimators.push_back({s, std::make_unique<FeatureSlamEstimator>(configForRobot(robot, s)), 0.0});
    TimedPsmSlam psm{PsmSlamEstimator(o.psm_config.empty() ? PsmSlamEstimatorConfig{}
                                                           : loadPsmSlamEstimatorConfig(o.psm_config))};
    Fanout sink(estimators, psm);
    Simulator sim(world, robot, seed);
    const double limit = o.seconds > 0 ? o.seconds : 3600.0;
    while (sim.time() < limit && !sim.finished()) sim.step(sink);
    const std::vector<PoseStamped> truth = inStartFrame(sink.truth);
    if (std::getenv("PSM_DEBUG")) writeTumTrajectory("/tmp/prof/truth.tum", sink.truth);
    std::printf("%6llu %8.1f |", static_cast<unsigned long long>(seed), sim.time());
    std::map<SlamSensors, bool> success;
    for (TimedEstimator& t : estimators) {
      const auto start = Clock::now();
      nlohmann::json report;
      std::string dir;
      if (!o.out.empty() && k == 0) {
        dir = (std::filesystem::path(o.out) / world.name / toString(t.sensors)).string();
        std::filesystem::create_directories(dir);
      }
      t.estimator->finish(dir, report);
      t.seconds += std::chrono::duration<double>(Clock::now() - start).count();
      if (!dir.empty()) writeTumTrajectory(dir + "/trajectory.tum", t.estimator->trajectory());
      const RunResult r = evaluate(*t.estimator, truth, sim.time(), t.seconds, o);
      rows[t.sensors].runs.push_back(r);
      if (!o.nees_trace.empty() && k == 0) {
        std::ofstream trace(o.nees_trace + "." + world.name + "." + toString(t.sensors) + ".csv");
        trace << "second,nees,forward_error,left_error,heading_error,forward_std,left_std,heading_std\n";
        for (size_t i = 0; i < r.nees.size(); ++i) trace << i + 1 << "," << r.nees[i] << "," << r.trace[i] << "\n";
      }
      success[t.sensors] = r.success;
      std::printf(" %6.3f %6.3f %4zu %-3s %s |", r.ate_rmse, r.max_error, r.map_size, r.loop_closed ? "yes" : "no",
                  r.success ? "ok  " : "FAIL");
    }
    {
      const auto start = Clock::now();
      nlohmann::json report;
      const std::string dir = !o.out.empty() && k == 0 ? (std::filesystem::path(o.out) / world.name / "psm-slam").string() : "";
      psm.estimator.finish(dir, report);
      psm.seconds += std::chrono::duration<double>(Clock::now() - start).count();
      if (!dir.empty()) writeTumTrajectory(dir + "/trajectory.tum", psm.estimator.trajectory());
      const AteResult ate = evaluateAte(psm.estimator.trajectory(), truth);
      psm_ate.push_back(ate.raw_translation.rmse);
      psm_max.push_back(ate.raw_translation.max);
      psm_speed.push_back(psm.seconds > 0 ? sim.time() / psm.seconds : 0.0);
      std::printf(" %6.3f %6.3f |", psm_ate.back(), psm_max.back());
    }
    const bool win = success[SlamSensors::Fused] && (!success[SlamSensors::Laser] || !success[SlamSensors::Sonar]);
    fused_wins += win;
    std::printf("%s\n", win ? " fused succeeds where a single sensor fails" : "");
    std::fflush(stdout);
  }

  std::printf("\nsummary over %d seeds (success: loop closed and max error <= %.2f m)\n", o.seeds, o.max_error_limit);
  std::printf("%-7s %10s %10s %10s %10s %10s %10s %10s\n", "sensors", "ATE mean", "ATE med", "max mean", "max worst",
              "map size", "success", "x realtime");
  for (SlamSensors s : configs) {
    const auto& runs = rows[s].runs;
    std::vector<double> ate, max_error, map_size, speed;
    int ok = 0;
    for (const RunResult& r : runs) {
      ate.push_back(r.ate_rmse);
      max_error.push_back(r.max_error);
      map_size.push_back(static_cast<double>(r.map_size));
      speed.push_back(r.realtime_factor);
      ok += r.success;
    }
    std::printf("%-7s %10.3f %10.3f %10.3f %10.3f %10.1f %7d/%-2zu %10.1f\n", toString(s), mean(ate), median(ate),
                mean(max_error), *std::max_element(max_error.begin(), max_error.end()), mean(map_size), ok, runs.size(),
                mean(speed));
  }
  std::printf("%-7s %10.3f %10.3f %10.3f %10.3f %10s %10s %10.1f   (PSM SLAM, laser + odometry, same runs)\n",
              "psm", mean(psm_ate), median(psm_ate), mean(psm_max), *std::max_element(psm_max.begin(), psm_max.end()),
              "-", "-", mean(psm_speed));
  std::printf("fused succeeds where laser-only or sonar-only fails: %d of %d seeds\n", fused_wins, o.seeds);

  // Consistency of the fused filter: NEES averaged over the runs at each second.
  std::vector<std::vector<double>> nees;
  size_t steps = std::numeric_limits<size_t>::max();
  for (const RunResult& r : rows[SlamSensors::Fused].runs) steps = std::min(steps, r.nees.size());
  for (const RunResult& r : rows[SlamSensors::Fused].runs)
    nees.emplace_back(r.nees.begin(), r.nees.begin() + static_cast<std::ptrdiff_t>(steps));
  if (steps > 0 && steps != std::numeric_limits<size_t>::max()) {
    const NeesSummary n = summarizeNees(nees, 3, 0.95);
    std::printf("\nfused robot-pose NEES over %zu runs x %zu s: average %.2f, 95%% bounds of a %zu-run average [%.2f, %.2f] "
                "-> %s; seconds whose run-average lies inside: %.0f%%\n",
                nees.size(), steps, n.average, nees.size(), n.step_interval.lower, n.step_interval.upper,
                n.average >= n.step_interval.lower && n.average <= n.step_interval.upper ? "inside" : "OUTSIDE",
                100.0 * n.fraction_steps_inside);
  }
}

// ---- PSM SLAM alone -----------------------------------------------------------------------------

/// A loop edge whose measurement is this far from the true relative pose of its nodes, and
/// farther than its covariance allows (χ²₃(0.999)), is wrong: along a corridor a match may be
/// off by more and say so in its covariance.
constexpr double kWrongLoopTranslation = 0.3;        // m
constexpr double kWrongLoopRotation = 5.0 * M_PI / 180.0;
constexpr double kWrongLoopChi2 = 16.27;

struct LoopEdgeCheck {
  size_t active = 0, inactive = 0;
  size_t wrong_active = 0, wrong_inactive = 0;
  double worst_active_miss = 0.0;  ///< m: largest distance of an active loop edge from the truth
};

LoopEdgeCheck checkLoopEdges(const PoseGraph& graph, const TrajectoryLookup& truth, bool print) {
  LoopEdgeCheck check;
  for (const PoseGraphEdge& e : graph.edges()) {
    if (!disownable(e.kind)) continue;  // loop closures and refinement edges
    (e.active ? check.active : check.inactive) += 1;
    const auto a = truth.interpolate(graph.node(e.from).utime, 100000);
    const auto b = truth.interpolate(graph.node(e.to).utime, 100000);
    if (!a || !b) continue;
    const Pose2 miss = between(between(*a, *b), e.measurement);
    const bool wrong = (miss.translation().norm() > kWrongLoopTranslation || std::abs(miss.theta) > kWrongLoopRotation) &&
                       edgeChiSquared(*a, *b, e) > kWrongLoopChi2;
    if (e.active) check.worst_active_miss = std::max(check.worst_active_miss, miss.translation().norm());
    if (wrong) (e.active ? check.wrong_active : check.wrong_inactive) += 1;
    if (wrong && print)
      std::printf("         wrong %s edge %lld -> %lld (%s): off the truth by %.2f m, %.1f deg (true nodes at %.2f %.2f "
                  "and %.2f %.2f, start frame)\n",
                  edgeKindName(e.kind), static_cast<long long>(e.from), static_cast<long long>(e.to),
                  e.active ? "active" : "disowned",
                  miss.translation().norm(), rad2deg(miss.theta), a->x, a->y, b->x, b->y);
  }
  return check;
}

void runPsmOnly(const Options& o, const std::string& world_path) {
  const World world = loadWorld(world_path);
  const RobotDescription robot = loadRobotDescription(o.robot);
  const PsmSlamEstimatorConfig config =
      o.psm_config.empty() ? PsmSlamEstimatorConfig{} : loadPsmSlamEstimatorConfig(o.psm_config);
  constexpr double kMaxErrorGoal = 1.0;  // m
  std::printf("\n=== PSM SLAM only: world %s, robot %s, %d seeds from %llu\n", world_path.c_str(), o.robot.c_str(),
              o.seeds, static_cast<unsigned long long>(o.first_seed));
  std::printf("%6s %8s %7s %7s | %6s %8s %6s %6s %6s %6s | %6s %6s %6s\n", "seed", "seconds", "ATE", "max", "loops",
              "ambiguous", "gated", "unconf", "refute", "disown", "edges", "wrong", "x real");
  std::vector<double> ate, max_error, speed;
  size_t over_goal = 0, accepted = 0, ambiguous = 0, gated = 0, unconfirmed = 0, refuted = 0, unfiltered_refuted = 0, unverified = 0, disowned = 0, wrong_active = 0,
         runs_without_loop = 0;
  for (int k = 0; k < o.seeds; ++k) {
    const uint64_t seed = o.first_seed + static_cast<uint64_t>(k);
    PsmSlamEstimator estimator(config);
    testing::EstimatorSimSink sink(estimator);
    Simulator sim(world, robot, seed);
    const double limit = o.seconds > 0 ? o.seconds : 3600.0;
    while (sim.time() < limit && !sim.finished()) sim.step(sink);
    nlohmann::json report;
    estimator.finish("", report);
    const std::vector<PoseStamped> truth = inStartFrame(sink.truth);
    const AteResult result = evaluateAte(estimator.trajectory(), truth);
    const PsmSlamStats& s = estimator.slam().stats();
    ate.push_back(result.raw_translation.rmse);
    max_error.push_back(result.raw_translation.max);
    speed.push_back(estimator.slamSeconds() > 0 ? sim.time() / estimator.slamSeconds() : 0.0);
    const bool over = max_error.back() > kMaxErrorGoal;
    over_goal += over;
    const LoopEdgeCheck edges = checkLoopEdges(estimator.slam().graph(), TrajectoryLookup(truth), false);
    accepted += s.loop_closures;
    runs_without_loop += s.loop_closures == 0;
    ambiguous += s.loop_ambiguous;
    gated += s.loop_gate_rejections;
    unconfirmed += s.loop_unconfirmed;
    refuted += s.loop_refuted;
    unfiltered_refuted += s.loop_unfiltered_refuted;
    unverified += s.loop_unverified;
    disowned += s.rejected_loop_edges;
    wrong_active += edges.wrong_active;
    std::printf("%6llu %8.1f %7.3f %7.3f | %6zu %8zu %6zu %6zu %6zu %6zu | %6zu %6zu %6.1f%s\n",
                static_cast<unsigned long long>(seed), sim.time(), ate.back(), max_error.back(), s.loop_closures,
                s.loop_ambiguous, s.loop_gate_rejections, s.loop_unconfirmed, s.loop_refuted, s.rejected_loop_edges, edges.active,
                edges.wrong_active, speed.back(), over ? "  OVER 1 m" : "");
    if (edges.wrong_active + edges.wrong_inactive > 0) checkLoopEdges(estimator.slam().graph(), TrajectoryLookup(truth), true);
    std::fflush(stdout);
  }
  const auto n = static_cast<double>(o.seeds);
  std::printf("\nPSM SLAM over %d seeds from %llu (%s)\n", o.seeds, static_cast<unsigned long long>(o.first_seed),
              world.name.c_str());
  std::printf("  %-48s %10zu   goal 0\n", "runs with maximum error above 1 m", over_goal);
  std::printf("  %-48s %10.3f   goal <= %.1f m\n", "worst maximum error (m)", *std::max_element(max_error.begin(), max_error.end()),
              kMaxErrorGoal);
  std::printf("  %-48s %10.3f   goal <= 0.10 m\n", "mean ATE (m)", mean(ate));
  std::printf("  %-48s %10zu   goal 0\n", "active loop/refinement edges off the truth", wrong_active);
  std::printf("  %-48s %10zu   goal 0 (every run closes its loop)\n", "runs without an accepted loop closure",
              runs_without_loop);
  std::printf("  %-48s %10.1f   goal >= 1\n", "loop closures accepted per run", static_cast<double>(accepted) / n);
  std::printf("  %-48s %10.1f   no goal: refusing is safe, wrong closures are not\n",
              "loop closures refused per run (ambiguous)", static_cast<double>(ambiguous) / n);
  std::printf("  %-48s %10.1f   no goal\n", "... refused by the chi2 gate", static_cast<double>(gated) / n);
  std::printf("  %-48s %10.1f   no goal\n", "... waiting for a second closure", static_cast<double>(unconfirmed) / n);
  std::printf("  %-48s %10.1f   no goal\n", "... refuted by a neighbouring reference scan", static_cast<double>(refuted) / n);
  std::printf("  %-48s %10.1f   no goal\n", "... refuted by the scans without the median filter",
              static_cast<double>(unfiltered_refuted) / n);
  std::printf("  %-48s %10.1f   no goal\n", "... unverified in a prior wider than the search", static_cast<double>(unverified) / n);
  std::printf("  %-48s %10.1f   no goal\n", "... (or refinement edges) disowned by the optimiser", static_cast<double>(disowned) / n);
  std::printf("  %-48s %10.1f   goal >= 1 (real time)\n", "speed (x real time, mean)", mean(speed));
}

// ---- Speed -----------------------------------------------------------------------------------------

/// A map of n point features on a grid around the robot, then timed updates that each observe
/// the 12 features nearest to the robot (association over all n features + batch update).
void timeUpdates(int n) {
  FeatureSlamParams params;
  params.confirm_observations = 1;
  FeatureSlam slam(params);
  std::mt19937_64 rng(n);
  std::normal_distribution<double> noise(0.0, 0.005);
  const int side = static_cast<int>(std::ceil(std::sqrt(n)));
  std::vector<Vec2> points;
  for (int i = 0; i < n; ++i) points.push_back({1.0 + 1.5 * (i % side) - 0.75 * side, 1.3 * (i / side) - 0.65 * side + 0.3});
  OdometryReading o;
  o.utime = 1'000'000;
  slam.addOdometry(o);
  FeatureSet all;
  all.utime = o.utime;
  for (const Vec2& p : points) {
    PointFeature f;
    f.x = p.x();
    f.y = p.y();
    f.cov = Mat2::Identity() * 2.5e-5;
    all.points.push_back(f);
  }
  slam.addFeatures(all);
  int updates = 0;
  double seconds = 0.0;
  for (int k = 1; k <= 40; ++k) {
    o.utime += 100'000;
    const double travel = 0.02 * k;
    o.left_travel = o.right_travel = travel;
    o.pose.x = travel;
    slam.addOdometry(o);
    std::vector<std::pair<double, Vec2>> nearest;
    for (const Vec2& p : points) nearest.emplace_back((p - Vec2(travel, 0)).norm(), p);
    std::partial_sort(nearest.begin(), nearest.begin() + 12, nearest.end(),
                      [](const auto& a, const auto& b) { return a.first < b.first; });
    FeatureSet set;
    set.utime = o.utime;
    for (int i = 0; i < 12; ++i) {
      PointFeature f;
      f.x = nearest[i].second.x() - travel + noise(rng);
      f.y = nearest[i].second.y() + noise(rng);
      f.cov = Mat2::Identity() * 2.5e-5;
      set.points.push_back(f);
    }
    const double before = slam.stats().update_seconds;
    slam.addFeatures(set);
    o.utime += 1;
    slam.addOdometry(o);  // lets the set through
    seconds += slam.stats().update_seconds - before;
    ++updates;
  }
  std::printf("%8d %10d %14.3f %14ld\n", static_cast<int>(slam.state().features().size()), slam.state().dimension(),
              1e3 * seconds / updates, slam.stats().paired / std::max<long>(1, slam.stats().updates - 1));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_slam: laser-only, sonar-only and fused EKF SLAM; consistency; speed"};
  Options o;
  bool speed_only = false, no_speed = false;
  app.add_option("--world", o.worlds, "world files, each run in turn")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--robot", o.robot)->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--seeds", o.seeds)->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--first-seed", o.first_seed)->capture_default_str();
  app.add_option("--seconds", o.seconds, "simulated seconds per run (0 = until the path ends)")->capture_default_str();
  app.add_option("--max-error", o.max_error_limit, "m: a run whose error ever exceeds this failed")->capture_default_str();
  app.add_option("--out", o.out, "write map.json and trajectory.tum of the first seed per configuration here");
  app.add_option("--psm-config", o.psm_config, "PSM SLAM parameters (YAML)")->check(CLI::ExistingFile);
  app.add_option("--nees-trace", o.nees_trace, "write PREFIX.<sensors>.csv: per-second NEES of the first seed");
  app.add_flag("--speed-only", speed_only, "only the update timing");
  app.add_flag("--psm-only", o.psm_only, "PSM SLAM alone over the seeds: wrong loop closures (issue 19); no speed table");
  app.add_flag("--no-speed", no_speed, "skip the update timing");
  CLI11_PARSE(app, argc, argv);
  try {
    if (o.psm_only) {
      for (const std::string& world : o.worlds) runPsmOnly(o, world);
      return 0;
    }
    if (!speed_only)
      for (const std::string& world : o.worlds) runClaim(o, world);
    if (!no_speed) {
      std::printf("\ntime per EKF update (association over all features + batch update of 12 point observations)\n");
      std::printf("%8s %10s %14s %14s\n", "features", "state dim", "ms / update", "paired/update");
      for (int n : {100, 300, 1000}) timeUpdates(n);
    }
  } catch (const std::exception& e) {
    std::cerr << "bench_slam: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
