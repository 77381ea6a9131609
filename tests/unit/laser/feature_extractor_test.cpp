// Segmentation and the LaserFeatureExtractor on analytic scans: rooms, corners, breaks, hints,
// bad readings, any beam count and field of view.

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "laser/laser_feature_extractor.hpp"
#include "scratch_files.hpp"
#include "unit/laser/synthetic_scans.hpp"

namespace polarslam {
namespace {

using synthetic::Wall;

/// Index of the wall whose line matches (α, d) within the tolerances, or -1.
int matchingWall(const std::vector<Wall>& walls, double alpha, double d, double angle_tol = deg2rad(2.0),
                 double distance_tol = 0.05) {
  for (size_t k = 0; k < walls.size(); ++k) {
    const PolarLine truth = synthetic::lineThrough(walls[k].a, walls[k].b);
    if (std::abs(wrapAngle(alpha - truth.alpha)) < angle_tol && std::abs(d - truth.d) < distance_tol)
      return static_cast<int>(k);
  }
  return -1;
}

void expectFinite(const FeatureSet& f) {
  for (const LineFeature& l : f.lines) {
    EXPECT_TRUE(std::isfinite(l.alpha) && std::isfinite(l.d) && l.d >= 0.0);
    EXPECT_TRUE(l.cov.allFinite() && l.random_cov.allFinite() && l.systematic_bound.allFinite());
    EXPECT_GT(l.cov.determinant(), 0.0);
  }
  for (const CornerFeature& c : f.corners) {
    EXPECT_TRUE(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.gamma));
    EXPECT_TRUE(c.cov.allFinite());
  }
}

TEST(FeatureExtractor, FindsEveryWallAndCornerOfARoom) {
  const std::vector<Wall> walls = synthetic::room(-3.0, -2.0, 5.0, 3.0);
  LaserScan scan = synthetic::scanOfWalls(walls, -std::numbers::pi / 2, deg2rad(0.5), 361);
  scan.utime = 123456;
  scan.seq = 7;
  scan.laser_pose = Pose2(0.2, 0.0, 0.0);
  ExtractionDetails details;
  const FeatureSet f = LaserFeatureExtractor().extract(scan, {}, {}, &details);
  EXPECT_EQ(f.utime, 123456);
  EXPECT_EQ(f.seq, 7);
  EXPECT_EQ(f.frame, "laser");
  EXPECT_DOUBLE_EQ(f.sensor_pose.x, 0.2);
  expectFinite(f);
  // Front wall and both side walls are in view (the back wall is behind the laser).
  ASSERT_EQ(f.lines.size(), 3u);
  std::vector<int> seen;
  for (const LineFeature& l : f.lines) {
    const int k = matchingWall(walls, l.alpha, l.d, 1e-6, 1e-6);
    EXPECT_GE(k, 0) << "alpha " << l.alpha << " d " << l.d;
    seen.push_back(k);
    EXPECT_GE(l.num_points, 6);
    EXPECT_LE(l.first_index, l.last_index);
    EXPECT_EQ(l.last_index - l.first_index + 1, l.num_points);
    // Endpoints lie on the line and within the wall.
    for (const Vec2& e : {l.endpoint_a, l.endpoint_b}) {
      EXPECT_NEAR(std::cos(l.alpha) * e.x() + std::sin(l.alpha) * e.y(), l.d, 1e-9);
      EXPECT_TRUE(e.x() >= -3.0 - 1e-6 && e.x() <= 5.0 + 1e-6 && e.y() >= -2.0 - 1e-6 && e.y() <= 3.0 + 1e-6);
    }
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::unique(seen.begin(), seen.end()), seen.end()) << "each wall once";
  // The two front corners, concave, with γ pointing back into the room.
  ASSERT_EQ(f.corners.size(), 2u);
  for (const CornerFeature& c : f.corners) {
    EXPECT_FALSE(c.convex);
    const Vec2 apex(c.x, c.y);
    const bool left = (apex - Vec2(5.0, 3.0)).norm() < 1e-6, right = (apex - Vec2(5.0, -2.0)).norm() < 1e-6;
    EXPECT_TRUE(left || right) << apex.transpose();
    EXPECT_NEAR(wrapAngle(c.gamma - deg2rad(left ? -135.0 : 135.0)), 0.0, 1e-6);
    EXPECT_GT(c.num_points, 12);
  }
}

TEST(FeatureExtractor, FullCircleScansSeeAllFourWalls) {
  const std::vector<Wall> walls = synthetic::room(-3.0, -2.0, 5.0, 3.0);
  for (int beams : {360, 720, 1440}) {
    SCOPED_TRACE(beams);
    const double step = 2.0 * std::numbers::pi / beams;
    const LaserScan scan = synthetic::scanOfWalls(walls, -std::numbers::pi, step, beams);
    const FeatureSet f = LaserFeatureExtractor().extract(scan);
    expectFinite(f);
    // The wall behind the laser is split where the scan starts and ends (bearing ±π).
    EXPECT_GE(f.lines.size(), 4u);
    EXPECT_LE(f.lines.size(), 5u);
    std::vector<bool> found(walls.size(), false);
    for (const LineFeature& l : f.lines) {
      const int k = matchingWall(walls, l.alpha, l.d, 1e-6, 1e-6);
      ASSERT_GE(k, 0);
      found[static_cast<size_t>(k)] = true;
    }
    EXPECT_EQ(std::count(found.begin(), found.end(), true), 4);
    EXPECT_EQ(f.corners.size(), 4u);
  }
}

TEST(FeatureExtractor, WorksForAnyBeamCountAndFieldOfView) {
  const std::vector<Wall> walls = synthetic::room(-4.0, -3.0, 4.0, 3.5);
  struct Layout {
    double fov_deg;
    int beams;
  };
  for (const Layout& layout : {Layout{180, 181}, Layout{180, 361}, Layout{240, 682}, Layout{270, 1081},
                               Layout{100, 50}, Layout{360, 10}, Layout{30, 16}}) {
    SCOPED_TRACE(::testing::Message() << layout.fov_deg << " deg, " << layout.beams << " beams");
    const double fov = deg2rad(layout.fov_deg);
    const LaserScan scan = synthetic::scanOfWalls(walls, -fov / 2, fov / (layout.beams - 1), layout.beams);
    const FeatureSet f = LaserFeatureExtractor().extract(scan);
    expectFinite(f);
    for (const LineFeature& l : f.lines) EXPECT_GE(matchingWall(walls, l.alpha, l.d, 1e-6, 1e-6), 0);
    if (layout.beams >= 100) {
      EXPECT_GE(f.lines.size(), 2u);
    }
  }
}

TEST(FeatureExtractor, FindsConvexCornersOfABox) {
  // A box rotated 45° in front of the laser: its near vertex is a convex corner.
  const Vec2 v(2.0, 0.0), up(2.6, 0.6), down(2.6, -0.6), back(3.2, 0.0);
  const std::vector<Wall> walls = {{v, up}, {up, back}, {back, down}, {down, v}};
  const LaserScan scan = synthetic::scanOfWalls(walls, -std::numbers::pi / 2, deg2rad(0.5), 361);
  const FeatureSet f = LaserFeatureExtractor().extract(scan);
  ASSERT_EQ(f.lines.size(), 2u);
  ASSERT_EQ(f.corners.size(), 1u);
  EXPECT_TRUE(f.corners[0].convex);
  EXPECT_NEAR((Vec2(f.corners[0].x, f.corners[0].y) - v).norm(), 0.0, 1e-6);
  EXPECT_NEAR(wrapAngle(f.corners[0].gamma - std::numbers::pi), 0.0, 1e-6);
}

TEST(FeatureExtractor, RangeBreaksSeparateObjects) {
  // A wall with a doorway, and a pillar face in front of the wall.
  const std::vector<Wall> walls = {{{3.0, -3.0}, {3.0, -0.5}}, {{3.0, 0.5}, {3.0, 6.0}}, {{1.5, 1.2}, {1.5, 1.8}}};
  const LaserScan scan = synthetic::scanOfWalls(walls, -std::numbers::pi / 2, deg2rad(0.5), 361);
  const FeatureSet f = LaserFeatureExtractor().extract(scan);
  expectFinite(f);
  // Doorway: two collinear lines; the pillar face splits the upper wall into two more pieces.
  int on_wall = 0, on_pillar = 0;
  for (const LineFeature& l : f.lines) {
    if (std::abs(l.d - 3.0) < 1e-6 && std::abs(l.alpha) < 1e-6) ++on_wall;
    if (std::abs(l.d - 1.5) < 1e-6 && std::abs(l.alpha) < 1e-6) ++on_pillar;
  }
  EXPECT_EQ(on_wall, 3);
  EXPECT_EQ(on_pillar, 1);
  EXPECT_TRUE(f.corners.empty());
}

TEST(FeatureExtractor, BreakHintsSplitLinesButKeepCorners) {
  const std::vector<Wall> wall = {{{2.0, -3.0}, {2.0, 3.0}}};
  const LaserScan scan = synthetic::scanOfWalls(wall, -std::numbers::pi / 2, deg2rad(0.5), 361);
  const LaserFeatureExtractor extractor;
  EXPECT_EQ(extractor.extract(scan).lines.size(), 1u);
  const std::vector<double> hint = {deg2rad(10.0)};
  const FeatureSet split = extractor.extract(scan, hint);
  ASSERT_EQ(split.lines.size(), 2u);
  EXPECT_TRUE(split.corners.empty()) << "collinear halves are not a corner";
  // The two pieces meet at the hinted bearing.
  const double seam = std::atan2(split.lines[0].endpoint_b.y(), split.lines[0].endpoint_b.x());
  EXPECT_NEAR(seam, deg2rad(10.0), deg2rad(0.5) + 1e-6);  // the reading before the hint
  // Hints outside the scan or not finite change nothing.
  const std::vector<double> useless = {deg2rad(120.0), std::numeric_limits<double>::quiet_NaN(), -7.0};
  EXPECT_EQ(extractor.extract(scan, useless).lines.size(), 1u);
  // A hint at a room corner still gives the corner.
  const std::vector<Wall> room = synthetic::room(-3.0, -2.0, 5.0, 3.0);
  const LaserScan room_scan = synthetic::scanOfWalls(room, -std::numbers::pi / 2, deg2rad(0.5), 361);
  const std::vector<double> corner_hint = {std::atan2(3.0, 5.0)};
  EXPECT_EQ(extractor.extract(room_scan, corner_hint).corners.size(), 2u);
}

TEST(FeatureExtractor, ReversedScanGivesTheSameFeatures) {
  const std::vector<Wall> walls = synthetic::room(-3.0, -2.0, 5.0, 3.0);
  const LaserScan forward = synthetic::scanOfWalls(walls, -std::numbers::pi / 2, deg2rad(0.5), 361);
  LaserScan reversed = forward;
  std::reverse(reversed.ranges.begin(), reversed.ranges.end());
  reversed.angle_min = std::numbers::pi / 2;
  reversed.angle_increment = -deg2rad(0.5);
  const LaserFeatureExtractor extractor;
  const FeatureSet a = extractor.extract(forward), b = extractor.extract(reversed);
  ASSERT_EQ(a.lines.size(), b.lines.size());
  ASSERT_EQ(a.corners.size(), b.corners.size());
  for (size_t k = 0; k < a.lines.size(); ++k) {
    EXPECT_NEAR(a.lines[k].alpha, b.lines[k].alpha, 1e-9);
    EXPECT_NEAR(a.lines[k].d, b.lines[k].d, 1e-9);
    // Beam indices refer to the scan as received.
    EXPECT_EQ(a.lines[k].first_index, 360 - b.lines[k].last_index);
    EXPECT_EQ(a.lines[k].last_index, 360 - b.lines[k].first_index);
  }
}

TEST(FeatureExtractor, NeverCrashesOnBadScans) {
  const LaserFeatureExtractor extractor;
  std::vector<LaserScan> scans;
  LaserScan base;
  base.angle_min = -std::numbers::pi / 2;
  base.angle_increment = deg2rad(1.0);
  base.range_max = 30.0;
  scans.push_back(base);  // empty
  LaserScan one = base;
  one.ranges = {2.0f};
  scans.push_back(one);
  LaserScan bad = base;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  bad.ranges = {nan, -1.0f, 0.0f, inf, 1e30f, -inf, 1e-30f, 2.0f, 2.0f, nan, 2.0f, 1e9f};
  scans.push_back(bad);
  LaserScan zero_step = base;
  zero_step.angle_increment = 0.0;
  zero_step.ranges.assign(50, 2.0f);
  scans.push_back(zero_step);
  LaserScan nan_header = base;
  nan_header.angle_min = std::numeric_limits<double>::quiet_NaN();
  nan_header.ranges.assign(50, 2.0f);
  scans.push_back(nan_header);
  LaserScan huge = base;
  huge.angle_increment = 2.0 * std::numbers::pi / 20000;
  huge.ranges.assign(20000, 3.0f);  // a circle: no lines, and no crash
  scans.push_back(huge);
  LaserScan same_range = base;
  same_range.ranges.assign(181, 5.0f);
  scans.push_back(same_range);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> any(-5.0f, 40.0f);
  for (int t = 0; t < 50; ++t) {
    LaserScan garbage = base;
    garbage.angle_increment = deg2rad(0.25 + t * 0.1);
    garbage.ranges.resize(static_cast<size_t>(1 + t * 13));
    for (float& r : garbage.ranges) r = (t % 3 == 0 && r == 0.0f) ? nan : any(rng);
    scans.push_back(garbage);
  }
  // Piecewise-flat staircase ranges: many tiny segments.
  LaserScan stairs = base;
  stairs.angle_increment = deg2rad(0.5);
  for (int i = 0; i < 361; ++i) stairs.ranges.push_back(1.0f + 0.05f * static_cast<float>(i / 3 % 2));
  scans.push_back(stairs);
  for (const LaserScan& scan : scans) {
    const FeatureSet f = extractor.extract(scan);
    expectFinite(f);
  }
  EXPECT_TRUE(extractor.extract(scans[0]).lines.empty());
  EXPECT_TRUE(extractor.extract(scans[1]).lines.empty());
  EXPECT_TRUE(extractor.extract(zero_step).lines.empty());
}

TEST(FeatureExtractor, TrimsBeamsNearlyParallelToAWall) {
  // A long side wall seen down to 87° incidence: the grazing readings are dropped, the rest kept.
  const std::vector<Wall> wall = {{{-1.0, 1.0}, {25.0, 1.0}}};
  const LaserScan scan = synthetic::scanOfWalls(wall, 0.0, deg2rad(0.5), 181);
  const FeatureSet f = LaserFeatureExtractor().extract(scan);
  ASSERT_EQ(f.lines.size(), 1u);
  EXPECT_NEAR(f.lines[0].d, 1.0, 1e-6);  // float ranges
  // Beams within 79° (max_incidence = 80°, less a degree of margin) of the normal at 90°:
  // bearings > 11° (beam 22 lies on the limit).
  EXPECT_EQ(f.lines[0].first_index, 23);
}

/// Extracted lines of noisy room scans are consistent with their filter covariance: the NEES
/// (α, d) has the χ²(2) statistics when the error model is the one generating the errors.
TEST(FeatureExtractor, LineCovarianceIsConsistentOnNoisyScans) {
  LaserFeatureConfig config;
  config.errors = LaserErrorParams{};
  config.errors.range.noise_sigma = 0.01;
  config.errors.range.scan_bias_sigma = 0.005;
  const LaserFeatureExtractor extractor(config);
  const std::vector<Wall> walls = synthetic::room(-3.0, -2.5, 6.0, 4.0);
  std::mt19937_64 rng(8);
  std::normal_distribution<double> bias(0.0, 0.005);
  double nees_sum = 0.0;
  int count = 0, inside_gate = 0;
  for (int t = 0; t < 400; ++t) {
    LaserScan scan = synthetic::scanOfWalls(walls, -std::numbers::pi / 2, deg2rad(0.5), 361);
    synthetic::addNoise(scan, 0.01, rng);
    const float rb = static_cast<float>(bias(rng));
    for (float& r : scan.ranges) r += rb;
    for (const LineFeature& l : extractor.extract(scan).lines) {
      const int k = matchingWall(walls, l.alpha, l.d, deg2rad(10.0), 0.3);  // walls are far apart in (α, d)
      ASSERT_GE(k, 0) << "alpha " << l.alpha << " d " << l.d << " n " << l.num_points << " first " << l.first_index;
      const PolarLine truth = synthetic::lineThrough(walls[static_cast<size_t>(k)].a, walls[static_cast<size_t>(k)].b);
      const Vec2 e(wrapAngle(l.alpha - truth.alpha), l.d - truth.d);
      const double nees = e.dot(l.cov.inverse() * e);
      nees_sum += nees;
      inside_gate += nees < 5.991;  // 95% of χ²(2)
      ++count;
    }
  }
  ASSERT_GT(count, 1000);
  // Lines of one scan share the per-scan bias, so scans are the independent units: generous bounds.
  EXPECT_NEAR(nees_sum / count, 2.0, 0.25);
  EXPECT_NEAR(static_cast<double>(inside_gate) / count, 0.95, 0.03);
}

TEST(FeatureExtractor, SegmentationReportsCornerCandidatesOnlyForPerpendicularNeighbours) {
  // An obtuse (135°) bend is two lines but no corner candidate.
  const std::vector<Wall> walls = {{{2.0, -2.0}, {2.0, 0.0}}, {{2.0, 0.0}, {0.0, 2.0}}};
  const LaserScan scan = synthetic::scanOfWalls(walls, -std::numbers::pi / 2, deg2rad(0.5), 361);
  const FeatureSet f = LaserFeatureExtractor().extract(scan);
  EXPECT_EQ(f.lines.size(), 2u);
  EXPECT_TRUE(f.corners.empty());
}

TEST(LaserFeatureConfig, ReadsTheProjectFeaturesFileAndRejectsTypos) {
  const LaserFeatureConfig c = loadLaserFeatureConfig(POLARSLAM_SOURCE_DIR "/config/laser-features.yaml");
  EXPECT_DOUBLE_EQ(c.errors.range.noise_sigma, 0.01);
  EXPECT_EQ(c.segmentation.min_line_points, 6);
  ScratchFiles scratch;
  const std::string typo = scratch.write("typo.yaml", "laser_features:\n  segmentation:\n    min_line_pionts: 5\n");
  EXPECT_THROW(loadLaserFeatureConfig(typo), std::runtime_error);
  const std::string neither = scratch.write("neither.yaml", "something: 1\n");
  EXPECT_THROW(loadLaserFeatureConfig(neither), std::runtime_error);
  EXPECT_THROW(loadLaserFeatureConfig(POLARSLAM_SOURCE_DIR "/no/such/file.yaml"), std::runtime_error);
}

}  // namespace
}  // namespace polarslam
