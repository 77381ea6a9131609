// The raster of OccupancyGrid against an independent truth: OctoMap's own
// OcTree::insertPointCloud, run here on the same scans, with the sensor model and ray rules the
// raster copies. Plus the per-scan rules on hand-made scans, raster growth and its limits.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <tuple>

#include "grid_fixtures.hpp"

namespace polarslam {
namespace {

using test::castScan;
using test::twoRoomWorld;

/// What the reference does with a scan: the end points (as floats, OctoMap's point type) and the
/// sensor position, inserted with insertPointCloud and the grid's max range.
void insertIntoOctree(octomap::OcTree& tree, const LaserScan& scan, const Pose2& robot, const GridOptions& o,
                      double z) {
  const Pose2 sensor = robot * scan.laser_pose;
  octomap::Pointcloud cloud;
  for (size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const Vec2 p = sensor.transform(scan.point(i));
    cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(z));
  }
  const double max_range = o.max_range > 0.0 ? o.max_range : scan.range_max;
  tree.insertPointCloud(cloud, octomap::point3d(static_cast<float>(sensor.x), static_cast<float>(sensor.y),
                                                static_cast<float>(z)),
                        max_range);
}

octomap::OcTree referenceTree(const std::vector<LaserScan>& scans, const std::vector<Pose2>& poses,
                              const GridOptions& o) {
  octomap::OcTree tree(o.resolution);
  tree.setProbHit(o.prob_hit);
  tree.setProbMiss(o.prob_miss);
  tree.setClampingThresMin(o.clamp_min);
  tree.setClampingThresMax(o.clamp_max);
  const double z = 0.5 * o.resolution;
  for (size_t k = 0; k < scans.size(); ++k) insertIntoOctree(tree, scans[k], poses[k], o, z);
  return tree;
}

enum class CellClass { Unknown, Free, Uncertain, Occupied };

CellClass classOf(const GridSlice& s, int ix, int iy) {
  if (!s.inside(ix, iy) || !s.known(ix, iy)) return CellClass::Unknown;
  if (s.occupied(ix, iy)) return CellClass::Occupied;
  return s.free(ix, iy) ? CellClass::Free : CellClass::Uncertain;
}

struct Agreement {
  int known_in_either = 0, same_class = 0;
  int occupied_in_either = 0, occupied_in_both = 0;
  int same_probability = 0;  ///< known in both with equal probability (to float rounding)
};

/// Compares two slices cell by cell in map-frame cell indices (their origins may differ).
Agreement compare(const GridSlice& a, const GridSlice& b) {
  const double res = a.resolution;
  auto firstCell = [res](const GridSlice& s) {
    return std::pair{static_cast<int>(std::lround(s.origin.x() / res)), static_cast<int>(std::lround(s.origin.y() / res))};
  };
  const auto [ax, ay] = firstCell(a);
  const auto [bx, by] = firstCell(b);
  const int x0 = std::min(ax, bx), y0 = std::min(ay, by);
  const int x1 = std::max(ax + a.width, bx + b.width), y1 = std::max(ay + a.height, by + b.height);
  Agreement r;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const CellClass ca = classOf(a, x - ax, y - ay), cb = classOf(b, x - bx, y - by);
      if (ca == CellClass::Unknown && cb == CellClass::Unknown) continue;
      ++r.known_in_either;
      r.same_class += ca == cb;
      if (ca == CellClass::Occupied || cb == CellClass::Occupied) {
        ++r.occupied_in_either;
        r.occupied_in_both += ca == cb;
      }
      if (ca != CellClass::Unknown && cb != CellClass::Unknown)
        r.same_probability += std::abs(a.at(x - ax, y - ay) - b.at(x - bx, y - by)) < 1e-6f;
    }
  return r;
}

/// Scans in the two-room world from many poses, with a 3 m max range (longer beams only clear
/// space) and some beams without return (NaN, 0, +inf: glass, black surfaces).
struct SimulatedRun {
  std::vector<LaserScan> scans;
  std::vector<Pose2> poses;
};

