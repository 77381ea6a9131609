// The configuration files shipped in config/ list every key of their component with its
// built-in default (as Cartographer's configuration files do), so a user reading one reads what
// the programs run with.
#include <gtest/gtest.h>

#include <fstream>

#include "source_path.hpp"
#include "pipeline/feature_slam_estimator.hpp"
#include "pipeline/pipelines.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "robot/robot_description.hpp"

namespace polarslam {
namespace {

using testing::sourcePath;

TEST(ShippedConfig, PsmSlamFileListsEveryKeyWithItsDefault) {
  const YamlFields file(sourcePath("config/psm-slam.yaml"));
  PsmSlamEstimatorConfig defaults;
  ParameterTable table;
  describePsmSlamEstimatorConfig(table, defaults);
  EXPECT_TRUE(table.missingFrom(file.root()).empty())
      << "config/psm-slam.yaml lacks " << ::testing::PrintToString(table.missingFrom(file.root()));
  PipelineOptions options;
  options.config = sourcePath("config/psm-slam.yaml");
  EXPECT_EQ(effectiveConfigYaml("psm-slam", options), table.yaml()) << "a value differs from its default";
}

TEST(ShippedConfig, EkfFileListsEveryKeyWithItsDefault) {
  const YamlFields file(sourcePath("config/ekf.yaml"));
  FeaturePipelineConfig defaults;
  FeaturePipelineTables tables;
  describeFeaturePipeline(tables, defaults);
  EXPECT_TRUE(tables.ekf.missingFrom(file.root()["ekf"]).empty());
  EXPECT_TRUE(tables.fusion.missingFrom(file.root()["fusion"]).empty());
  // The laser's error model comes from the robot file the pipeline file names.
  defaults.laser.errors = laserErrorParams(loadRobotDescription(sourcePath("config/robots/default.yaml")).laser);
  PipelineOptions options;
  options.config = sourcePath("config/ekf.yaml");
  EXPECT_EQ(effectiveConfigYaml("ekf", options), "ekf:\n" + tables.ekf.yaml(2) + "fusion:\n" + tables.fusion.yaml(2) +
                                                     "laser_features:\n" + tables.laser_features.yaml(2));
}

TEST(ShippedConfig, LaserFeaturesFileListsEveryKeyWithItsDefault) {
  const YamlFields file(sourcePath("config/laser-features.yaml"));
  LaserFeatureConfig defaults;
  ParameterTable table;
  describeLaserFeatures(table, defaults);
  EXPECT_TRUE(table.missingFrom(file.root()["laser_features"]).empty())
      << "config/laser-features.yaml lacks " << ::testing::PrintToString(table.missingFrom(file.root()["laser_features"]));
  LaserFeatureConfig loaded = loadLaserFeatureConfig(sourcePath("config/laser-features.yaml"));
  ParameterTable loaded_table;
  describeLaserFeatures(loaded_table, loaded);
  EXPECT_EQ(loaded_table.yaml(), table.yaml()) << "a value differs from its default";
}

TEST(ShippedConfig, PsmSlamParametersLoadAndTyposAreRejected) {
  const std::string dir = ::testing::TempDir();
  const std::string good = dir + "/psm_slam_good.yaml", bad = dir + "/psm_slam_bad.yaml";
  std::ofstream(good) << "reference_scans: {keyframe_distance: 0.8, keyframe_angle_deg: 30}\n"
                         "loop_closure: {loop_search_radius: 3.5}\npsm:\n  max_range: 12\n  covariance: heuristic\n"
                         "grid: {resolution: 0.1, scans: all}\n";
  std::ofstream(bad) << "reference_scans: {keyframe_distanse: 0.8}\n";
  const PsmSlamEstimatorConfig c = loadPsmSlamEstimatorConfig(good);
  EXPECT_DOUBLE_EQ(c.slam.keyframe_distance, 0.8);
  EXPECT_DOUBLE_EQ(c.slam.keyframe_angle, deg2rad(30.0));
  EXPECT_DOUBLE_EQ(c.slam.loop_search_radius, 3.5);
  EXPECT_DOUBLE_EQ(c.slam.psm.max_range, 12.0);
  EXPECT_EQ(c.slam.psm.covariance, CovarianceModel::Heuristic);
  EXPECT_DOUBLE_EQ(c.map.resolution, 0.1);
  EXPECT_TRUE(c.map.all_scans);
  try {
    loadPsmSlamEstimatorConfig(bad);
    FAIL() << "a misspelt key was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad + ":1:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loadPsmSlamEstimatorConfig(dir + "/does_not_exist.yaml"), std::runtime_error);
}

}  // namespace
}  // namespace polarslam
