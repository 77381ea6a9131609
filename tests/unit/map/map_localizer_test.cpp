// Localisation in a stored map and mapping on from it (issue 15, items 2-3): a simulated corridor
// loop is mapped once, then other runs in the same building are localised in that map (from an
// unknown start, and after the robot is carried elsewhere while its odometry noticed nothing) or
// continue it.
#include <gtest/gtest.h>

#include <cstdio>
#include <optional>
#include <random>

#include "map/map_store.hpp"
#include "pipeline/map_continuation_estimator.hpp"
#include "pipeline/map_localization_estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "slam/map_localizer.hpp"
#include "unit/slam/synthetic_run.hpp"

namespace polarslam {
namespace {

using testing::SyntheticRun;
using testing::SyntheticRunOptions;

PsmSlamEstimatorConfig testConfig() {
  PsmSlamEstimatorConfig c;
  c.slam.odometry.poses = testing::syntheticOdometryModel();
  return c;
}

/// `refined`: mapped with the refinement (GraphRefinementParams) on.
StoredMap storedMapOfOneLap(bool refined = false) {
  SyntheticRunOptions options;
  options.seed = 7;
  const SyntheticRun run = testing::simulateLoopRun(testing::makeLoopWorld(), options);
  PsmSlamEstimatorConfig config = testConfig();
  config.slam.refinement.enabled = refined;
  PsmSlamEstimator mapping(config);
  for (size_t k = 0; k < run.scans.size(); ++k) {
    mapping.onOdometry(run.odometry[k]);
    mapping.onLaser(run.scans[k]);
  }
  nlohmann::json report;
  mapping.finish("", report);
  return mapping.storedMap();
}

std::vector<MapReference> mapOfOneLap() { return mapReferences(storedMapOfOneLap()); }

/// The loop's true path in the world (the mapping run started at its first pose).
std::vector<Pose2> loopPathInWorld(int laps) {
  SyntheticRunOptions options;
  options.laps = laps;
  return testing::loopPath(options);
}

/// A run along `path` (world poses) whose odometry sees every step but `hidden_step` (the kidnap:
/// the robot was carried, the wheels did not turn), moved by `odometry_frame`. Its truth is in
/// the map frame: the world seen from where the mapping run started.
SyntheticRun runAlong(const std::vector<Pose2>& path, size_t hidden_step, const Pose2& odometry_frame, uint64_t seed) {
  const Pose2 map_from_world = loopPathInWorld(1).front().inverse();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  SyntheticRunOptions options;
  const World world = testing::makeLoopWorld();
  SyntheticRun run;
  Pose2 odometry = odometry_frame;
  const int64_t t0 = 2'000'000'000'000'000, period = 200'000;
  for (size_t k = 0; k < path.size(); ++k) {
    if (k > 0 && k != hidden_step)
      odometry = odometry * testing::noisyOdometryStep(between(path[k - 1], path[k]), options, rng, unit);
    const int64_t utime = t0 + static_cast<int64_t>(k) * period;
    run.odometry.push_back({utime, static_cast<int64_t>(k), odometry, Mat3::Zero(), 0.0, 0.0, 0.0, 0.0});
    run.scans.push_back(testing::castScan(world, path[k], options, rng, utime));
    run.truth.push_back(map_from_world * path[k]);
  }
  return run;
}

/// A second run in the building: two laps starting 40 scans into the loop (not at the map's
/// origin), its odometry moved far away.
SyntheticRun runFromMidLoop(uint64_t seed) {
  std::vector<Pose2> path = loopPathInWorld(2);
  path.erase(path.begin(), path.begin() + 40);
  return runAlong(path, 0, Pose2(150.0, -80.0, 2.5), seed);
}

struct Localised {
  std::vector<MapLocalizationResult> results;
  MapLocalizerStats stats;
};

Localised localise(const std::vector<MapReference>& map, const SyntheticRun& run) {
  MapLocalizer localizer(map, testConfig().slam);
  Localised out;
  for (size_t k = 0; k < run.scans.size(); ++k) {
    localizer.addOdometry(run.odometry[k]);
    out.results.push_back(localizer.addScan(run.scans[k]));
  }
  out.stats = localizer.stats();
  return out;
}

double distance(const Pose2& a, const Pose2& b) { return (a.translation() - b.translation()).norm(); }

// The loop is nearly symmetric: the global search refuses look-alike places until one fits
// unambiguously, and still finds the start within issue 15's 10 scans.
TEST(MapLocalizer, FindsAnUnknownStartAndThenTracksTheMap) {
  const std::vector<MapReference> map = mapOfOneLap();
  const SyntheticRun run = runFromMidLoop(21);
  const Localised loc = localise(map, run);
  ASSERT_GE(loc.stats.first_fix_scan, 0) << "never found";
  EXPECT_LT(loc.stats.first_fix_scan, 10) << "issue 15: the start is found within 10 scans";
  std::printf("unknown start found at scan %lld (%zu ambiguous searches)\n",
              static_cast<long long>(loc.stats.first_fix_scan), loc.stats.global_ambiguous);
  for (size_t k = 0; k < run.scans.size(); ++k) {
    EXPECT_EQ(loc.results[k].localized, k >= static_cast<size_t>(loc.stats.first_fix_scan)) << "scan " << k;
    if (loc.results[k].localized) {
      EXPECT_LT(distance(loc.results[k].pose.pose, run.truth[k]), 0.10) << "m from the truth at scan " << k;
    }
  }
  EXPECT_EQ(loc.stats.losses, 0u);
}

// A map whose grids would not fit in memory (one reference scan 100 km off, a corrupted pose that
// passed its checksum, or a campus far wider than 410 m) is refused at once with a clear error,
// rather than allocating gigabytes or hanging.
TEST(MapLocalizer, AMapTooWideForItsGridsIsRefusedWithAClearError) {
  const std::vector<MapReference> map = mapOfOneLap();
  for (const double x : {1e5, 1e12, 1e300}) {
    std::vector<MapReference> spread = map;
    spread[3].pose.x = x;
    try {
      MapLocalizer localizer(spread, testConfig().slam);
      ADD_FAILURE() << "a map reaching x = " << x << " m was accepted";
    } catch (const std::length_error& e) {
      EXPECT_NE(std::string(e.what()).find("more than max_cells"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("the map spans"), std::string::npos) << e.what();
    }
  }
}

TEST(MapLocalizer, AKnownStartTracksFromTheFirstScanWithoutSearching) {
  const std::vector<MapReference> map = mapOfOneLap();
  const std::vector<Pose2> path = loopPathInWorld(1);
  const SyntheticRun run = runAlong(path, 0, Pose2(), 22);
  MapLocalizer localizer(map, testConfig().slam);
  localizer.setInitialPose(run.truth.front(), Vec3(0.01, 0.01, 1e-4).asDiagonal());
  double worst = 0.0;
  for (size_t k = 0; k < run.scans.size(); ++k) {
    localizer.addOdometry(run.odometry[k]);
    const Pose2 got = localizer.addScan(run.scans[k]).pose.pose;
    if (distance(got, run.truth[k]) > 0.1) ADD_FAILURE() << k << " got " << got.x << "," << got.y << " truth " << run.truth[k].x << "," << run.truth[k].y;
    worst = std::max(worst, distance(got, run.truth[k]));
  }
  EXPECT_EQ(localizer.stats().global_searches, 0u);
  EXPECT_LT(worst, 0.10);
}

/// 20 runs along the loop, each with the robot carried 4-12 m along it mid-run (scans of the path
/// skipped) while its odometry notices nothing.
struct Kidnapping {
  uint64_t seed = 0;
  size_t kidnap = 0;     ///< first scan after the robot was carried
  double carried = 0.0;  ///< m
  SyntheticRun run;
};

std::vector<Kidnapping> kidnappings() {
  const std::vector<Pose2> path = loopPathInWorld(3);
  std::mt19937_64 pick(15);
  std::vector<Kidnapping> out;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const size_t kidnap = 60 + pick() % 40, carried = 40 + pick() % 80;
    std::vector<Pose2> truth(path.begin(), path.begin() + static_cast<long>(kidnap));
    truth.insert(truth.end(), path.begin() + static_cast<long>(kidnap + carried),
                 path.begin() + static_cast<long>(std::min(path.size(), kidnap + carried + 150)));
    out.push_back({seed, kidnap, distance(path[kidnap - 1], path[kidnap + carried]), runAlong(truth, kidnap, Pose2(), 100 + seed)});
  }
  return out;
}

/// How soon each kidnapping was noticed and the robot found again: printed per seed and in all.
class KidnapTally {
 public:
  void add(const Kidnapping& k, size_t noticed, std::optional<size_t> found_again) {
    std::printf("seed %2llu: carried %.1f m, noticed after %zu scans, found again after %lld\n",
                static_cast<unsigned long long>(k.seed), k.carried, noticed - k.kidnap,
                found_again ? static_cast<long long>(*found_again - k.kidnap) : -1LL);
    latest_notice_ = std::max(latest_notice_, noticed - k.kidnap);
    if (found_again && *found_again - k.kidnap <= 20) ++found_within_20_;
  }
  size_t foundWithin20() const { return found_within_20_; }
  void print(const char* who) const {
    std::printf("%s: kidnap noticed within %zu scans on every seed; found again within 20 scans on %zu of 20 seeds\n", who,
                latest_notice_, found_within_20_);
  }

