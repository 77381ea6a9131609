#include "map/map_store.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "grid/occupancy_grid.hpp"
#include "io/text_fields.hpp"

namespace polarslam {
namespace {
namespace fs = std::filesystem;

LaserScan testScan(int64_t utime, double phase) {
  LaserScan scan;
  scan.utime = utime;
  scan.seq = utime / 1000;
  scan.angle_min = -std::numbers::pi / 2;
  scan.angle_increment = std::numbers::pi / 180;
  scan.time_increment = 1.0 / 13300;
  scan.range_max = 8.1;
  scan.laser_pose = Pose2(0.1, 0.0, 0.0);
  for (int i = 0; i < 181; ++i) scan.ranges.push_back(static_cast<float>(2.0 + std::sin(0.1 * i + phase) / 3.0));
  scan.ranges[7] = std::numeric_limits<float>::infinity();  // no return: must survive the round trip
  return scan;
}

StoredMap testMap() {
  StoredMap map;
  map.laser = laserGeometryOf(testScan(0, 0));
  for (int64_t id = 0; id < 4; ++id)
    map.graph.addNode({id, 1000000 + id * 250000, Pose2(0.3 * id + 1.0 / 3, -0.1 * id, 0.2 * id - 0.7)});
  PoseGraphEdge edge;
  for (int64_t id = 1; id < 4; ++id) {
    edge.from = id - 1;
    edge.to = id;
    edge.measurement = Pose2(0.3, 0.1 / 7, 0.2);
    edge.covariance << 1e-4, 1e-6, 0, 1e-6, 2e-4, 0, 0, 0, 1e-5;
    edge.kind = id == 2 ? PoseGraphEdgeKind::Odometry : PoseGraphEdgeKind::Match;
    map.graph.addEdge(edge);
  }
  edge.from = 0;
  edge.to = 3;
  edge.kind = PoseGraphEdgeKind::Loop;
  map.graph.addEdge(edge);
  map.graph.edges().back().active = false;
  for (int64_t id = 0; id < 4; ++id) {
    MapReferenceScan reference{testScan(1000000 + id * 250000, 0.5 * id), {}};
    reference.anchor = {reference.scan.utime, id, Pose2(), true};
    map.scans.push_back(reference);
  }
  map.parameters_yaml = "psm_slam:\n  max_range: 8.0\n";
  return map;
}

class MapStore : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("polarslam-map-test-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
    dir_ = (root_ / "office").string();
  }
  void TearDown() override { fs::remove_all(root_); }

  /// Loads the map and returns the error message (empty if it loaded).
  std::string loadError(const std::optional<LaserGeometry>& laser = std::nullopt) const {
    try {
      loadMap(dir_, laser);
    } catch (const MapFormatError& e) {
      return e.what();
    }
    return {};
  }
  void rewrite(const std::string& name, const std::string& content) const {
    std::ofstream(dir_ + "/" + name, std::ios::binary | std::ios::trunc) << content;
  }
  /// Rewrites `name` and makes the manifest's size and CRC32 of it fit: the parsers see the content.
  void rewriteFitting(const std::string& name, const std::string& content, const std::string& manifest) const {
    rewrite(name, content);
    nlohmann::json fitted = nlohmann::json::parse(manifest);
    fitted["files"][name] = {{"bytes", content.size()}, {"crc32", mapCrc32(content)}};
    rewrite("manifest.json", fitted.dump(1));
  }

  fs::path root_;
  std::string dir_;
};

void expectSamePose(const Pose2& a, const Pose2& b) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.theta, b.theta);
}

