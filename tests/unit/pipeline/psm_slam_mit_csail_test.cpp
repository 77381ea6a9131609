// PSM SLAM on the MIT CSAIL log against its Kümmerle relations (the figure scripts/bench-psm-slam
// prints), so that a change that makes the real-data accuracy worse fails here. Measured
// 0.0282 m / 0.364°; guarded at Cartographer's published 0.032 m and 0.40° (issue 19 asks for a
// guard at 0.015 m once the error is below 0.010 m). And issue 15's check, as scripts/bench-localize
// runs it: the first half mapped, the second localised in that map. Skipped when the public logs
// are absent.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "eval/relation_metric.hpp"
#include "io/carmen.hpp"
#include "io/relations.hpp"
#include "pipeline/map_then_localize.hpp"
#include "pipeline/psm_slam_estimator.hpp"

namespace polarslam {
namespace {

constexpr double kGuardTranslation = 0.032;  ///< m, mean relation error
constexpr double kGuardRotation = 0.40;      ///< deg

const std::string kDir = std::string(POLARSLAM_SHARED_DATA_DIR) + "/mit-csail";
const std::string kLogPath = kDir + "/mit-csail.clf", kRelationsPath = kDir + "/mit-csail.relations";

class PsmSlamMitCsail : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kLogPath) || !std::filesystem::exists(kRelationsPath))
      GTEST_SKIP() << "shared data absent: " << kLogPath << " or " << kRelationsPath
                   << " (the public logs live in ../shared/data next to the project)";
  }
};

/// Full-run PSM SLAM's final trajectory over `log`.
std::vector<PoseStamped> fullRun(const CarmenLog& log, const PsmSlamEstimatorConfig& config) {
  PsmSlamEstimator estimator(config);
  runOverLog(estimator, log.events);
  return estimator.trajectory();
}

TEST_F(PsmSlamMitCsail, RelationErrorStaysWithinTheGuard) {
  // The defaults, which config/psm-slam.yaml equals.
  const RelationMetric metric = evaluateRelations(fullRun(readCarmenLogFile(kLogPath), {}), readRelations(kRelationsPath));
  EXPECT_GT(metric.evaluated, 1100u);
  EXPECT_LT(metric.translation.mean, kGuardTranslation) << "MIT CSAIL relation error (m), scripts/bench-psm-slam";
  EXPECT_LT(metric.rotation_deg.mean, kGuardRotation) << "MIT CSAIL relation error (deg)";
}

// Issue 15: the first half of the log mapped, the second half localised in that map with its
// odometry moved far away. The start is found within 10 scans, and the joined trajectory (one
// frame) is within 1.25x full-run SLAM's relation error, relations across the halves included;
// from the known start too. Measured 1.10x and 1.07x (the first half's map closes the loop its
// last seconds make only with loop_min_overlap 0.15; with 0.3 it ended 1-1.5 m off: 1.76x, 2.11x).
TEST_F(PsmSlamMitCsail, TheSecondHalfLocalisedInTheFirstHalfsMapKeepsTheRelationError) {
  const CarmenLog log = readCarmenLogFile(kLogPath);
  const std::vector<Relation> relations = readRelations(kRelationsPath);
  const PsmSlamEstimatorConfig config = loadPsmSlamEstimatorConfig(std::string(POLARSLAM_SOURCE_DIR) + "/config/psm-slam.yaml");
  const int64_t split = halfwayLaserTime(log.events);
  const double full = evaluateRelations(fullRun(log, config), relations).translation.mean;
  MapThenLocalizeOptions options;
  options.odometry_moved_by = kOdometryFarAway;
  for (const bool known_start : {false, true}) {
    options.known_start = known_start;
    const MapThenLocalizeResult result = mapThenLocalize(log.events, split, config, options);
    const double joined = evaluateRelations(result.joined, relations).translation.mean;
    std::printf("%s start: first fix at scan %lld, joined %.4f m, full run %.4f m: %.2fx\n", known_start ? "known" : "unknown",
                static_cast<long long>(result.first_fix_scan), joined, full, joined / full);
    if (!known_start) {
      EXPECT_GE(result.first_fix_scan, 0) << "the start was never found";
      EXPECT_LT(result.first_fix_scan, 10) << "scans into the second half";
    }
    EXPECT_LE(joined, 1.25 * full) << (known_start ? "known" : "unknown") << " start: joined " << joined << " m, full run "
                                   << full << " m";
  }
}

}  // namespace
}  // namespace polarslam