SimulatedRun simulatedRun() {
  const World world = twoRoomWorld();
  SimulatedRun run;
  for (const Pose2& p : test::twoRoomPoses()) run.poses.push_back(p);
  for (int k = 0; k < 24; ++k) {  // a loop through both rooms and the doorway, turning as it goes
    const double t = 2.0 * std::numbers::pi * k / 24.0;
    run.poses.emplace_back(3.0 + 2.0 * std::cos(t), 2.0 + 1.2 * std::sin(t), 0.7 * t);
  }
  for (size_t k = 0; k < run.poses.size(); ++k) {
    LaserScan scan = castScan(world, run.poses[k], 361, 1.5 * std::numbers::pi);
    for (size_t i = k % 7; i < scan.size(); i += 7) scan.ranges[i] = std::numeric_limits<float>::quiet_NaN();
    for (size_t i = k % 11; i < scan.size(); i += 23) scan.ranges[i] = 0.0f;
    for (size_t i = k % 5; i < scan.size(); i += 31) scan.ranges[i] = std::numeric_limits<float>::infinity();
    run.scans.push_back(std::move(scan));
  }
  return run;
}

TEST(OctomapReference, RasterAgreesWithInsertPointCloud) {
  const SimulatedRun run = simulatedRun();
  int beyond_max_range = 0, without_return = 0;
  for (const LaserScan& s : run.scans)
    for (size_t i = 0; i < s.size(); ++i) {
      beyond_max_range += s.valid(i) && s.ranges[i] > 3.0f;
      without_return += !s.valid(i);
    }
  ASSERT_GT(beyond_max_range, 1000);
  ASSERT_GT(without_return, 1000);

  for (const double resolution : {0.05, 0.1}) {
    GridOptions o;
    o.resolution = resolution;
    o.max_range = 3.0;
    const GridSlice raster = buildGrid(run.scans, run.poses, o).slice();
    const GridSlice reference = sliceOf(referenceTree(run.scans, run.poses, o), 0.5 * resolution);
    const Agreement r = compare(raster, reference);
    SCOPED_TRACE("resolution " + std::to_string(resolution));
    ASSERT_GT(r.known_in_either, 1000);
    ASSERT_GT(r.occupied_in_either, 100);
    EXPECT_GE(r.same_class, 0.99 * r.known_in_either) << r.same_class << " of " << r.known_in_either;
    EXPECT_GE(r.occupied_in_both, 0.99 * r.occupied_in_either)
        << r.occupied_in_both << " of " << r.occupied_in_either;
    // Same update arithmetic: where both saw a cell, nearly always the very same probability.
    EXPECT_GE(r.same_probability, 0.98 * r.known_in_either) << r.same_probability << " of " << r.known_in_either;
  }
}

TEST(OctomapReference, ExportedTreeHoldsTheRasterExactly) {
  const SimulatedRun run = simulatedRun();
  GridOptions o;
  o.max_range = 3.0;
  const OccupancyGrid grid = buildGrid(run.scans, run.poses, o);
  const GridSlice raster = grid.slice();
  const GridSlice exported = sliceOf(*grid.toOcTree(), grid.layerZ());
  ASSERT_EQ(exported.width, raster.width);
  ASSERT_EQ(exported.height, raster.height);
  EXPECT_NEAR(exported.origin.x(), raster.origin.x(), 1e-9);
  EXPECT_NEAR(exported.origin.y(), raster.origin.y(), 1e-9);
  for (size_t i = 0; i < raster.probability.size(); ++i) {
    ASSERT_EQ(std::isnan(raster.probability[i]), std::isnan(exported.probability[i])) << i;
    if (!std::isnan(raster.probability[i])) {
      ASSERT_FLOAT_EQ(raster.probability[i], exported.probability[i]) << i;
    }
  }
}

/// A scan of `ranges` along the given bearings from a sensor at the origin looking along x.
LaserScan handMadeScan(const std::vector<float>& ranges, double angle_min, double increment) {
  LaserScan scan;
  scan.range_max = 20.0;
  scan.angle_min = angle_min;
  scan.angle_increment = increment;
  scan.ranges = ranges;
  return scan;
}

