// World loading and ray casting against hand-computed geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <unistd.h>

#include "sim/world.hpp"

namespace polarslam {
namespace {

const std::string kRoom = std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/room.yaml";

TEST(World, LoadsRoomWithBumpAndBox) {
  const World w = loadWorld(kRoom);
  EXPECT_EQ(w.name, "room");
  // 4 outer walls + 4 extra segments for the pillar bump + 4 box sides.
  EXPECT_EQ(w.segments().size(), 12u);
  EXPECT_EQ(w.polylines().size(), 2u);
  ASSERT_TRUE(w.start.has_value());
  EXPECT_NEAR(w.start->theta, M_PI / 2, 1e-12);
  EXPECT_EQ(w.path.waypoints.size(), 4u);
  EXPECT_TRUE(w.path.loop);
  EXPECT_NEAR(w.boundsMin().x(), -1.5, 1e-12);
  EXPECT_NEAR(w.boundsMax().y(), 2.0, 1e-12);
}

TEST(World, RayRangesInTheRoomMatchHandGeometry) {
  const World w = loadWorld(kRoom);
  struct Case { Vec2 origin; double dir, range; };
  const Case cases[] = {
      {{0, 0}, 0.0, 1.5},                 // east wall
      {{0, 0}, M_PI / 2, 2.0},            // north wall
      {{0, 0}, M_PI, 1.5},                // west wall
      {{0, 0}, -M_PI / 2, 2.0},           // south wall
      {{0, 0.5}, 0.0, 1.45},              // pillar face, 5 cm proud of the east wall
      {{0, 0.5}, deg2rad(1.0), 1.45 / std::cos(deg2rad(1.0))},
      {{-1.2, 0}, M_PI / 2, 1.3},         // cabinet's south face at y = 1.3
      {{0, 0}, deg2rad(30), 1.5 / std::cos(deg2rad(30))},
  };
  for (const Case& c : cases) {
    const RayHit h = w.castRay(c.origin, c.dir, 10.0, Sensor::Laser);
    ASSERT_TRUE(h.hit) << c.origin.transpose() << " dir " << c.dir;
    EXPECT_TRUE(h.echo);
    EXPECT_NEAR(h.range, c.range, 1e-9) << c.origin.transpose() << " dir " << c.dir;
    EXPECT_NEAR((h.point - c.origin).norm(), c.range, 1e-9);
  }
}

TEST(World, IncidenceAngleIsBetweenRayAndNormal) {
  const World w = loadWorld(kRoom);
  for (double deg : {0.0, 10.0, 30.0, 45.0, -20.0}) {
    const RayHit h = w.castRay({0, 0}, deg2rad(deg), 10.0, Sensor::Laser);
    ASSERT_TRUE(h.hit);
    EXPECT_NEAR(h.incidence, deg2rad(std::abs(deg)), 1e-9) << deg;
  }
  // North wall at 60° from east: the normal is +y, so β = 30°.
  const RayHit h = w.castRay({0, 0}, deg2rad(60), 10.0, Sensor::Laser);
  EXPECT_NEAR(h.range, 2.0 / std::sin(deg2rad(60)), 1e-9);
  EXPECT_NEAR(h.incidence, deg2rad(30), 1e-9);
}

TEST(World, MaxRangeLimitsHits) {
  const World w = loadWorld(kRoom);
  EXPECT_FALSE(w.castRay({0, 0}, 0.0, 1.49, Sensor::Laser).hit);
  EXPECT_TRUE(w.castRay({0, 0}, 0.0, 1.51, Sensor::Laser).hit);
  // Outside the room looking away: nothing at all.
  EXPECT_FALSE(w.castRay({5, 0}, 0.0, 100.0, Sensor::Laser).hit);
  // Outside looking in: hits the east wall's outside at 3.5 m.
  EXPECT_NEAR(w.castRay({5, 0}, M_PI, 100.0, Sensor::Laser).range, 3.5, 1e-9);
}

World glassAndAbsorbingWorld() {
  World w;
  w.addPolyline({{2, -1}, {2, 1}}, {Material::Glass}, false, "glass");
  w.addPolyline({{3, -1}, {3, 1}}, {Material::Wall}, false, "wall behind glass");
  w.addPolyline({{-1, 1.5}, {1, 1.5}}, {Material::Absorbing}, false, "partition");
  w.addPolyline({{-1, 2.5}, {1, 2.5}}, {Material::Wall}, false, "wall behind partition");
  return w;
}

TEST(World, GlassIsTransparentToLaserAndReflectsSound) {
  const World w = glassAndAbsorbingWorld();
  const RayHit laser = w.castRay({0, 0}, 0.0, 10.0, Sensor::Laser);
  ASSERT_TRUE(laser.hit);
  EXPECT_NEAR(laser.range, 3.0, 1e-12);
  EXPECT_EQ(w.segments()[laser.segment].material, Material::Wall);
  const RayHit sonar = w.castRay({0, 0}, 0.0, 10.0, Sensor::Sonar);
  ASSERT_TRUE(sonar.hit);
  EXPECT_TRUE(sonar.echo);
  EXPECT_NEAR(sonar.range, 2.0, 1e-12);
  EXPECT_EQ(w.segments()[sonar.segment].material, Material::Glass);
}

TEST(World, AbsorbingStopsSoundWithoutEchoAndLaserSeesIt) {
  const World w = glassAndAbsorbingWorld();
  const RayHit laser = w.castRay({0, 0}, M_PI / 2, 10.0, Sensor::Laser);
  ASSERT_TRUE(laser.hit);
  EXPECT_TRUE(laser.echo);
  EXPECT_NEAR(laser.range, 1.5, 1e-12);
  const RayHit sonar = w.castRay({0, 0}, M_PI / 2, 10.0, Sensor::Sonar);
  ASSERT_TRUE(sonar.hit);
  EXPECT_FALSE(sonar.echo);  // absorbed: no echo, and the wall behind is hidden
  EXPECT_NEAR(sonar.range, 1.5, 1e-12);
  EXPECT_FALSE(w.lineOfSight({0, 0}, {0, 2.5}, Sensor::Sonar));
  EXPECT_FALSE(w.lineOfSight({0, 0}, {0, 2.5}, Sensor::Laser));
  EXPECT_TRUE(w.lineOfSight({0, 0}, {3, 0}, Sensor::Laser));   // through glass
  EXPECT_FALSE(w.lineOfSight({0, 0}, {3, 0}, Sensor::Sonar));  // glass blocks sound
}

TEST(World, GridTraversalAgreesWithTestingEverySegment) {
  World w = loadWorld(kRoom);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coord(-6.0, 6.0), angle(-M_PI, M_PI), len(0.05, 3.0);
  for (int i = 0; i < 150; ++i) {
    const Vec2 a(coord(rng), coord(rng));
    const double th = angle(rng);
    const Material m = i % 5 == 0 ? Material::Glass : i % 7 == 0 ? Material::Absorbing : Material::Wall;
    w.addPolyline({a, a + len(rng) * Vec2(std::cos(th), std::sin(th))}, {m}, false);
  }
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec2 o(coord(rng) * 1.3, coord(rng) * 1.3);
    const double dir = angle(rng);
    const Sensor s = i % 2 ? Sensor::Laser : Sensor::Sonar;
    const RayHit fast = w.castRay(o, dir, 12.0, s);
    const RayHit slow = w.castRayAllSegments(o, dir, 12.0, s);
    ASSERT_EQ(fast.hit, slow.hit) << i;
    if (!fast.hit) continue;
    ++hits;
    EXPECT_NEAR(fast.range, slow.range, 1e-9) << i;
    EXPECT_EQ(fast.echo, slow.echo) << i;
  }
  EXPECT_GT(hits, 10000);
  // Axis-aligned rays along grid lines (the traversal's special cases).
  for (double y : {-2.0, -1.0, 0.0, 0.5, 1.0}) {
    for (double dir : {0.0, M_PI / 2, M_PI, -M_PI / 2}) {
      const RayHit fast = w.castRay({0.0, y}, dir, 12.0, Sensor::Laser);
      const RayHit slow = w.castRayAllSegments({0.0, y}, dir, 12.0, Sensor::Laser);
      ASSERT_EQ(fast.hit, slow.hit);
      if (fast.hit) {
        EXPECT_NEAR(fast.range, slow.range, 1e-9);
      }
    }
  }
}

TEST(World, SurfacesGroupCollinearPiecesAroundABump) {
  const World w = loadWorld(kRoom);
  // The east wall is split by the bump into two collinear pieces with one surface id.
  const RayHit below = w.castRay({0, 0}, 0.0, 10.0, Sensor::Laser);
  const RayHit above = w.castRay({0, 1.5}, 0.0, 10.0, Sensor::Laser);
  const RayHit bump = w.castRay({0, 0.5}, 0.0, 10.0, Sensor::Laser);
  EXPECT_NE(below.segment, above.segment);
  EXPECT_EQ(w.segments()[below.segment].surface, w.segments()[above.segment].surface);
  EXPECT_NE(w.segments()[bump.segment].surface, w.segments()[below.segment].surface);
}

const WorldVertex& vertexAt(const World& w, const Vec2& p) {
  for (const WorldVertex& v : w.vertices())
    if ((v.position - p).norm() < 1e-6) return v;
  throw std::runtime_error("no vertex there");
}

TEST(World, VerticesLookLikeCornersFromInsideAndEdgesFromOutside) {
  const World w = loadWorld(kRoom);
  const double tol = deg2rad(10);
  // Room corner seen from inside: a concave right angle; from outside: a convex edge.
  EXPECT_EQ(w.vertexAppearance(vertexAt(w, {1.5, 2.0}), {0, 0}, tol), VertexAppearance::RightAngleCorner);
  EXPECT_EQ(w.vertexAppearance(vertexAt(w, {1.5, 2.0}), {3, 3}, tol), VertexAppearance::Edge);
  // Pillar: its front corners are edges, its feet against the wall concave right angles.
  EXPECT_EQ(w.vertexAppearance(vertexAt(w, {1.45, 0.45}), {0, 0}, tol), VertexAppearance::Edge);
  EXPECT_EQ(w.vertexAppearance(vertexAt(w, {1.5, 0.45}), {0, 0}, tol), VertexAppearance::RightAngleCorner);
  // Cabinet corners from the room centre are edges.
  EXPECT_EQ(w.vertexAppearance(vertexAt(w, {-1.0, 1.3}), {0, 0}, tol), VertexAppearance::Edge);
  // A lone wall: its ends are edges; a T-junction gives two right-angle corners.
  World t;
  t.addPolyline({{-2, 0}, {2, 0}}, {Material::Wall}, false);
  t.addPolyline({{0, 0}, {0, 2}}, {Material::Wall}, false);
  EXPECT_EQ(t.vertexAppearance(vertexAt(t, {2, 0}), {0, 1}, tol), VertexAppearance::Edge);
  EXPECT_EQ(t.vertexAppearance(vertexAt(t, {0, 0}), {1, 1}, tol), VertexAppearance::RightAngleCorner);
  EXPECT_EQ(t.vertexAppearance(vertexAt(t, {0, 0}), {-1, 1}, tol), VertexAppearance::RightAngleCorner);
  EXPECT_EQ(t.vertexAppearance(vertexAt(t, {0, 0}), {0, -1}, tol), VertexAppearance::None);  // flat side
  // A 120° concave corner is not a right angle.
  World v;
  v.addPolyline({{2, 0}, {0, 0}, {2 * std::cos(deg2rad(120)), 2 * std::sin(deg2rad(120))}}, {Material::Wall}, false);
  EXPECT_EQ(v.vertexAppearance(vertexAt(v, {0, 0}), {0.5, 0.5}, tol), VertexAppearance::ConcaveCorner);
}

// ---------------------------------------------------------------------------------------------
// Loader errors name the file and the line.

class WorldFileErrors : public ::testing::Test {
 protected:
  std::string write(const std::string& text) {
    const auto dir = std::filesystem::temp_directory_path() / ("polarslam_world_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    path_ = (dir / "bad.yaml").string();
    std::ofstream(path_) << text;
    return path_;
  }
  void TearDown() override { std::filesystem::remove_all(std::filesystem::path(path_).parent_path()); }
  /// Loads `text` and returns the error message (fails the test if it loads).
  std::string errorOf(const std::string& text) {
    try {
      loadWorld(write(text));
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    ADD_FAILURE() << "loaded without error:\n" << text;
    return {};
  }
  std::string path_;
};

TEST_F(WorldFileErrors, NameFileLineAndProblem) {
  struct Case { std::string text, line, words; };
  const Case cases[] = {
      {"name: x\nwalls:\n  - points: [[0, 0]]\n", ":3:", "at least 2 points"},
      {"name: x\nwalls:\n  - points: [[0, 0], [1, zero]]\n", ":3:", "not a number"},
      {"name: x\nwalls:\n  - points: [[0, 0], [1, 0]]\n    material: velvet\n", ":4:", "unknown material 'velvet'"},
      {"name: x\nwalls:\n  - points: [[0, 0], [1, 1e9]]\n", ":3:", "outside the allowed range"},
      {"name: x\nwalls:\n  - closed: true\n", ":3:", "missing key 'points'"},
      {"name: x\n\nwals:\n  - points: [[0, 0], [1, 0]]\n", ":3:", "unknown key 'wals'"},
      {"name: x\n", "bad.yaml", "missing key 'walls'"},
      {"walls:\n  - points: [[0, 0], [1, 0]]\n    bumps:\n      - {at: 0.5, width: 0.9, depth: 0.05}\n", ":4:",
       "beyond its segment"},
      {"walls:\n  - points: [[0, 0], [1, 0], [2, 0]]\n    materials: [wall]\n", ":3:", "2 segments"},
      {"walls:\n  - points: [[0, 0], [1, 0]]\npath:\n  waypoints: [[0, 0], [1, .nan]]\n", ":4:", "finite"},
      {"walls: [\n", ":", "syntax"},
      {"walls:\n  - points: [[0, 0], [4, 0], [4, 4], [0, 4]]\n    closed: true\nstart: {x: 9, y: 1, theta_deg: 0}\n",
       ":4:", "start: (9, 1) is outside the walls"},
      {"walls:\n  - points: [[0, 0], [4, 0], [4, 4], [0, 4]]\n    closed: true\npath:\n  waypoints:\n    - [1, 1]\n"
       "    - [9, 1]\n", ":7:", "(9, 1) is outside the walls"},
      {"walls:\n  - points: [[0, 0], [4, 0], [4, 4], [0, 4]]\n    closed: true\n  - points: [[2, 0], [2, 4]]\n"
       "start: {x: 1, y: 1, theta_deg: 0}\npath:\n  waypoints:\n    - [1, 2]\n    - [3, 2]\n",
       ":9:", "passes through a wall"},
  };
  for (const Case& c : cases) {
    const std::string msg = errorOf(c.text);
    EXPECT_NE(msg.find("bad.yaml"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.line), std::string::npos) << "expected " << c.line << " in: " << msg;
    EXPECT_NE(msg.find(c.words), std::string::npos) << "expected '" << c.words << "' in: " << msg;
  }
}

TEST(WorldFile, MissingFileIsNamed) {
  try {
    loadWorld("/nonexistent/w.yaml");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/w.yaml"), std::string::npos);
  }
}

}  // namespace
}  // namespace polarslam