TEST_F(MapStore, SaveThenLoadRoundTripsExactly) {
  const StoredMap saved = testMap();
  saveMap(dir_, saved);
  const StoredMap loaded = loadMap(dir_, saved.laser);

  ASSERT_EQ(loaded.graph.nodes().size(), saved.graph.nodes().size());
  for (size_t i = 0; i < saved.graph.nodes().size(); ++i) {
    EXPECT_EQ(loaded.graph.nodes()[i].id, saved.graph.nodes()[i].id);
    EXPECT_EQ(loaded.graph.nodes()[i].utime, saved.graph.nodes()[i].utime);
    expectSamePose(loaded.graph.nodes()[i].pose, saved.graph.nodes()[i].pose);
  }
  ASSERT_EQ(loaded.graph.edges().size(), saved.graph.edges().size());
  for (size_t i = 0; i < saved.graph.edges().size(); ++i) {
    const PoseGraphEdge &a = loaded.graph.edges()[i], &b = saved.graph.edges()[i];
    EXPECT_EQ(a.from, b.from);
    EXPECT_EQ(a.to, b.to);
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.active, b.active);
    expectSamePose(a.measurement, b.measurement);
    EXPECT_EQ(a.covariance, b.covariance);
  }
  ASSERT_EQ(loaded.scans.size(), saved.scans.size());
  for (size_t i = 0; i < saved.scans.size(); ++i) {
    const LaserScan &a = loaded.scans[i].scan, &b = saved.scans[i].scan;
    EXPECT_EQ(a.utime, b.utime);
    EXPECT_EQ(a.seq, b.seq);
    EXPECT_EQ(a.angle_min, b.angle_min);
    EXPECT_EQ(a.angle_increment, b.angle_increment);
    EXPECT_EQ(a.time_increment, b.time_increment);
    EXPECT_EQ(a.range_max, b.range_max);
    expectSamePose(a.laser_pose, b.laser_pose);
    EXPECT_EQ(a.ranges, b.ranges);
    EXPECT_EQ(loaded.scans[i].anchor.node, saved.scans[i].anchor.node);
    EXPECT_EQ(loaded.scans[i].anchor.new_node, saved.scans[i].anchor.new_node);
    expectSamePose(loaded.scans[i].anchor.relative, saved.scans[i].anchor.relative);
  }
  EXPECT_EQ(loaded.parameters_yaml, saved.parameters_yaml);
  EXPECT_EQ(laserGeometryMismatch(loaded.laser, saved.laser), "");
}

TEST_F(MapStore, SavingTwiceGivesIdenticalFiles) {
  saveMap(dir_, testMap());
  const std::string first = readTextFile(dir_ + "/scans.txt") + readTextFile(dir_ + "/graph.txt");
  saveMap(dir_, loadMap(dir_));
  EXPECT_EQ(readTextFile(dir_ + "/scans.txt") + readTextFile(dir_ + "/graph.txt"), first);
}

TEST_F(MapStore, ReplacesAnOldMapAndLeavesNoTemporaryFolder) {
  saveMap(dir_, testMap());
  StoredMap smaller = testMap();
  smaller.scans.resize(1);
  saveMap(dir_, smaller);
  EXPECT_EQ(loadMap(dir_).scans.size(), 1u);
  size_t entries = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(root_)) ++entries;
  EXPECT_EQ(entries, 1u);
}

TEST_F(MapStore, AFailedSaveLeavesTheOldMapIntact) {
  saveMap(dir_, testMap());
  StoredMap bad = testMap();
  bad.scans[2].anchor.node = 99;  // a node the graph lacks
  EXPECT_THROW(saveMap(dir_, bad), MapFormatError);
  EXPECT_EQ(loadMap(dir_).scans.size(), 4u);
  EXPECT_FALSE(fs::exists(dir_ + ".saving-" + std::to_string(::getpid())));
}

TEST_F(MapStore, RefusesToReplaceAFolderThatIsNotAMap) {
  fs::create_directories(dir_);
  std::ofstream(dir_ + "/thesis.tex") << "precious";
  EXPECT_THROW(saveMap(dir_, testMap()), MapFormatError);
  EXPECT_TRUE(fs::exists(dir_ + "/thesis.tex"));
}

TEST_F(MapStore, RefusesAScanThatDoesNotMatchTheMapsLaser) {
  StoredMap map = testMap();
  map.scans[1].scan.ranges.pop_back();
  EXPECT_THROW(saveMap(dir_, map), MapFormatError);
}

TEST_F(MapStore, SavesAndChecksTheGridFiles) {
  OccupancyGrid grid;
  const StoredMap map = testMap();
  for (const MapReferenceScan& reference : map.scans) grid.insertScan(reference.scan, map.graph.node(reference.anchor.node).pose);
  saveMap(dir_, map, &grid);
  for (const char* name : {"map.ot", "map.bt", "map.pgm", "map.yaml", "map.png"}) EXPECT_TRUE(fs::exists(dir_ + "/" + name)) << name;
  EXPECT_EQ(loadError(), "");
  std::string png = readTextFile(dir_ + "/map.png");
  png[png.size() / 2] = static_cast<char>(png[png.size() / 2] ^ 0x01);
  rewrite("map.png", png);
  const std::string error = loadError();
  EXPECT_NE(error.find("map.png"), std::string::npos) << error;
  EXPECT_NE(error.find("CRC32"), std::string::npos) << error;
}

