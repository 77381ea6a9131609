// Occupancy from exact scans against the walls they were cast from; map files read back with
// OctoMap's own reader and parsed as map_server does.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "grid/grid_files.hpp"
#include "grid_fixtures.hpp"

namespace polarslam {
namespace {

using test::castScan;
using test::distanceToWalls;
using test::twoRoomGrid;
using test::twoRoomWorld;

std::string tempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("polarslam_grid_" + name + "_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                    "_" + std::to_string(reinterpret_cast<uintptr_t>(&name) & 0xffff));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

TEST(OccupancyGrid, OccupiedCellsLieOnTheWallsAndWallsAreCovered) {
  const World world = twoRoomWorld();
  const GridSlice slice = twoRoomGrid().slice();
  ASSERT_GT(slice.width, 100);
  int occupied = 0, near_wall = 0;
  for (int y = 0; y < slice.height; ++y)
    for (int x = 0; x < slice.width; ++x) {
      if (!slice.occupied(x, y)) continue;
      ++occupied;
      near_wall += distanceToWalls(world, slice.cellCenter(x, y)) <= slice.resolution;
    }
  EXPECT_GT(occupied, 300);
  EXPECT_EQ(near_wall, occupied);
  // Walk along every wall: the cell under it (or its neighbour across the wall) is occupied.
  int samples = 0, covered = 0;
  for (const WallSegment& s : world.segments())
    for (double t = 0.05; t < s.length() - 0.05; t += 0.05) {
      const Vec2 p = s.a + s.direction() * t;
      ++samples;
      bool hit = false;
      int cx, cy;
      slice.cellOf(p, cx, cy);
      for (int dy = -1; dy <= 1 && !hit; ++dy)
        for (int dx = -1; dx <= 1 && !hit; ++dx) hit = slice.inside(cx + dx, cy + dy) && slice.occupied(cx + dx, cy + dy);
      covered += hit;
    }
  EXPECT_GT(covered, 0.97 * samples);
}

TEST(OccupancyGrid, SpaceBetweenRobotAndWallsIsFree) {
  const GridSlice slice = twoRoomGrid().slice();
  for (const Vec2& p : {Vec2(1.0, 2.0), Vec2(3.0, 2.0), Vec2(4.5, 1.0), Vec2(5.5, 3.5)}) {
    int x, y;
    slice.cellOf(p, x, y);
    EXPECT_TRUE(slice.free(x, y)) << p.transpose();
  }
  // Outside the room nothing was observed.
  int x, y;
  slice.cellOf({2.0, 4.3}, x, y);
  EXPECT_TRUE(!slice.inside(x, y) || !slice.known(x, y));
}

TEST(OccupancyGrid, ScansBeyondMaxRangeOnlyClearSpace) {
  World corridor;
  corridor.addPolyline({{5.0, -1.0}, {5.0, 1.0}}, {Material::Wall}, false);
  GridOptions o;
  o.max_range = 3.0;
  OccupancyGrid grid(o);
  const LaserScan scan = castScan(corridor, Pose2(0, 0, 0), 181, std::numbers::pi / 4);
  for (int k = 0; k < 5; ++k) grid.insertScan(scan, Pose2(0, 0, 0));  // enough misses to call a cell free
  grid.finishUpdates();
  const GridSlice slice = grid.slice();
  for (int y = 0; y < slice.height; ++y)
    for (int x = 0; x < slice.width; ++x) EXPECT_FALSE(slice.occupied(x, y));
  int cx, cy;
  slice.cellOf({2.5, 0.0}, cx, cy);
  EXPECT_TRUE(slice.free(cx, cy));
  EXPECT_LT(slice.extentMax().x(), 3.5);
}

TEST(OccupancyGrid, BuildGridNeedsOnePosePerScan) {
  EXPECT_THROW(buildGrid(std::vector<LaserScan>(2), std::vector<Pose2>(1)), std::invalid_argument);
}

TEST(GridFiles, BinaryTreeReadsBackWithOctomapAndMatches) {
  const OccupancyGrid grid = twoRoomGrid();
  const std::string dir = tempDir("bt");
  const GridFiles files = writeGridFiles(dir, grid);
  octomap::OcTree bt(0.1);
  ASSERT_TRUE(bt.readBinary(files.bt));
  EXPECT_DOUBLE_EQ(bt.getResolution(), 0.05);
  const GridSlice original = grid.slice();
  const GridSlice read = sliceOf(bt, grid.layerZ());
  ASSERT_EQ(read.width, original.width);
  ASSERT_EQ(read.height, original.height);
  int disagreements = 0;
  for (int y = 0; y < read.height; ++y)
    for (int x = 0; x < read.width; ++x) {
      EXPECT_EQ(read.known(x, y), original.known(x, y));
      // .bt keeps occupied/free by the tree's 0.5 threshold.
      if (original.known(x, y)) disagreements += (read.at(x, y) > 0.5) != (original.at(x, y) > 0.5);
    }
  EXPECT_EQ(disagreements, 0);
  // The grid written from is untouched (writeBinary converts only its copy).
  EXPECT_EQ(grid.slice().probability.size(), original.probability.size());
  int changed = 0;
  const GridSlice after = grid.slice();
  for (size_t i = 0; i < after.probability.size(); ++i)
    changed += !(after.probability[i] == original.probability[i] ||
                 (std::isnan(after.probability[i]) && std::isnan(original.probability[i])));
  EXPECT_EQ(changed, 0);
  std::filesystem::remove_all(dir);
}

TEST(GridFiles, FullProbabilityTreeReadsBack) {
  const OccupancyGrid grid = twoRoomGrid();
  const std::string dir = tempDir("ot");
  const GridFiles files = writeGridFiles(dir, grid);
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(files.ot));
  ASSERT_TRUE(tree);
  auto* ot = dynamic_cast<octomap::OcTree*>(tree.get());
  ASSERT_NE(ot, nullptr);
  const GridSlice a = grid.slice(), b = sliceOf(*ot, grid.layerZ());
  ASSERT_EQ(a.probability.size(), b.probability.size());
  for (size_t i = 0; i < a.probability.size(); ++i)
    if (!std::isnan(a.probability[i])) {
      EXPECT_NEAR(a.probability[i], b.probability[i], 1e-6);
    }
  std::filesystem::remove_all(dir);
}

struct Pgm {
  int width = 0, height = 0, max_value = 0;
  std::vector<uint8_t> pixels;
};

/// Parses a binary PGM the way map_server's image loader sees it.
Pgm readPgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  Pgm pgm;
  in >> magic >> pgm.width >> pgm.height >> pgm.max_value;
  in.get();  // the single whitespace before the raster
  EXPECT_EQ(magic, "P5");
  pgm.pixels.resize(static_cast<size_t>(pgm.width) * pgm.height);
  in.read(reinterpret_cast<char*>(pgm.pixels.data()), static_cast<std::streamsize>(pgm.pixels.size()));
  EXPECT_EQ(in.gcount(), static_cast<std::streamsize>(pgm.pixels.size()));
  EXPECT_EQ(in.peek(), std::char_traits<char>::eof());
  return pgm;
}

TEST(GridFiles, PgmAndYamlFollowTheMapServerFormat) {
  const World world = twoRoomWorld();
  const OccupancyGrid grid = twoRoomGrid();
  const std::string dir = tempDir("pgm");
  const GridFiles files = writeGridFiles(dir, grid);
  const YAML::Node yaml = YAML::LoadFile(files.yaml);
  ASSERT_TRUE(yaml["image"] && yaml["resolution"] && yaml["origin"] && yaml["negate"] && yaml["occupied_thresh"] &&
              yaml["free_thresh"]);
  EXPECT_EQ(yaml["image"].as<std::string>(), "map.pgm");
  const double resolution = yaml["resolution"].as<double>();
  EXPECT_DOUBLE_EQ(resolution, 0.05);
  ASSERT_EQ(yaml["origin"].size(), 3u);
  const Vec2 origin(yaml["origin"][0].as<double>(), yaml["origin"][1].as<double>());
  EXPECT_EQ(yaml["negate"].as<int>(), 0);
  const double occupied_thresh = yaml["occupied_thresh"].as<double>(), free_thresh = yaml["free_thresh"].as<double>();
  EXPECT_GT(occupied_thresh, free_thresh);

  const Pgm pgm = readPgm((std::filesystem::path(dir) / yaml["image"].as<std::string>()).string());
  EXPECT_EQ(pgm.max_value, 255);
  // map_server: p = (255 − value) / 255 (negate 0); occupied if p > occupied_thresh, free if
  // p < free_thresh. Pixel (i, j) covers x = origin.x + i·res, y = origin.y + (height − 1 − j)·res.
  int occupied_on_wall = 0, occupied = 0, free_near_wall = 0;
  for (int j = 0; j < pgm.height; ++j)
    for (int i = 0; i < pgm.width; ++i) {
      const uint8_t v = pgm.pixels[static_cast<size_t>(j) * pgm.width + i];
      EXPECT_TRUE(v == 0 || v == 205 || v == 254) << int(v);
      const double p = (255.0 - v) / 255.0;
      const Vec2 center = origin + resolution * Vec2(i + 0.5, pgm.height - j - 0.5);
      const double d = distanceToWalls(world, center);
      if (p > occupied_thresh) {
        ++occupied;
        occupied_on_wall += d <= resolution;
      } else if (p < free_thresh) {
        free_near_wall += d < 0.25 * resolution;
      }
    }
  EXPECT_GT(occupied, 300);
  EXPECT_EQ(occupied_on_wall, occupied);
  EXPECT_EQ(free_near_wall, 0);
  // The room spans x ∈ [0, 6]: the image's extent must match it within a cell or two.
  EXPECT_NEAR(origin.x(), 0.0, 2 * resolution);
  EXPECT_NEAR(origin.x() + pgm.width * resolution, 6.0, 2 * resolution);
  EXPECT_NEAR(origin.y() + pgm.height * resolution, 4.0, 2 * resolution);
  EXPECT_TRUE(std::filesystem::file_size(files.png) > 1000);
  std::filesystem::remove_all(dir);
}

TEST(GridFiles, EmptyGridStillWritesValidFiles) {
  const std::string dir = tempDir("empty");
  const GridFiles files = writeGridFiles(dir, OccupancyGrid());
  const Pgm pgm = readPgm(files.pgm);
  EXPECT_EQ(pgm.width, 1);
  EXPECT_EQ(pgm.pixels.at(0), 205);
  octomap::OcTree bt(0.1);
  EXPECT_TRUE(bt.readBinary(files.bt));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace polarslam
