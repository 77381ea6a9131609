// Sonar planes filled into laser scans: glass the laser misses is filled at the wall's range,
// walls the laser sees are left alone, and spurious one-off echoes are not repeated.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "slam/sonar_planes.hpp"

namespace polarslam {
namespace {

/// 181 beams over 180°, laser at the robot origin, every beam without a return.
LaserScan blindScan() {
  LaserScan scan;
  scan.angle_min = -M_PI / 2;
  scan.angle_increment = M_PI / 180;
  scan.range_max = 8.0;
  scan.ranges.assign(181, std::numeric_limits<float>::infinity());
  return scan;
}

/// A left-hand wall 1 m away, as the left array (at 0, 0.2, facing left) reports it.
SonarScan leftWallEcho() {
  SonarScan sonar;
  sonar.sensor_pose = Pose2(0.0, 0.2, M_PI / 2);
  SonarTarget t;
  t.kind = SonarKind::Plane;
  t.range = 0.8;
  sonar.targets.push_back(t);
  return sonar;
}

TEST(SonarPlanes, GlassTheLaserMissesIsFilledAtTheWallsRange) {
  LaserScan scan = blindScan();
  const std::vector<SonarPlane> planes = sonarPlanes(leftWallEcho());
  ASSERT_EQ(planes.size(), 1u);
  SonarPlaneFillOptions options;
  options.half_extent = 1.0;
  const size_t filled = fillFromSonarPlanes(scan, planes, options);
  // The beams at bearings from 45° to 90° (left; up to 1 m ahead along the wall) meet it.
  EXPECT_NEAR(static_cast<double>(filled), 45.5, 1.0);
  EXPECT_NEAR(scan.ranges[180], 1.0, 1e-5);                                // straight left
  EXPECT_NEAR(scan.ranges[150], 1.0 / std::sin(deg2rad(60.0)), 1e-4);      // 30° ahead of left
  EXPECT_TRUE(std::isinf(scan.ranges[130]));                               // 1.2 m ahead along the wall
  EXPECT_TRUE(std::isinf(scan.ranges[90]));                                // straight ahead: no wall
}

TEST(SonarPlanes, AWallTheLaserSeesIsLeftAlone) {
  LaserScan scan = blindScan();
  for (size_t i = 120; i <= 180; ++i) scan.ranges[i] = static_cast<float>(1.0 / std::sin(scan.bearing(i)));
  scan.ranges[170] = 5.0f;  // a doorway in the wall: the sonar's plane must not close it
  EXPECT_EQ(fillFromSonarPlanes(scan, sonarPlanes(leftWallEcho()), {}), 0u);
  EXPECT_FLOAT_EQ(scan.ranges[170], 5.0f);
}

TEST(SonarPlanes, OnlyPlanesTheNextScanRepeatsAreKept) {
  const std::vector<SonarPlane> before = sonarPlanes(leftWallEcho());
  // The robot drove 0.3 m forward: the same wall, its foot point moved back along it.
  const Pose2 motion(0.3, 0.0, 0.0);
  std::vector<SonarPlane> moved;
  for (const SonarPlane& p : before) moved.push_back(movedPlane(p, motion));
  EXPECT_NEAR(moved[0].foot.x(), -0.3, 1e-9);
  EXPECT_NEAR(moved[0].foot.y(), 1.0, 1e-9);
  const std::vector<SonarPlane> now = sonarPlanes(leftWallEcho());
  EXPECT_EQ(repeatedPlanes(now, moved, {}).size(), 1u);
  SonarScan spurious = leftWallEcho();
  spurious.targets[0].range = 2.5;  // an echo from 2.7 m the previous scan did not have
  EXPECT_TRUE(repeatedPlanes(sonarPlanes(spurious), moved, {}).empty());
}

}  // namespace
}  // namespace polarslam
