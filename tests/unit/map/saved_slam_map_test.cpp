// The map of a PSM SLAM run, saved by the estimator (`polarslam run --pipeline psm-slam
// --save-map M`) and loaded back: the same graph, the run's reference scans, its parameters.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "io/text_fields.hpp"
#include "map/map_store.hpp"
#include "pipeline/pipelines.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "unit/slam/synthetic_run.hpp"

namespace polarslam {
namespace {
namespace fs = std::filesystem;

class SavedSlamMap : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("polarslam-saved-map-test-" + std::to_string(::getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

TEST_F(SavedSlamMap, TheEstimatorSavesItsFinalGraphAndReferenceScans) {
  const testing::SyntheticRun run = testing::simulateLoopRun(testing::makeLoopWorld(), {});
  PsmSlamEstimator estimator;
  const std::string map_dir = (root_ / "map").string();
  estimator.saveMapTo(map_dir);
  for (size_t k = 0; k < run.scans.size(); ++k) {
    estimator.onOdometry(run.odometry[k]);
    estimator.onLaser(run.scans[k]);
  }
  nlohmann::json report;
  estimator.finish((root_ / "out").string(), report);
  ASSERT_TRUE(report.contains("saved_map")) << report.dump(2);

  const StoredMap map = loadMap(map_dir, laserGeometryOf(run.scans.front()));
  const PoseGraph& graph = estimator.slam().graph();
  ASSERT_GT(graph.nodes().size(), 2u);
  ASSERT_EQ(map.graph.nodes().size(), graph.nodes().size());
  for (size_t i = 0; i < graph.nodes().size(); ++i) {
    EXPECT_EQ(map.graph.nodes()[i].pose.x, graph.nodes()[i].pose.x);
    EXPECT_EQ(map.graph.nodes()[i].pose.theta, graph.nodes()[i].pose.theta);
  }
  EXPECT_EQ(map.graph.edges().size(), graph.edges().size());
  EXPECT_EQ(map.scans.size(), graph.nodes().size()) << "one reference scan per graph node";
  for (const MapReferenceScan& reference : map.scans) {
    EXPECT_TRUE(reference.anchor.new_node);
    EXPECT_GE(map.graph.indexOf(reference.anchor.node), 0);
  }
  EXPECT_EQ(map.parameters_yaml, effectiveConfigYaml("psm-slam", {}));
  EXPECT_TRUE(fs::exists(map_dir + "/map.pgm"));
}

TEST_F(SavedSlamMap, NothingToSaveIsAClearError) {
  PsmSlamEstimator estimator;
  estimator.saveMapTo((root_ / "map").string());
  nlohmann::json report;
  try {
    estimator.finish((root_ / "out").string(), report);
    FAIL() << "an empty run saved a map";
  } catch (const MapFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("no reference scans"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(root_ / "map"));
}

}  // namespace
}  // namespace polarslam