 private:
  size_t latest_notice_ = 0, found_within_20_ = 0;
};

// 20 seeds: the robot is carried 4-12 m along the loop mid-run while its odometry notices nothing.
// The localiser notices (a doubt search finds the scans fit a place elsewhere much better; or they
// match nothing), flags its poses as odometry only, and no fix, ever, is more than 0.3 m from the
// truth (no wrong lock-on). Issue 15's goal: found again within 20 scans on every seed.
TEST(MapLocalizer, AKidnappedRobotIsNoticedAndNeverLocksOnAWrongPlace) {
  const std::vector<MapReference> map = mapOfOneLap();
  KidnapTally tally;
  for (const Kidnapping& kidnapping : kidnappings()) {
    const SyntheticRun& run = kidnapping.run;
    const size_t kidnap = kidnapping.kidnap;
    const uint64_t seed = kidnapping.seed;
    MapLocalizer localizer(map, testConfig().slam);
    localizer.setInitialPose(run.truth.front(), Vec3(0.01, 0.01, 1e-4).asDiagonal());
    std::optional<size_t> noticed, found_again;
    for (size_t k = 0; k < run.scans.size(); ++k) {
      localizer.addOdometry(run.odometry[k]);
      const MapLocalizationResult r = localizer.addScan(run.scans[k]);
      if (k < kidnap) {
        EXPECT_TRUE(r.localized) << "seed " << seed << ", scan " << k;
      }
      if (k >= kidnap && !r.localized && !noticed) noticed = k;
      if (r.found) {
        EXPECT_LT(distance(r.pose.pose, run.truth[k]), 0.3) << "seed " << seed << ": a wrong lock-on at scan " << k;
        if (k >= kidnap && !found_again) found_again = k;
      }
    }
    ASSERT_TRUE(noticed) << "seed " << seed << ": the kidnap at scan " << kidnap << " went unnoticed";
    tally.add(kidnapping, *noticed, found_again);
  }
  tally.print("MapLocalizer");
  EXPECT_EQ(tally.foundWithin20(), 20u) << "issue 15: every kidnap recovered within 20 scans";
}

/// Feeds `run` to `estimator` and finishes it; the report.
nlohmann::json runThrough(Estimator& estimator, const SyntheticRun& run) {
  for (size_t k = 0; k < run.scans.size(); ++k) {
    estimator.onOdometry(run.odometry[k]);
    estimator.onLaser(run.scans[k]);
  }
  nlohmann::json report;
  estimator.finish("", report);
  return report;
}

PsmSlamEstimatorConfig temporaryMappingConfig() {
  PsmSlamEstimatorConfig c = testConfig();
  c.slam.localization.temporary_mapping = true;
  return c;
}

// --mode localize with localization.temporary_mapping (map_localization_estimator.hpp): PSM SLAM
// over the map held fixed, with temporary reference scans. The map does not move and nothing joins it.
TEST(MapLocalization, AKnownStartTracksOverTheFixedMap) {
  const StoredMap map = storedMapOfOneLap();
  const SyntheticRun run = runFromMidLoop(33);
  MapLocalizationEstimator localization(map, temporaryMappingConfig(), run.truth.front());
  const nlohmann::json report = runThrough(localization, run);
  const std::vector<PoseStamped>& poses = localization.trajectory();
  ASSERT_EQ(poses.size(), run.truth.size());
  double worst = 0.0, worst_online = 0.0;
  for (size_t k = 0; k < poses.size(); ++k) {
    worst = std::max(worst, distance(poses[k].pose, run.truth[k]));
    worst_online = std::max(worst_online, distance(localization.onlineTrajectory()[k].pose, run.truth[k]));
  }
  std::printf("known start, localised: worst %.3f m online, %.3f m final\n", worst_online, worst);
  EXPECT_LT(worst, 0.10) << "m from the truth, in the map's frame";
  EXPECT_LT(worst_online, 0.10);
  EXPECT_EQ(report["localization"]["tracking_losses"].get<size_t>(), 0u) << report.dump();
  EXPECT_GT(report["psm_slam"]["map_loop_closures"].get<size_t>(), 10u) << report["psm_slam"].dump();
  EXPECT_EQ(localization.map().graph.nodes().size(), map.graph.nodes().size());
}

/// The kidnappings localised by temporary mapping (the default) in `map`: every pose before the
/// kidnap placed within 0.1 m, every pose from the fix on within 0.3 m of the truth (no wrong
/// lock-on); how soon each was noticed and found again.
KidnapTally kidnapsWithTemporaryMapping(const StoredMap& map) {
  KidnapTally tally;
  for (const Kidnapping& kidnapping : kidnappings()) {
    const SyntheticRun& run = kidnapping.run;
    const size_t kidnap = kidnapping.kidnap;
    const uint64_t seed = kidnapping.seed;
    MapLocalizationEstimator localization(map, temporaryMappingConfig(), run.truth.front(), Vec3(0.01, 0.01, 1e-4).asDiagonal());
    runThrough(localization, run);
    const std::vector<bool>& placed = localization.localizedFlags();
    std::optional<size_t> noticed, found_again;
    for (size_t k = 0; k < run.scans.size(); ++k) {
      if (k < kidnap) {
        EXPECT_TRUE(placed[k]) << "seed " << seed << ", scan " << k;
        EXPECT_LT(distance(localization.trajectory()[k].pose, run.truth[k]), 0.10) << "seed " << seed << ", scan " << k;
      }
      if (k >= kidnap && !placed[k] && !noticed) noticed = k;
      if (noticed && placed[k] && !found_again) found_again = k;
      if (found_again) {
        EXPECT_LT(distance(localization.onlineTrajectory()[k].pose, run.truth[k]), 0.3)
            << "seed " << seed << ": a wrong lock-on, scan " << k;
      }
    }
    EXPECT_TRUE(noticed) << "seed " << seed << ": the kidnap at scan " << kidnap << " went unnoticed";
    if (noticed) tally.add(kidnapping, *noticed, found_again);
  }
  return tally;
}

// The kidnap of MapLocalizer.AKidnappedRobotIsNoticedAndNeverLocksOnAWrongPlace with temporary
// mapping (the default): scans near the map without a match with it lose the robot, the global
// search finds it again, and every pose from a fix on is where the robot is. How soon is printed
// (issue 15's goal: found again within 20 scans on every seed; with doubt_max_fit 0.9 one seed
// was noticed late, its tracked pose along a look-alike stretch fitting 90-94 % of the scan).
TEST(MapLocalization, AKidnappedRobotIsNoticedAndFoundAgainWhereItIs) {
  const KidnapTally tally = kidnapsWithTemporaryMapping(storedMapOfOneLap());
  tally.print("temporary mapping");
  EXPECT_EQ(tally.foundWithin20(), 20u) << "issue 15: every kidnap recovered within 20 scans";
}

// The same in a map made with the refinement: its look-alike places match each other better, so the
// searches while lost stay ambiguous longer (seed 20: 16 scans). A hit from scans seen along 1.5 m
// needs no confirming search (confirm_sequence_length); with one, seed 20 was found after 22 scans.
TEST(MapLocalization, AKidnappedRobotIsFoundAgainInARefinedMapToo) {
  const KidnapTally tally = kidnapsWithTemporaryMapping(storedMapOfOneLap(true));
  tally.print("temporary mapping, refined map");
  EXPECT_EQ(tally.foundWithin20(), 20u) << "issue 15: every kidnap recovered within 20 scans";
}

// The drifted stretch before a loss, re-placed when the fix explains the loss as drift: the
// correction grows along it with the weights, none before the first weight, all of it at the end.
TEST(MapLocalization, ACorrectionIsSpreadAlongTheStretchByItsWeights) {
  std::vector<PoseStamped> poses;
  for (int i = 1; i <= 4; ++i) poses.push_back({i, Pose2(i, 0.0, 0.0), Mat3::Zero()});
  const std::vector<PoseStamped> before = poses;
  const Pose2 corrected(4.0, 0.4, 0.0);  // the last pose 0.4 m off sideways, no turn
  spreadCorrection(poses, Vec2(0.0, 0.0), corrected, {0.0, 0.0, 1.0, 1.0});
  auto same = [](const Pose2& a, const Pose2& b) { return distance(a, b) < 1e-12 && std::abs(a.theta - b.theta) < 1e-12; };
  EXPECT_TRUE(same(poses[0].pose, before[0].pose));
  EXPECT_TRUE(same(poses[1].pose, before[1].pose));
  EXPECT_NEAR(poses[2].pose.y, 0.2, 1e-12);
  EXPECT_NEAR(poses[2].pose.x, 3.0, 1e-12);
  EXPECT_TRUE(same(poses[3].pose, corrected));

  // A turn is spread too, about the pivot: with equal weights the first of four poses turns by a
  // quarter of it and keeps its distance from the pivot (no translation left at the end).
  poses = before;
  const double turn = deg2rad(8.0);
  const Pose2 turned(4.0 * std::cos(turn), 4.0 * std::sin(turn), turn);
  spreadCorrection(poses, Vec2(0.0, 0.0), turned, {1.0, 1.0, 1.0, 1.0});
  EXPECT_NEAR(poses[0].pose.theta, turn / 4.0, 1e-12);
  EXPECT_NEAR(poses[0].pose.translation().norm(), 1.0, 1e-12);
  EXPECT_NEAR(std::atan2(poses[1].pose.y, poses[1].pose.x), turn / 2.0, 1e-12);
  EXPECT_NEAR(distance(poses[3].pose, turned), 0.0, 1e-12);

  // No weight anywhere: the whole stretch moves rigidly with its end.
  poses = before;
  spreadCorrection(poses, Vec2(0.0, 0.0), corrected, {0.0, 0.0, 0.0, 0.0});
  for (const PoseStamped& p : poses) EXPECT_NEAR(p.pose.y, 0.4, 1e-12);
}

TEST(MapContinuation, AKnownStartMapsOnInTheMapsFrameAndClosesLoopsWithIt) {
  const StoredMap map = storedMapOfOneLap();
  const SyntheticRun run = runFromMidLoop(31);
  MapContinuationEstimator continuation(map, testConfig(), run.truth.front());
  const nlohmann::json report = runThrough(continuation, run);
  const std::vector<PoseStamped>& poses = continuation.trajectory();
  ASSERT_EQ(poses.size(), run.truth.size());
  double worst = 0.0;
  for (size_t k = 0; k < poses.size(); ++k) worst = std::max(worst, distance(poses[k].pose, run.truth[k]));
  EXPECT_LT(worst, 0.10) << "m from the truth, in the map's frame";
  EXPECT_GT(report["psm_slam"]["map_loop_closures"].get<size_t>(), 10u) << report["psm_slam"].dump();
  // The map grows: its nodes and reference scans stay, new ones join them.
  const StoredMap extended = continuation.mappingEstimator().storedMap();
  EXPECT_GT(extended.graph.nodes().size(), map.graph.nodes().size());
  EXPECT_EQ(extended.scans.size(), extended.graph.nodes().size());
  // The map's poses are known to about a millimetre in the filter (PsmSlam::continueMap).
  EXPECT_LT(distance(extended.graph.node(0).pose, map.graph.node(0).pose), 1e-3) << "the map frame moved";
}

TEST(MapContinuation, AnUnknownStartIsSearchedFirstThenMappingGoesOn) {
  const StoredMap map = storedMapOfOneLap();
  const SyntheticRun run = runFromMidLoop(32);
  MapContinuationEstimator continuation(map, testConfig(), std::nullopt);
  const nlohmann::json report = runThrough(continuation, run);
  const std::vector<PoseStamped>& poses = continuation.trajectory();
  ASSERT_TRUE(continuation.mapping()) << "the start was never found";
  const size_t found = report["localization"]["scans_before_mapping"].get<size_t>();
  ASSERT_GT(found, 0u);
  std::printf("continuing from an unknown start: found at scan %zu\n", found - 1);
  ASSERT_EQ(poses.size(), run.truth.size());
  for (size_t k = found - 1; k < poses.size(); ++k)
    EXPECT_LT(distance(poses[k].pose, run.truth[k]), 0.10) << "m from the truth at scan " << k;
}

TEST(MapContinuation, AMapWhoseNodesLackTheirScansIsRefused) {
  StoredMap map = storedMapOfOneLap();
  map.scans.pop_back();
  EXPECT_THROW(MapContinuationEstimator(map, testConfig(), Pose2()), std::invalid_argument);
}

}  // namespace
}  // namespace polarslam
