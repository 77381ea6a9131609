// Scan projection (docs/algorithms.md §6) and the frame conversions of §1.3 and §5.
#include <gtest/gtest.h>

#include <cmath>

#include "scan_fixtures.hpp"
#include "scanmatch/scan_matcher.hpp"

namespace polarslam {
namespace {

PsmParams unfiltered() {
  PsmParams p;
  p.median_filter = false;
  return p;
}

TEST(Projection, ScanOntoItselfReturnsItsRangesAndEmptyLonePoints) {
  const World room = fixtures::clutteredOffice();
  const PreparedScan s = prepareScan(fixtures::simulateScan(room, {0.3, -0.4, 0.8}, {}), unfiltered());
  Projection p;
  projectScan(*s.geometry, s, Pose2{}, p);
  int lone = 0, covered = 0;
  for (size_t j = 0; j < s.size(); ++j) {
    if (s.bad(j)) continue;
    if (s.segment[j] == 0) {
      ++lone;
      EXPECT_EQ(p.tag[j], kFlagEmpty) << j;
      continue;
    }
    ++covered;
    ASSERT_EQ(p.tag[j], 0) << j;
    EXPECT_NEAR(p.range[j], s.range[j], 1e-5) << j;
  }
  EXPECT_GT(covered, 150);
  EXPECT_GE(lone, 0);
}

TEST(Projection, TranslatedWallGivesTheRangesSeenFromTheNewPlace) {
  // One long wall 3 m ahead (x = 3). The current scan is taken 0.5 m closer and 0.2 m to the
  // left; projected into the reference frame it must give the reference's own ranges 3/cos φ.
  World wall;
  wall.addPolyline({{3.0, -20.0}, {3.0, 20.0}}, {Material::Wall}, false);
  const fixtures::ScanSpec spec;
  const Pose2 cur_pose(0.5, 0.2, 0.1);
  const PreparedScan ref = prepareScan(fixtures::simulateScan(wall, {}, spec), unfiltered());
  const PreparedScan cur = prepareScan(fixtures::simulateScan(wall, cur_pose, spec), unfiltered());
  Projection p;
  projectScan(*ref.geometry, cur, cur_pose, p);
  int checked = 0;
  for (size_t j = 0; j < ref.size(); ++j) {
    if (p.tag[j] != 0 || ref.bad(j)) continue;
    EXPECT_NEAR(p.range[j], 3.0 / std::cos(ref.geometry->bearing(j)), 2e-5 * p.range[j]) << j;
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(Projection, NearerSurfaceHidesFartherOne) {
  // A box 1.7 m ahead of the reference laser, a wall at 4 m. The current laser, 0.5 m to the
  // left, sees the wall also where the reference cannot (parallax); projected into the
  // reference frame those wall samples fall behind the box's face and must lose to it.
  World w;
  w.addPolyline({{4.0, -10.0}, {4.0, 10.0}}, {Material::Wall}, false, "wall");
  w.addBox({2.0, 0.0}, {0.6, 0.6}, 0.0, Material::Wall, "box");
  const fixtures::ScanSpec spec{361, std::numbers::pi, 80.0, 0.0};
  const Pose2 cur_pose(0.0, 0.5, 0.0);
  const PreparedScan ref = prepareScan(fixtures::simulateScan(w, {}, spec), unfiltered());
  const PreparedScan cur = prepareScan(fixtures::simulateScan(w, cur_pose, spec), unfiltered());
  Projection p;
  projectScan(*ref.geometry, cur, cur_pose, p);
  int checked = 0;
  for (size_t j = 0; j < ref.size(); ++j) {
    const double bearing = ref.geometry->bearing(j);
    if (std::abs(bearing) > deg2rad(9.0) || p.tag[j] != 0) continue;
    EXPECT_NEAR(p.range[j], 1.7 / std::cos(bearing), 1e-4) << "bearing " << rad2deg(bearing);
    ++checked;
  }
  EXPECT_GT(checked, 25);
}

TEST(Projection, SurfaceSeenFromBehindIsTaggedOccluded) {
  // A single wall 2 m ahead of the reference laser; the current laser stands beyond it and
  // looks back at it, so it sees the face the reference sees from behind.
  World w;
  w.addPolyline({{2.0, -1.5}, {2.0, 1.5}}, {Material::Wall}, false, "thin wall");
  const Pose2 cur_pose(3.0, 0.0, std::numbers::pi);
  const PreparedScan ref = prepareScan(fixtures::simulateScan(w, {}, {}), unfiltered());
  const PreparedScan cur = prepareScan(fixtures::simulateScan(w, cur_pose, {}), unfiltered());
  Projection p;
  projectScan(*ref.geometry, cur, cur_pose, p);
  int occluded = 0;
  for (size_t j = 0; j < ref.size(); ++j) {
    const double bearing = ref.geometry->bearing(j);
    if (std::abs(bearing) > deg2rad(35.0)) continue;
    EXPECT_EQ(p.tag[j], kFlagOccluded) << rad2deg(bearing);
    EXPECT_NEAR(p.range[j], 2.0 / std::cos(bearing), 1e-4);
    ++occluded;
  }
  EXPECT_GT(occluded, 60);
}

TEST(Projection, OutsideTheReferenceViewStaysEmpty) {
  // The current laser looks backwards: everything it sees is behind the reference laser.
  const World room = fixtures::psmTestRoom();
  const Pose2 cur_pose(0.0, 0.0, std::numbers::pi);
  const PreparedScan ref = prepareScan(fixtures::simulateScan(room, {}, {}), unfiltered());
  const PreparedScan cur = prepareScan(fixtures::simulateScan(room, cur_pose, {}), unfiltered());
  Projection p;
  projectScan(*ref.geometry, cur, cur_pose, p);
  int filled = 0;
  for (size_t j = 1; j + 1 < ref.size(); ++j)
    if (!(p.tag[j] & kFlagEmpty)) ++filled;
  EXPECT_EQ(filled, 0);
}

// §5: the original closed form has the laser on the robot's +Y axis (original frame: +Y
// forward, cm). Our SE(2) form with the mount (L, 0, 0) in the polarslam frame must agree.
TEST(Frames, InitialGuessEqualsTheOriginalClosedForm) {
  fixtures::Noise noise(7);
  const double L = 0.313;
  for (int k = 0; k < 50; ++k) {
    const Pose2 r = fixtures::randomPose(noise, -5, -5, 5, 5), c = fixtures::randomPose(noise, -5, -5, 5, 5);
    // The same robot poses in the original frame: position (x_p, y_p) = (−y, x), heading θ.
    const double xr = -r.y, yr = r.x, xc = -c.y, yc = c.x;
    const double tr = r.theta, tc = c.theta;
    const double xo = L * std::sin(tr - tc) + std::cos(tr) * (xc - xr) + std::sin(tr) * (yc - yr);
    const double yo = L * std::cos(tr - tc) - std::sin(tr) * (xc - xr) + std::cos(tr) * (yc - yr) - L;
    const Pose2 ours = laserPoseInReferenceLaser(r, c, {L, 0, 0}, {L, 0, 0});
    // Result conversion of §1.3: dx = ry, dy = −rx.
    EXPECT_NEAR(ours.x, yo, 1e-12);
    EXPECT_NEAR(ours.y, -xo, 1e-12);
    EXPECT_NEAR(wrapAngle(ours.theta - (tc - tr)), 0.0, 1e-12);
  }
}

TEST(Frames, LaserMotionConvertsBackToRobotMotion) {
  fixtures::Noise noise(8);
  const Pose2 mount(0.78, -0.05, 0.02);
  for (int k = 0; k < 20; ++k) {
    const Pose2 r = fixtures::randomPose(noise, -5, -5, 5, 5), c = fixtures::randomPose(noise, -5, -5, 5, 5);
    const Pose2 laser = laserPoseInReferenceLaser(r, c, mount, mount);
    const Pose2 robot = robotMotionFromLaserMotion(laser, mount, mount);
    const Pose2 truth = between(r, c);
    EXPECT_NEAR(robot.x, truth.x, 1e-12);
    EXPECT_NEAR(robot.y, truth.y, 1e-12);
    EXPECT_NEAR(wrapAngle(robot.theta - truth.theta), 0.0, 1e-12);
  }
}

TEST(Frames, RobotMotionCovarianceMatchesFiniteDifferences) {
  const Pose2 mount(0.4, 0.1, 0.3), laser(0.2, -0.1, 0.25);
  Mat3 J_numeric;
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Vec3 dp = Vec3::Zero();
    dp(k) = h;
    const Pose2 plus = robotMotionFromLaserMotion(Pose2(laser.vec() + dp), mount, mount);
    const Pose2 minus = robotMotionFromLaserMotion(Pose2(laser.vec() - dp), mount, mount);
    J_numeric.col(k) = Vec3(plus.x - minus.x, plus.y - minus.y, wrapAngle(plus.theta - minus.theta)) / (2 * h);
  }
  const Mat3 cov = Vec3(0.01, 0.02, 0.003).asDiagonal();
  const Mat3 expected = J_numeric * cov * J_numeric.transpose();
  const Mat3 got = robotMotionCovariance(laser, cov, mount, mount);
  EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-8);
}

}  // namespace
}  // namespace polarslam