TEST_F(MapStore, RefusesAMissingFolder) {
  const std::string error = loadError();
  EXPECT_NE(error.find("office"), std::string::npos) << error;
}

TEST_F(MapStore, RefusesATruncatedFileNamingIt) {
  saveMap(dir_, testMap());
  const std::string scans = readTextFile(dir_ + "/scans.txt");
  rewrite("scans.txt", scans.substr(0, scans.size() / 2));
  const std::string error = loadError();
  EXPECT_NE(error.find("scans.txt"), std::string::npos) << error;
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
}

TEST_F(MapStore, RefusesATruncatedManifest) {
  saveMap(dir_, testMap());
  const std::string manifest = readTextFile(dir_ + "/manifest.json");
  rewrite("manifest.json", manifest.substr(0, manifest.size() - 20));
  const std::string error = loadError();
  EXPECT_NE(error.find("manifest.json"), std::string::npos) << error;
}

TEST_F(MapStore, RefusesAnotherFormatVersion) {
  saveMap(dir_, testMap());
  std::string manifest = readTextFile(dir_ + "/manifest.json");
  const size_t at = manifest.find("\"version\": 1");
  ASSERT_NE(at, std::string::npos);
  manifest.replace(at, 12, "\"version\": 2");
  rewrite("manifest.json", manifest);
  const std::string error = loadError();
  EXPECT_NE(error.find("manifest.json"), std::string::npos) << error;
  EXPECT_NE(error.find("version 2"), std::string::npos) << error;
}

TEST_F(MapStore, RefusesAChecksumMismatchNamingTheFile) {
  saveMap(dir_, testMap());
  std::string graph = readTextFile(dir_ + "/graph.txt");
  const size_t at = graph.find("node 1 ");
  ASSERT_NE(at, std::string::npos);
  graph[at + 5] = '2';  // same size, different content
  rewrite("graph.txt", graph);
  const std::string error = loadError();
  EXPECT_NE(error.find("graph.txt"), std::string::npos) << error;
  EXPECT_NE(error.find("CRC32"), std::string::npos) << error;
}

TEST_F(MapStore, RefusesAMapMadeWithAnotherLaser) {
  saveMap(dir_, testMap());
  LaserGeometry other = testMap().laser;
  other.beams = 361;
  std::string error = loadError(other);
  EXPECT_NE(error.find("manifest.json"), std::string::npos) << error;
  EXPECT_NE(error.find("another laser"), std::string::npos) << error;
  other = testMap().laser;
  other.mount.x += 0.05;
  error = loadError(other);
  EXPECT_NE(error.find("mount"), std::string::npos) << error;
  EXPECT_EQ(loadError(testMap().laser), "");
}

TEST_F(MapStore, RefusesAMissingListedFile) {
  saveMap(dir_, testMap());
  fs::remove(dir_ + "/parameters.yaml");
  const std::string error = loadError();
  EXPECT_NE(error.find("parameters.yaml"), std::string::npos) << error;
}

TEST_F(MapStore, RefusesAWellChecksummedButMalformedRecordNamingTheLine) {
  // A writer bug, not disk damage: the checksum fits, the content does not.
  StoredMap map = testMap();
  saveMap(dir_, map);
  const std::string original = readTextFile(dir_ + "/graph.txt");
  const std::string graph = original + "edge 0 7 1 1 0 0 0 1 0 0 0 1 0 0 0 1\n";  // node 7 does not exist
  rewriteFitting("graph.txt", graph, readTextFile(dir_ + "/manifest.json"));
  const std::string error = loadError();
  EXPECT_NE(error.find("graph.txt:"), std::string::npos) << error;
}

// Found by fuzzing (tests/fuzz/map.cpp): node ids out of order threw the pose graph's
// std::invalid_argument, which named no file.
TEST_F(MapStore, NodeIdsOutOfOrderAreRefusedNamingTheLine) {
  StoredMap map = testMap();
  saveMap(dir_, map);
  const std::string graph = readTextFile(dir_ + "/graph.txt") + "node -5 0 1 2 0.5\n";
  rewriteFitting("graph.txt", graph, readTextFile(dir_ + "/manifest.json"));
  const std::string error = loadError();
  EXPECT_NE(error.find("graph.txt:"), std::string::npos) << error;
  EXPECT_NE(error.find("must increase"), std::string::npos) << error;
}

