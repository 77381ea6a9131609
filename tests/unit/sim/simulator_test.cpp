// The whole simulated robot: event order and rates, determinism, path following, motion
// distortion in the emitted scans, and the bundled worlds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sim/path_follower.hpp"
#include "sim_test_helpers.hpp"

namespace polarslam {
namespace {

using test::RecordingSink;
using test::sourcePath;

/// Every number of every event, in emission order.
std::string fingerprint(const RecordingSink& s) {
  std::ostringstream out;
  out.precision(17);
  for (const auto& l : s.lasers) {
    out << "L" << l.utime;
    for (float r : l.ranges) out << ' ' << r;
  }
  for (const auto& o : s.odometry) out << "O" << o.utime << ' ' << o.pose.x << ' ' << o.pose.y << ' ' << o.pose.theta << ' ' << o.cov(1, 1);
  for (const auto& n : s.sonars) {
    out << "S" << n.utime << ' ' << n.sensor_id;
    for (const auto& t : n.targets) out << ' ' << static_cast<int>(t.kind) << ' ' << t.range << ' ' << t.bearing;
  }
  for (const auto& g : s.truth) out << "G" << g.utime << ' ' << g.pose.x << ' ' << g.pose.y;
  for (int64_t t : s.event_times) out << ' ' << t;
  return out.str();
}

World room() { return loadWorld(sourcePath("config/worlds/room.yaml")); }

TEST(Simulator, SameSeedGivesIdenticalEventsAndOtherSeedsDiffer) {
  Simulator a(room(), RobotDescription{}, 42), b(room(), RobotDescription{}, 42), c(room(), RobotDescription{}, 43);
  const RecordingSink ra = test::run(a, 5.0), rb = test::run(b, 5.0), rc = test::run(c, 5.0);
  EXPECT_EQ(fingerprint(ra), fingerprint(rb));
  EXPECT_NE(fingerprint(ra), fingerprint(rc));
  // Ground truth does not depend on the seed.
  ASSERT_EQ(ra.truth.size(), rc.truth.size());
  EXPECT_EQ(ra.truth.back().pose.x, rc.truth.back().pose.x);
}

TEST(Simulator, EventsAreInTimeOrderAtTheConfiguredRates) {
  RobotDescription cfg;
  Simulator sim(room(), cfg, 1);
  const RecordingSink s = test::run(sim, 10.0);
  EXPECT_TRUE(std::is_sorted(s.event_times.begin(), s.event_times.end()));
  EXPECT_NEAR(sim.time(), 10.0, 1e-9);
  EXPECT_EQ(sim.utime(), cfg.start_utime + 10000000);
  EXPECT_EQ(s.lasers.size(), 100u);    // 10 Hz
  EXPECT_EQ(s.odometry.size(), 500u);  // 50 Hz
  EXPECT_EQ(s.truth.size(), 500u);     // 50 Hz
  EXPECT_EQ(s.sonars.size(), 300u);    // 3 arrays × 10 Hz
  EXPECT_EQ(s.odometry.front().utime, cfg.start_utime);
  EXPECT_EQ(s.lasers[1].utime - s.lasers[0].utime, 100000);
  for (const LaserScan& l : s.lasers) {
    EXPECT_TRUE(validateScan(l).empty());
    EXPECT_EQ(l.size(), 181u);
    EXPECT_NEAR(l.angle_increment, deg2rad(1.0), 1e-12);
    EXPECT_NEAR(l.laser_pose.x, 0.2, 1e-12);
    EXPECT_GT(std::count_if(l.ranges.begin(), l.ranges.end(), [](float r) { return std::isfinite(r); }), 170);
  }
  for (size_t i = 1; i < s.lasers.size(); ++i) EXPECT_EQ(s.lasers[i].seq, s.lasers[i - 1].seq + 1);
}

TEST(Simulator, LaserReadingsAreNearTheTrueRangesWithDefaultErrors) {
  // Sanity of the whole chain with the default SICK-like errors: beam 0 of each scan, taken at
  // a ground-truth instant, is within a few σ of the exact ray cast.
  Simulator sim(room(), RobotDescription{}, 5);
  const RecordingSink s = test::run(sim, 10.0);
  const World w = room();
  std::vector<double> errors;
  for (const LaserScan& l : s.lasers) {
    const auto truth = std::find_if(s.truth.begin(), s.truth.end(), [&](const PoseStamped& p) { return p.utime == l.utime; });
    ASSERT_NE(truth, s.truth.end());
    const Pose2 laser = truth->pose * l.laser_pose;
    const RayHit h = w.castRay(laser.translation(), laser.theta + l.bearing(0), l.range_max, Sensor::Laser);
    if (h.hit && std::isfinite(l.ranges[0])) errors.push_back(l.ranges[0] - h.range);
  }
  ASSERT_GT(errors.size(), 80u);
  for (double e : errors) EXPECT_LT(std::abs(e), 0.08);
}

TEST(Simulator, ScansAreDistortedWhenTheRobotTurns) {
  RobotDescription cfg = test::exactConfig();
  cfg.laser.time_increment = 0.0005;  // 90 ms per scan: distortion well above noise
  cfg.sonars.clear();
  const World w = room();
  Simulator sim(w, cfg, 1);
  const RecordingSink s = test::run(sim, 20.0);
  int distorted = 0;
  for (const LaserScan& l : s.lasers) {
    const auto truth = std::find_if(s.truth.begin(), s.truth.end(), [&](const PoseStamped& p) { return p.utime == l.utime; });
    ASSERT_NE(truth, s.truth.end());
    const Pose2 at_start = truth->pose * l.laser_pose;
    auto frozenRange = [&](size_t i) {
      return w.castRay(at_start.translation(), at_start.theta + l.bearing(i), l.range_max, Sensor::Laser).range;
    };
    EXPECT_NEAR(l.ranges[0], frozenRange(0), 1e-5);  // beam 0 is measured at the scan's stamp
    double worst = 0.0;
    for (size_t i = 0; i < l.size(); ++i) worst = std::max(worst, std::abs(l.ranges[i] - frozenRange(i)));
    if (worst > 0.02) ++distorted;
  }
  EXPECT_GT(distorted, 50);  // the room loop is one long turn
}

TEST(Simulator, PathFollowerVisitsWaypointsAndStopsAtTheLast) {
  RobotDescription cfg = test::exactConfig();
  cfg.laser.enabled = false;
  cfg.sonars.clear();
  World w = room();
  w.start = Pose2(-1.0, -1.5, 0.0);
  w.path = {{{-1.0, -1.5}, {1.0, -1.5}, {1.0, 1.0}, {-0.5, 1.0}, {-0.5, -0.5}}, false};
  Simulator sim(w, cfg, 1);
  const RecordingSink s = test::run(sim, 120.0);
  EXPECT_TRUE(sim.finished());
  EXPECT_LT(sim.time(), 60.0);
  const Pose2 end = sim.truePose();
  EXPECT_LT((end.translation() - Vec2(-0.5, -0.5)).norm(), cfg.robot.follower.goal_tolerance + 0.03);
  for (const Vec2& wp : w.path.waypoints) {
    double closest = 1e9;
    for (const PoseStamped& p : s.truth) closest = std::min(closest, (p.pose.translation() - wp).norm());
    EXPECT_LT(closest, 0.3) << wp.transpose();  // pure pursuit cuts corners by less than its look-ahead
  }
  // Speed and turn-rate limits hold.
  for (size_t i = 1; i < s.truth.size(); ++i) {
    const double dt = 1e-6 * static_cast<double>(s.truth[i].utime - s.truth[i - 1].utime);
    const double v = (s.truth[i].pose.translation() - s.truth[i - 1].pose.translation()).norm() / dt;
    const double w_rate = std::abs(wrapAngle(s.truth[i].pose.theta - s.truth[i - 1].pose.theta)) / dt;
    EXPECT_LE(v, cfg.robot.max_speed + 1e-9);
    EXPECT_LE(w_rate, cfg.robot.max_turn_rate + 1e-9);
  }
  // Never closer than 0.35 m to a wall along the way.
  for (const PoseStamped& p : s.truth)
    for (const WallSegment& seg : w.segments()) {
      const Vec2 e = seg.b - seg.a;
      const double u = std::clamp((p.pose.translation() - seg.a).dot(e) / e.squaredNorm(), 0.0, 1.0);
      EXPECT_GT((seg.a + u * e - p.pose.translation()).norm(), 0.3);
    }
}

TEST(Simulator, SetPathReplacesTheRemainingPath) {
  RobotDescription cfg = test::exactConfig();
  cfg.laser.enabled = false;
  cfg.sonars.clear();
  Simulator sim(room(), cfg, 1);  // the room's path loops forever
  test::run(sim, 3.0);
  EXPECT_FALSE(sim.finished());
  sim.setPath({{0.8, 1.2}});
  test::run(sim, 60.0);
  EXPECT_TRUE(sim.finished());
  EXPECT_LT((sim.truePose().translation() - Vec2(0.8, 1.2)).norm(), 0.08);
}

TEST(Simulator, RobotWithoutPathStandsStill) {
  World w = room();
  w.path = {};
  w.start = Pose2(0.3, 0.2, 1.0);
  Simulator sim(w, test::exactConfig(), 1);
  RecordingSink s;
  for (int i = 0; i < 100; ++i) sim.step(s);
  EXPECT_TRUE(sim.finished());
  EXPECT_NEAR(s.truth.back().pose.x, 0.3, 1e-12);
  EXPECT_NEAR(s.truth.back().pose.theta, 1.0, 1e-12);
  EXPECT_EQ(s.odometry.back().pose.x, 0.0);
}

TEST(Simulator, BundledWorldsLoadAndTheirPathsStayClearOfWalls) {
  for (const char* name : {"room", "corridor", "office"}) {
    const World w = loadWorld(sourcePath(std::string("config/worlds/") + name + ".yaml"));
    ASSERT_FALSE(w.path.waypoints.empty()) << name;
    // Every leg of the path is free of walls for the laser and the sonar.
    const auto& wp = w.path.waypoints;
    const size_t legs = w.path.loop ? wp.size() : wp.size() - 1;
    for (size_t i = 0; i < legs; ++i) {
      const Vec2 a = wp[i], b = wp[(i + 1) % wp.size()];
      EXPECT_TRUE(w.lineOfSight(a, b, Sensor::Sonar, 0.0)) << name << " leg " << i;
      EXPECT_TRUE(w.lineOfSight(a, b, Sensor::Laser, 0.0)) << name << " leg " << i;
    }
  }
}

double closestWall(const World& w, const Vec2& p) {
  double closest = 1e9;
  for (const WallSegment& seg : w.segments()) {
    const Vec2 e = seg.b - seg.a;
    const double u = std::clamp((p - seg.a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    closest = std::min(closest, (seg.a + u * e - p).norm());
  }
  return closest;
}

TEST(Simulator, OfficeDriveClosesItsLoopInAFewMinutesWithoutTouchingWalls) {
  RobotDescription cfg = test::exactConfig();
  cfg.laser.enabled = false;
  cfg.sonars.clear();
  const World w = loadWorld(sourcePath("config/worlds/office.yaml"));
  Simulator sim(w, cfg, 1);
  const RecordingSink s = test::run(sim, 600.0);
  EXPECT_TRUE(sim.finished());
  EXPECT_GT(sim.time(), 120.0);
  EXPECT_LT(sim.time(), 240.0);
  double length = 0.0, nearest_wall = 1e9;
  for (size_t i = 0; i < s.truth.size(); ++i) {
    if (i > 0) length += (s.truth[i].pose.translation() - s.truth[i - 1].pose.translation()).norm();
    if (i % 5 == 0) nearest_wall = std::min(nearest_wall, closestWall(w, s.truth[i].pose.translation()));
  }
  EXPECT_GT(length, 70.0);
  EXPECT_LT(length, 85.0);
  EXPECT_GT(nearest_wall, 0.3);  // doors are 1.2 m wide; pure pursuit cuts corners by < 0.3 m
  EXPECT_LT((s.truth.back().pose.translation() - s.truth.front().pose.translation()).norm(), 1.0);
}

TEST(Simulator, OfficeWorldHasTheFeaturesTheExperimentsNeed) {
  const World w = loadWorld(sourcePath("config/worlds/office.yaml"));
  int glass = 0, absorbing = 0;
  for (const WallSegment& s : w.segments()) {
    glass += s.material == Material::Glass;
    absorbing += s.material == Material::Absorbing;
  }
  EXPECT_GT(glass, 0);
  EXPECT_GT(absorbing, 0);
  double length = 0.0;
  const auto& wp = w.path.waypoints;
  for (size_t i = 1; i < wp.size(); ++i) length += (wp[i] - wp[i - 1]).norm();
  EXPECT_GT(length, 60.0);
  EXPECT_LT(length, 130.0);
  // The loop closes: the path ends where it started.
  EXPECT_LT((wp.back() - wp.front()).norm(), 1.0);
}

}  // namespace
}  // namespace polarslam
