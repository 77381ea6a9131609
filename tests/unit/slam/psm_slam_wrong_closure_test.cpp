// PSM SLAM on simulated worlds for seeds on which a wrong loop closure was once accepted. On the
// glass-partition loop (config/worlds/glass-partition-loop.yaml) a look-alike place was: coming
// round the north-west corner after the laser-blind glass corridor, the heading is uncertain by about 12°
// and the corridor 5 m north of the start, with its pilaster, fits the first reference scan as
// well as the right place does. Those runs ended 5 m off; the closure checks of
// docs/algorithms.md §18 (neighbouring reference scans, the prior's core) must refuse it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "estimator_sim_sink.hpp"
#include "eval/ate.hpp"
#include "eval/trajectory_lookup.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "robot/robot_description.hpp"
#include "psm_slam_sim.hpp"
#include "sim/simulator.hpp"
#include "slam/psm_slam.hpp"

namespace polarslam {
namespace {

/// Largest position error of the final trajectory, the truth taken in the start frame (where
/// PSM SLAM puts its map origin).
double maxPositionError(const std::vector<PoseStamped>& estimate, const std::vector<PoseStamped>& truth) {
  const TrajectoryLookup lookup(inStartFrame(truth));
  double worst = 0.0;
  for (const PoseStamped& p : estimate)
    if (const auto t = lookup.interpolate(p.utime, 100000))
      worst = std::max(worst, (t->translation() - p.pose.translation()).norm());
  return worst;
}

/// PSM SLAM (default parameters) over the whole simulated run of `world_file` with `seed`, the
/// graph optimised at the end; the sink keeps the truth.
void runPsmSlam(const std::string& world_file, uint64_t seed, PsmSlam& slam, testing::PsmSlamSimSink& sink) {
  testing::simulatePsmSlam(world_file, seed, sink);
  slam.optimize();
}

// With slopes over 5 cm and residual-scaled weights (core/scanmatch/README.md), seed 1091 came
// round the corner with a 3 m prior, and two scans 0.65 m apart fitted the look-alike, its
// neighbouring reference scans agreeing: from so wide a prior the second closure must now come
// from 2 m farther along the path (loop_wide_confirm_distance), where the look-alike no longer fits.
TEST(PsmSlamWrongClosure, LookAlikeCorridorIsNotTakenForTheStart) {
  PsmSlamParams matcher_options;
  matcher_options.psm.slope_half_span = 0.05;
  matcher_options.psm.adaptive_weighting_scale = 4.0;
  for (const PsmSlamParams& params : {PsmSlamParams{}, matcher_options}) {
    for (const uint64_t seed : {1033u, 1058u, 1091u, 1092u}) {
      PsmSlam slam(params);
      testing::PsmSlamSimSink sink(slam);
      runPsmSlam("glass-partition-loop.yaml", seed, slam, sink);
      ASSERT_FALSE(sink.truth.empty());
      const std::string run = "seed " + std::to_string(seed) + ", slopes over " + std::to_string(params.psm.slope_half_span);
      EXPECT_LT(maxPositionError(slam.trajectory(), sink.truth), 1.0) << run;
      EXPECT_GE(slam.stats().loop_closures, 1u) << run << ": the right closure is still taken";
    }
  }
}

// Seeds (of 5000–5099, never used for tuning) on which the laser alone, blind in the glass
// corridor, let the look-alike closure through and the runs ended 5 m off. With the default
// configuration the sonar's planes fill the scans the laser sees little in (sonar.fill_planes).
// On 5051 they do, but the look-alike closure (σ 1.3 m, no neighbouring reference scan matched)
// still passed until loop_unverified_max_extent was 3 m rather than the search disc's 4 m.
TEST(PsmSlamWrongClosure, SonarPlanesCarryTheLaserThroughTheGlassCorridor) {
  const World world = loadWorld(std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/glass-partition-loop.yaml");
  const RobotDescription robot = loadRobotDescription(std::string(POLARSLAM_SOURCE_DIR) + "/config/robots/default.yaml");
  for (const uint64_t seed : {5010u, 5039u, 5061u, 5051u}) {
    PsmSlamEstimator estimator(PsmSlamEstimatorConfig{});
    testing::EstimatorSimSink sink(estimator);
    Simulator sim(world, robot, seed);
    while (!sim.finished() && sim.time() < 600.0) sim.step(sink);
    nlohmann::json report;
    estimator.finish("", report);
    ASSERT_FALSE(sink.truth.empty());
    EXPECT_LT(maxPositionError(estimator.trajectory(), sink.truth), 1.0) << "seed " << seed;
    EXPECT_GT(report["psm_slam"].value("sonar_filled_readings", size_t{0}), 0u) << "seed " << seed << ": " << report.dump();
  }
}

// Seeds of the office (config/worlds/office.yaml) on which the robot, turning at the west end of
// the start corridor on its way back, was tracked against a reference scan for which PSM also
// converges 0.3 m along the corridor with a 1 cm covariance: taken as an odometry fault, that
// match put the filter 0.35 m off, and the loop closed to the start's reference scan at that
// offset. The odometry's pose fits that scan about as well, so the odometry is believed
// (odometry_fault_fit_ratio) and the closure lands where the robot is.
TEST(PsmSlamWrongClosure, TrackingBelievesTheOdometryWhereTheScanFitsTwoPlaces) {
  for (const uint64_t seed : {1013u, 1016u, 1026u, 1031u, 1034u}) {
    PsmSlam slam;
    testing::PsmSlamSimSink sink(slam);
    runPsmSlam("office.yaml", seed, slam, sink);
    ASSERT_FALSE(sink.truth.empty());
    EXPECT_EQ(testing::edgesOffTheTruth(slam.graph(), sink.truth, PoseGraphEdgeKind::Loop), 0u) << "seed " << seed;
    EXPECT_GE(slam.stats().loop_closures, 1u) << "seed " << seed;
    EXPECT_LT(maxPositionError(slam.trajectory(), sink.truth), 0.75) << "seed " << seed;
  }
}

// Office seed 8159 (of 8000-8299, never used for tuning): a return scan 2 m from the start
// corridor's reference scan fitted it 0.4 m along the corridor. The median filter had removed a
// door jamb, 1-2 readings wide at that range, from one view and kept it in the other. Matched
// again from the prior with the raw ranges, the pair lands where the robot is, which refutes the
// closure (loop_check_unfiltered); without that check a wrong edge is in the graph. (Seed 8297
// showed it until the WLS covariance lost the slope noise's information, slope_noise_correction.)
TEST(PsmSlamWrongClosure, ClosuresHoldWithoutTheMedianFilter) {
  for (const bool check : {true, false}) {
    PsmSlamParams params;
    params.loop_check_unfiltered = check;
    PsmSlam slam(params);
    testing::PsmSlamSimSink sink(slam);
    runPsmSlam("office.yaml", 8159, slam, sink);
    ASSERT_FALSE(sink.truth.empty());
    const size_t wrong = testing::edgesOffTheTruth(slam.graph(), sink.truth, PoseGraphEdgeKind::Loop);
    if (check) {
      EXPECT_EQ(wrong, 0u);
      EXPECT_GE(slam.stats().loop_unfiltered_refuted, 1u);
      EXPECT_GE(slam.stats().loop_closures, 1u);
    } else {
      EXPECT_GE(wrong, 1u) << "the seed no longer shows the door jamb's closure: pick another";
      EXPECT_EQ(slam.stats().loop_unfiltered_refuted, 0u);
    }
  }
}

}  // namespace
}  // namespace polarslam
