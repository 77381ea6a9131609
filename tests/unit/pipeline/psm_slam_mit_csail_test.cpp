// PSM SLAM on the MIT CSAIL log against its Kümmerle relations (the figure scripts/bench-psm-slam
// prints), so that a change that makes the real-data accuracy worse fails here. Measured
// 0.0276 m / 0.360°; guarded at Cartographer's published 0.032 m and 0.40° (issue 19 asks for a
// guard at 0.015 m once the error is below 0.010 m). Skipped when the public logs are absent.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "eval/relation_metric.hpp"
#include "io/carmen.hpp"
#include "io/relations.hpp"
#include "pipeline/psm_slam_estimator.hpp"

namespace polarslam {
namespace {

constexpr double kGuardTranslation = 0.032;  ///< m, mean relation error
constexpr double kGuardRotation = 0.40;      ///< deg

TEST(PsmSlamMitCsail, RelationErrorStaysWithinTheGuard) {
  const std::string dir = std::string(POLARSLAM_SHARED_DATA_DIR) + "/mit-csail";
  const std::string log_path = dir + "/mit-csail.clf", relations_path = dir + "/mit-csail.relations";
  if (!std::filesystem::exists(log_path) || !std::filesystem::exists(relations_path))
    GTEST_SKIP() << "shared data absent: " << log_path << " or " << relations_path
                 << " (the public logs live in ../shared/data next to the project)";
  const CarmenLog log = readCarmenLogFile(log_path);
  PsmSlamEstimator estimator;  // the defaults, which config/psm-slam.yaml equals
  for (const auto& e : log.events) {
    if (e.isLaser()) estimator.onLaser(e.laser());
    else estimator.onOdometry(e.odometry());
  }
  nlohmann::json report;
  estimator.finish("", report);
  const RelationMetric metric = evaluateRelations(estimator.trajectory(), readRelations(relations_path));
  EXPECT_GT(metric.evaluated, 1100u);
  EXPECT_LT(metric.translation.mean, kGuardTranslation) << "MIT CSAIL relation error (m), scripts/bench-psm-slam";
  EXPECT_LT(metric.rotation_deg.mean, kGuardRotation) << "MIT CSAIL relation error (deg)";
}

}  // namespace
}  // namespace polarslam