float probabilityOf(double log_odds) { return static_cast<float>(1.0 - 1.0 / (1.0 + std::exp(log_odds))); }
float logOdds(double p) { return static_cast<float>(std::log(p / (1.0 - p))); }

float probabilityAt(const GridSlice& s, const Vec2& p) {
  int x, y;
  s.cellOf(p, x, y);
  return s.inside(x, y) ? s.at(x, y) : std::numeric_limits<float>::quiet_NaN();
}

TEST(OccupancyGridRules, EndPointCrossedByAnotherBeamCountsOccupiedOnly) {
  // Two beams along the same bearing: the short one ends in a cell the long one crosses.
  OccupancyGrid grid;
  grid.insertScan(handMadeScan({1.02f, 2.02f}, 0.0, 1e-9), Pose2(0.01, 0.01, 0.0));
  const GridSlice s = grid.slice();
  EXPECT_FLOAT_EQ(probabilityAt(s, {1.03, 0.01}), probabilityOf(logOdds(0.7)));
  EXPECT_FLOAT_EQ(probabilityAt(s, {2.03, 0.01}), probabilityOf(logOdds(0.7)));
  // Cells both beams cross, the sensor's own among them, get one miss, not two.
  EXPECT_FLOAT_EQ(probabilityAt(s, {0.5, 0.01}), probabilityOf(logOdds(0.4)));
  EXPECT_FLOAT_EQ(probabilityAt(s, {0.01, 0.01}), probabilityOf(logOdds(0.4)));
  EXPECT_FLOAT_EQ(probabilityAt(s, {1.5, 0.01}), probabilityOf(logOdds(0.4)));
}

TEST(OccupancyGridRules, OneUpdatePerScanAndClamping) {
  OccupancyGrid grid;
  const LaserScan scan = handMadeScan(std::vector<float>(90, 2.0f), -0.3, 0.6 / 90);
  grid.insertScan(scan, Pose2(0.01, 0.01, 0.0));
  EXPECT_FLOAT_EQ(probabilityAt(grid.slice(), {0.01, 0.01}), probabilityOf(logOdds(0.4)));
  for (int k = 0; k < 20; ++k) grid.insertScan(scan, Pose2(0.01, 0.01, 0.0));
  const GridSlice s = grid.slice();
  EXPECT_FLOAT_EQ(probabilityAt(s, {0.01, 0.01}), probabilityOf(logOdds(0.12)));  // clamped at clamp_min
  EXPECT_FLOAT_EQ(probabilityAt(s, {2.02, 0.01}), probabilityOf(logOdds(0.97)));  // clamped at clamp_max
  EXPECT_EQ(grid.scansInserted(), 21u);
}