// The manifest names files of the map folder only: loading never reads outside it.
TEST_F(MapStore, AManifestListingAFileOutsideTheFolderIsRefused) {
  StoredMap map = testMap();
  saveMap(dir_, map);
  const std::string outside = (root_ / "outside.txt").string();
  std::ofstream(outside) << "not the map's\n";
  rewriteFitting("../outside.txt", "not the map's\n", readTextFile(dir_ + "/manifest.json"));
  const std::string error = loadError();
  EXPECT_NE(error.find("manifest.json"), std::string::npos) << error;
  EXPECT_NE(error.find("not a file of the map folder"), std::string::npos) << error;
}

TEST_F(MapStore, TheNodesUncertaintyAndASnapshotsStateRoundTripAndABadCovarianceIsRefused) {
  StoredMap map = testMap();
  map.node_covariances = {{map.graph.nodes().front().id, Vec3(1e-4, 2e-4, 1e-5).asDiagonal()},
                          {map.graph.nodes().back().id, Vec3(0.25, 0.09, 1e-3).asDiagonal()}};
  map.resume_json = "{\"mode\": \"continue\"}\n";
  map.resume_filter = std::string("\0\x01\xff binary\n", 11);
  saveMap(dir_, map);
  const StoredMap loaded = loadMap(dir_);
  ASSERT_EQ(loaded.node_covariances.size(), 2u);
  EXPECT_EQ(loaded.node_covariances[1].first, map.graph.nodes().back().id);
  EXPECT_EQ(loaded.node_covariances[1].second, map.node_covariances[1].second);
  EXPECT_EQ(loaded.resume_json, map.resume_json);
  EXPECT_EQ(loaded.resume_filter, map.resume_filter);

  map.node_covariances[1].second(0, 0) = -1.0;
  saveMap(dir_, map);
  const std::string error = loadError();
  EXPECT_NE(error.find("uncertainty.json"), std::string::npos) << error;
  EXPECT_NE(error.find("positive definite"), std::string::npos) << error;
}

// What a crash or a bad disk leaves: every file of a snapshot-like map cut short, overwritten in
// places or padded with garbage, with the manifest's size and checksum made to fit so that the
// parsers themselves see it (the checksum would refuse most of it first). Loading gives the map
// or a MapFormatError, never another exception or a crash (CI runs this under ASan + UBSan).
TEST_F(MapStore, DamagedFilesThatPassTheChecksumAreRefusedWithAMapFormatError) {
  StoredMap map = testMap();
  map.node_covariances = {{0, Vec3(1e-4, 2e-4, 1e-5).asDiagonal()}, {3, Vec3(0.25, 0.09, 1e-3).asDiagonal()}};
  map.resume_json = "{\"mode\": \"continue\"}\n";
  map.resume_filter = std::string(64, '\x3f');
  saveMap(dir_, map);
  const std::string manifest = readTextFile(dir_ + "/manifest.json");
  const std::vector<std::string> names = {"manifest.json", "graph.txt", "scans.txt", "parameters.yaml",
                                          "uncertainty.json", "resume.json", "resume-filter.bin"};
  std::map<std::string, std::string> originals;
  for (const std::string& name : names) originals[name] = readTextFile(dir_ + "/" + name);
  std::mt19937 rng(20261207);
  size_t refused = 0, loaded = 0;
  for (int trial = 0; trial < 1400; ++trial) {
    const std::string& name = names[static_cast<size_t>(trial) % names.size()];
    std::string content = originals[name];
    const auto position = [&] { return content.empty() ? size_t{0} : rng() % content.size(); };
    switch (rng() % 4) {
      case 0: content.resize(position()); break;  // cut short
      case 1:
        for (int k = 0; k < 1 + static_cast<int>(rng() % 4) && !content.empty(); ++k)
          content[position()] = "0123456789-.e \n{}[]\",:naif\x80"[rng() % 26];
        break;
      case 2: content.insert(position(), std::string(1 + rng() % 40, static_cast<char>(rng()))); break;
      default: content = content.substr(position()) + content.substr(0, position());  // lines out of place
    }
    for (const std::string& other : names) rewrite(other, other == name ? content : originals[other]);
    if (name != "manifest.json") rewriteFitting(name, content, manifest);
    try {
      loadMap(dir_);
      ++loaded;
    } catch (const MapFormatError& e) {
      ++refused;
      EXPECT_FALSE(e.file().empty()) << e.what();
    }
  }
  std::printf("%zu damaged maps refused, %zu loaded (damage a parser cannot tell from data)\n", refused, loaded);
  EXPECT_GT(refused, 700u);
}

}  // namespace
}  // namespace polarslam
