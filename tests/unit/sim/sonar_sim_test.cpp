// Simulated advanced sonar: specular planes, corners, edges, materials, occlusion and the
// statistics of its errors.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/sonar_simulator.hpp"
#include "sim_test_helpers.hpp"

namespace polarslam {
namespace {

SonarConfig array60() {
  SonarConfig c;
  c.mount = Pose2();
  c.fov = deg2rad(60);
  return c;
}

std::vector<TrueSonarTarget> ofKind(const std::vector<TrueSonarTarget>& all, SonarKind kind) {
  std::vector<TrueSonarTarget> out;
  for (const auto& t : all)
    if (t.kind == kind) out.push_back(t);
  return out;
}

World singleWall(Material m) {
  World w;
  w.addPolyline({{2, -5}, {2, 5}}, {m}, false);
  return w;
}

TEST(SonarSim, GlassGivesAPlaneEchoAtTheNormalDistance) {
  const auto targets = SonarSimulator::visibleTargets(singleWall(Material::Glass), array60(), Pose2(0, 0, 0.2));
  const auto planes = ofKind(targets, SonarKind::Plane);
  ASSERT_EQ(planes.size(), 1u);
  EXPECT_NEAR(planes[0].range, 2.0, 1e-12);
  EXPECT_NEAR(planes[0].bearing, -0.2, 1e-12);  // the normal direction, seen from the array
}

TEST(SonarSim, AbsorbingWallGivesNoEcho) {
  const World w = singleWall(Material::Absorbing);
  EXPECT_TRUE(SonarSimulator::visibleTargets(w, array60(), Pose2()).empty());
  // Nor does anything behind it.
  World behind = w;
  behind.addPolyline({{3, -5}, {3, 5}}, {Material::Wall}, false);
  EXPECT_TRUE(SonarSimulator::visibleTargets(behind, array60(), Pose2()).empty());
}

TEST(SonarSim, PlaneSeenOnlyWhenItsNormalIsInsideTheFieldOfView) {
  const World w = singleWall(Material::Wall);
  for (double deg : {0.0, 10.0, 29.0, -29.0}) {
    EXPECT_EQ(ofKind(SonarSimulator::visibleTargets(w, array60(), Pose2(0, 0, deg2rad(deg))), SonarKind::Plane).size(), 1u)
        << deg;
  }
  EXPECT_TRUE(SonarSimulator::visibleTargets(w, array60(), Pose2(0, 0, deg2rad(31))).empty());
  for (double deg : {45.0, -60.0}) {
    const auto targets = SonarSimulator::visibleTargets(w, array60(), Pose2(0, 0, deg2rad(deg)));
    EXPECT_TRUE(ofKind(targets, SonarKind::Plane).empty()) << deg;
    EXPECT_EQ(ofKind(targets, SonarKind::Edge).size(), 1u) << deg;  // the wall's end is in view instead
  }
  EXPECT_TRUE(SonarSimulator::visibleTargets(w, array60(), Pose2(0, 0, M_PI)).empty());
  // The wall lies in view but the foot of the perpendicular is not on it: no specular echo.
  World offset;
  offset.addPolyline({{2, 0.5}, {2, 5}}, {Material::Wall}, false);
  const auto targets = SonarSimulator::visibleTargets(offset, array60(), Pose2(0, 0, deg2rad(20)));
  EXPECT_TRUE(ofKind(targets, SonarKind::Plane).empty());
  // …but its free end is an edge.
  const auto edges = ofKind(targets, SonarKind::Edge);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_NEAR(edges[0].range, std::hypot(2.0, 0.5), 1e-12);
  EXPECT_NEAR(edges[0].bearing, std::atan2(0.5, 2.0) - deg2rad(20), 1e-12);
}

TEST(SonarSim, RoomCornerIsACornerAndCabinetCornersAreEdges) {
  const World room = loadWorld(test::sourcePath("config/worlds/room.yaml"));
  // Looking at the south-east corner (1.5, -2) from the centre.
  const double to_corner = std::atan2(-2.0, 1.5);
  const auto corners = ofKind(SonarSimulator::visibleTargets(room, array60(), Pose2(0, 0, to_corner)), SonarKind::Corner);
  ASSERT_EQ(corners.size(), 1u);
  EXPECT_NEAR(corners[0].range, 2.5, 1e-12);
  EXPECT_NEAR(corners[0].bearing, 0.0, 1e-12);
  // Looking at the cabinet's near corner (-1.0, 1.3) from (0, 0).
  const double to_cabinet = std::atan2(1.3, -1.0);
  const auto edges = ofKind(SonarSimulator::visibleTargets(room, array60(), Pose2(0, 0, to_cabinet)), SonarKind::Edge);
  ASSERT_GE(edges.size(), 1u);
  EXPECT_NEAR(edges[0].range, std::hypot(1.0, 1.3), 1e-12);
}

struct PillarView {
  int edges = 0, corners = 0;
  std::vector<double> plane_ranges;
};

/// Targets on or at the foot of the 5 cm pillar on the room's east wall (x 1.45…1.5, y 0.45…0.55).
PillarView viewPillarFrom(const Pose2& array_pose) {
  const World room = loadWorld(test::sourcePath("config/worlds/room.yaml"));
  PillarView view;
  for (const auto& t : SonarSimulator::visibleTargets(room, array60(), array_pose)) {
    const Vec2 p = array_pose.transform({t.range * std::cos(t.bearing), t.range * std::sin(t.bearing)});
    const bool at_pillar = std::abs(p.y() - 0.5) < 0.06 && p.x() > 1.44;
    if (t.kind == SonarKind::Edge && at_pillar && std::abs(p.x() - 1.45) < 1e-9) ++view.edges;
    if (t.kind == SonarKind::Corner && at_pillar && std::abs(p.x() - 1.5) < 1e-9) ++view.corners;
    if (t.kind == SonarKind::Plane) view.plane_ranges.push_back(t.range);
  }
  return view;
}

TEST(SonarSim, SmallFeaturesAreResolved) {
  // Straight in front of the pillar: its two front edges; its feet are in its own shadow; the
  // only plane is its face (the wall's foot point lies behind the pillar).
  const PillarView front = viewPillarFrom(Pose2(0, 0.5, 0));
  EXPECT_EQ(front.edges, 2);
  EXPECT_EQ(front.corners, 0);
  ASSERT_EQ(front.plane_ranges.size(), 1u);
  EXPECT_NEAR(front.plane_ranges[0], 1.45, 1e-12);
  // From below: both edges, and the concave right angle between the pillar and the wall below it.
  const PillarView below = viewPillarFrom(Pose2(0, 0, 0));
  EXPECT_EQ(below.edges, 2);
  EXPECT_EQ(below.corners, 1);
  ASSERT_EQ(below.plane_ranges.size(), 1u);
  EXPECT_NEAR(below.plane_ranges[0], 1.5, 1e-12);  // the wall itself
}

TEST(SonarSim, OccludedTargetsAreNotSeen) {
  World w = singleWall(Material::Wall);
  w.addPolyline({{1, -0.3}, {1, 0.3}}, {Material::Wall}, false);  // a short screen in front
  const auto targets = SonarSimulator::visibleTargets(w, array60(), Pose2());
  const auto planes = ofKind(targets, SonarKind::Plane);
  ASSERT_EQ(planes.size(), 1u);
  EXPECT_NEAR(planes[0].range, 1.0, 1e-12);  // the screen, not the wall behind it
  EXPECT_EQ(ofKind(targets, SonarKind::Edge).size(), 2u);  // the screen's two ends
}

TEST(SonarSim, NoiseMisclassificationAndSpuriousReturnsFollowTheConfig) {
  SonarConfig c = array60();
  c.range_sigma = 0.001;
  c.bearing_sigma = deg2rad(0.1);
  c.misclassification_rate = 0.1;
  c.spurious_rate = 0.3;
  const World w = singleWall(Material::Wall);
  SonarSimulator sonar(c, 17);
  const int scans = 6000;
  int genuine = 0, misclassified = 0, extra = 0;
  double sum_r = 0, sum_r2 = 0, sum_b = 0, sum_b2 = 0;
  for (int k = 0; k < scans; ++k) {
    const SonarScan s = sonar.scan(w, k, Pose2());
    for (const SonarTarget& t : s.targets) {
      const bool near_truth = std::abs(t.range - 2.0) < 0.01 && std::abs(t.bearing) < deg2rad(1);
      if (!near_truth) {
        ++extra;
        continue;
      }
      ++genuine;
      if (t.kind != SonarKind::Plane) ++misclassified;
      sum_r += t.range - 2.0;
      sum_r2 += (t.range - 2.0) * (t.range - 2.0);
      sum_b += t.bearing;
      sum_b2 += t.bearing * t.bearing;
      EXPECT_NEAR(t.cov(0, 0), 1e-6, 1e-15);
    }
  }
  EXPECT_GE(genuine, scans);  // every scan sees the wall (spurious returns rarely fall this close)
  EXPECT_LT(genuine, scans + 10);
  EXPECT_NEAR(static_cast<double>(misclassified) / genuine, 0.1, 0.015);
  EXPECT_NEAR(static_cast<double>(extra) / scans, 0.3, 0.03);
  EXPECT_NEAR(std::sqrt(sum_r2 / genuine - std::pow(sum_r / genuine, 2)), 0.001, 0.00005);
  EXPECT_NEAR(std::sqrt(sum_b2 / genuine - std::pow(sum_b / genuine, 2)), deg2rad(0.1), deg2rad(0.005));
  EXPECT_NEAR(sum_r / genuine, 0.0, 4 * 0.001 / std::sqrt(genuine));
}

TEST(SonarSim, ScansCarryTheArrayGeometry) {
  SonarConfig c;
  c.id = 2;
  c.mount = Pose2(0.0, -0.2, -M_PI / 2);
  c.spurious_rate = 0.0;
  SonarSimulator sonar(c, 1);
  const SonarScan s = sonar.scan(singleWall(Material::Wall), 42, Pose2(0, 0, M_PI / 2));
  EXPECT_EQ(s.utime, 42);
  EXPECT_EQ(s.sensor_id, 2);
  EXPECT_NEAR(s.sensor_pose.y, -0.2, 1e-12);
  EXPECT_NEAR(s.field_of_view, c.fov, 1e-12);
  // Robot facing +y, right-hand array looks along +x at the wall x = 2 from x = 0.2.
  ASSERT_FALSE(s.targets.empty());
  EXPECT_NEAR(s.targets[0].range, 1.8, 0.01);
}

}  // namespace
}  // namespace polarslam