TEST(OccupancyGridRules, EveryRayIsAStaircaseFromTheSensorCellToTheEndCell) {
  // Sensors on cell corners and borders, beams along the axes and diagonals ending on borders:
  // where rounding could walk a ray one cell too far (buildGrid leaves no margin around the
  // cells the scans reach). One beam per grid: its cells must be exactly the 4-connected
  // staircase from the sensor's cell to the end cell, the end occupied, nothing outside.
  GridOptions o;
  o.resolution = 0.25;
  int rays = 0;
  for (const Vec2& sensor : {Vec2(0.0, 0.0), Vec2(0.125, 0.0), Vec2(0.0, -0.25), Vec2(-0.5, 0.3), Vec2(0.1, 0.2)})
    for (int k = 0; k < 32; ++k)
      for (const double range : {0.25, 0.5, 1.0, 0.75 * std::numbers::sqrt2, 1.3}) {
        const double bearing = k * std::numbers::pi / 16 + (k % 3 == 2 ? 0.01 : 0.0);
        const GridSlice s = buildGrid({handMadeScan({static_cast<float>(range)}, bearing, 0.0)},
                                      {Pose2(sensor.x(), sensor.y(), 0.0)}, o).slice();
        int sx, sy, ex = 0, ey = 0, occupied = 0;
        s.cellOf(sensor, sx, sy);
        for (int y = 0; y < s.height; ++y)
          for (int x = 0; x < s.width; ++x)
            if (s.occupied(x, y)) std::tie(ex, ey, occupied) = std::tuple(x, y, occupied + 1);
        SCOPED_TRACE(testing::Message() << "sensor " << sensor.transpose() << " bearing " << bearing << " range " << range);
        ASSERT_EQ(occupied, 1);
        int tx, ty;  // the end cell by this test's own rounding: the same, or next to it on a border
        s.cellOf(sensor + range * Vec2(std::cos(bearing), std::sin(bearing)), tx, ty);
        EXPECT_LE(std::abs(tx - ex), 1);
        EXPECT_LE(std::abs(ty - ey), 1);
        int known = 0;
        for (int y = 0; y < s.height; ++y)
          for (int x = 0; x < s.width; ++x) {
            if (!s.known(x, y)) continue;
            ++known;
            EXPECT_TRUE(x >= std::min(sx, ex) && x <= std::max(sx, ex) && y >= std::min(sy, ey) && y <= std::max(sy, ey));
            EXPECT_EQ(s.occupied(x, y), x == ex && y == ey);
            // A staircase: every cell but the sensor's has a known neighbour one step nearer to it.
            const bool has_previous = (x != sx && s.inside(x - (ex > sx ? 1 : -1), y) && s.known(x - (ex > sx ? 1 : -1), y)) ||
                                      (y != sy && s.inside(x, y - (ey > sy ? 1 : -1)) && s.known(x, y - (ey > sy ? 1 : -1)));
            EXPECT_TRUE((x == sx && y == sy) || has_previous) << x << " " << y;
          }
        EXPECT_EQ(known, (sx == ex && sy == ey) ? 1 : std::abs(ex - sx) + std::abs(ey - sy) + 1);
        ++rays;
      }
  EXPECT_EQ(rays, 5 * 32 * 5);
}

TEST(OccupancyGridRules, GrowingTheRasterKeepsEarlierCells) {
  const World world = twoRoomWorld();
  const LaserScan scan = castScan(world, Pose2(1.0, 1.0, 0.0));
  GridOptions o;
  o.max_range = 3.0;
  OccupancyGrid alone(o), grown(o);
  alone.insertScan(scan, Pose2(1.0, 1.0, 0.0));
  grown.insertScan(scan, Pose2(1.0, 1.0, 0.0));
  // Far away on every side: the raster is reallocated several times.
  for (const Pose2& far : {Pose2(-30.0, 3.0, 0.0), Pose2(35.0, -20.0, 1.0), Pose2(5.0, 40.0, 2.0)})
    grown.insertScan(scan, far);
  const GridSlice a = alone.slice(), g = grown.slice();
  EXPECT_GT(g.width, 1200);
  int compared = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (!a.known(x, y)) continue;
      int gx, gy;
      g.cellOf(a.cellCenter(x, y), gx, gy);
      ASSERT_TRUE(g.inside(gx, gy));
      EXPECT_EQ(a.at(x, y), g.at(gx, gy));
      ++compared;
    }
  EXPECT_GT(compared, 1000);
}

TEST(OccupancyGridRules, RasterLimitAndUnusablePoses) {
  GridOptions o;
  o.max_cells = 200 * 200;
  OccupancyGrid grid(o);
  const LaserScan scan = handMadeScan({2.0f, 2.0f, 2.0f}, -0.1, 0.1);
  grid.insertScan(scan, Pose2(0.0, 0.0, 0.0));
  EXPECT_THROW(grid.insertScan(scan, Pose2(50.0, 0.0, 0.0)), std::length_error);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NO_THROW(grid.insertScan(scan, Pose2(nan, 0.0, 0.0)));   // nothing to insert
  EXPECT_NO_THROW(grid.insertScan(scan, Pose2(1e7, 0.0, 0.0)));   // beyond OctoMap's key range: dropped, as there
  EXPECT_THROW(OccupancyGrid(GridOptions{.resolution = 0.0}), std::invalid_argument);
}

}  // namespace
}  // namespace polarslam
