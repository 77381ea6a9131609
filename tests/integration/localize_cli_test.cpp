// polarslam run --load-map M --mode localize|continue (issue 15, item 2) end to end: the default
// log's map saved by one run, the same log localised in it from a known start by another and
// mapped on from it by a third, and the option mistakes a user can make refused with a message.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "child_process.hpp"
#include "map/map_store.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::freshDir;
using polarslam::testing::readFile;
using polarslam::testing::readJson;
using polarslam::testing::runToEnd;
using polarslam::testing::sourcePath;

namespace {
namespace fs = std::filesystem;

TEST(LocalizeCli, TheDefaultLogLocalisesInAndContinuesItsOwnSavedMapAndBadOptionsAreRefused) {
  const fs::path dir = freshDir("localize-it");
  const std::string log = sourcePath("logs/office.lcmlog"), config = sourcePath("config/psm-slam.yaml");
  const std::string map = (dir / "map").string();
  ASSERT_EQ(runToEnd({binPath("polarslam"), "run", "--log", log, "--pipeline", "psm-slam", "--config", config,
                      "--save-map", map, "--out", (dir / "mapping").string()},
                     dir / "mapping.out", 300s),
            0)
      << readFile(dir / "mapping.out");

  ASSERT_EQ(runToEnd({binPath("polarslam"), "run", "--log", log, "--pipeline", "psm-slam", "--config", config,
                      "--load-map", map, "--initial-pose", "0,0,0", "--out", (dir / "localize").string()},
                     dir / "localize.out", 300s),
            0)
      << readFile(dir / "localize.out");
  const nlohmann::json report = readJson(dir / "localize" / "report.json");
  ASSERT_TRUE(report.contains("localization")) << report.dump(2);
  const auto& loc = report["localization"];
  EXPECT_EQ(loc["global_searches"], 0) << "a known start needs no search";
  EXPECT_EQ(loc["losses"], 0);
  // Temporary mapping (the default): between the map's reference scans, taken up again only near
  // its skeleton, the robot tracks temporary ones of its own (measured: 563 of 1537 scans matched
  // with the map; MapLocalizer alone, which has nothing else, over 90 %).
  EXPECT_GT(loc["matched_scans"].get<int>(), 0.3 * loc["scans"].get<int>()) << loc.dump(2);
  EXPECT_GT(report["psm_slam"]["map_loop_closures"].get<int>(), 10) << report["psm_slam"].dump(2);
  EXPECT_LT(report["ate_rmse_m"].get<double>(), 0.10) << "the map's frame is the mapping run's start frame";
  EXPECT_TRUE(fs::exists(dir / "localize" / "map.png"));
  EXPECT_TRUE(fs::exists(dir / "localize" / "trajectory.tum"));

  // --mode continue maps on from the saved map and saves the whole, old and new parts.
  const std::string extended = (dir / "extended").string();
  ASSERT_EQ(runToEnd({binPath("polarslam"), "run", "--log", log, "--pipeline", "psm-slam", "--config", config,
                      "--load-map", map, "--mode", "continue", "--initial-pose", "0,0,0", "--save-map", extended,
                      "--out", (dir / "continue").string()},
                     dir / "continue.out", 300s),
            0)
      << readFile(dir / "continue.out");
  const nlohmann::json continued = readJson(dir / "continue" / "report.json");
  EXPECT_LT(continued["ate_rmse_m"].get<double>(), 0.10) << continued.dump(2);
  EXPECT_GT(continued["psm_slam"]["map_loop_closures"].get<int>(), 0) << continued["psm_slam"].dump(2);
  const int map_nodes = continued["localization"]["map_reference_scans"].get<int>();
  EXPECT_GT(continued["saved_map"]["nodes"].get<int>(), map_nodes);
  EXPECT_EQ(continued["saved_map"]["reference_scans"], continued["saved_map"]["nodes"]);
  ASSERT_EQ(runToEnd({binPath("polarslam"), "map-check", extended}, dir / "check.out", 60s), 0) << readFile(dir / "check.out");
  EXPECT_NE(readFile(dir / "check.out").find("localisable"), std::string::npos) << readFile(dir / "check.out");

  // A map one of whose nodes lies 100 km away (intact files, fresh checksums) would need search
  // grids of 10^9 cells: map-check refuses it as run --load-map does, naming the map.
  polarslam::StoredMap wide = polarslam::loadMap(map);
  const polarslam::PoseGraphNode far = wide.graph.nodes().at(3);
  wide.graph.setPose(far.id, polarslam::Pose2(1e5, far.pose.y, far.pose.theta));
  const std::string wide_map = (dir / "wide").string();
  polarslam::saveMap(wide_map, wide);
  EXPECT_NE(runToEnd({binPath("polarslam"), "map-check", wide_map}, dir / "wide.out", 60s), 0) << readFile(dir / "wide.out");
  EXPECT_NE(readFile(dir / "wide.out").find("the map spans"), std::string::npos) << readFile(dir / "wide.out");
  EXPECT_NE(readFile(dir / "wide.out").find(wide_map), std::string::npos) << readFile(dir / "wide.out");

  const std::vector<std::pair<std::vector<std::string>, std::string>> mistakes{
      {{"--pipeline", "psm-slam", "--load-map", map, "--initial-pose", "1,2"}, "expected x,y,theta"},
      {{"--pipeline", "ekf", "--load-map", map}, "--load-map goes with --pipeline psm-slam"},
      {{"--pipeline", "psm-slam", "--initial-pose", "0,0,0"}, "--initial-pose goes with --load-map"},
      {{"--pipeline", "psm-slam", "--load-map", map, "--save-map", (dir / "other").string()}, "no --save-map"},
      {{"--pipeline", "psm-slam", "--load-map", (dir / "mapping").string()}, "manifest.json"},
  };
  for (const auto& [options, message] : mistakes) {
    std::vector<std::string> argv{binPath("polarslam"), "run", "--log", log, "--out", (dir / "refused").string()};
    argv.insert(argv.end(), options.begin(), options.end());
    EXPECT_NE(runToEnd(argv, dir / "refused.out", 60s), 0) << message;
    EXPECT_NE(readFile(dir / "refused.out").find(message), std::string::npos) << readFile(dir / "refused.out");
    EXPECT_FALSE(fs::exists(dir / "refused")) << message;
  }
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
