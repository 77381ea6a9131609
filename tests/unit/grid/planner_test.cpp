// Planning on grids built from exact scans, checked against the true walls; path tracking
// driving the simulated robot to a goal.
#include <gtest/gtest.h>

#include <random>

#include "grid/path_tracker.hpp"
#include "grid/planner.hpp"
#include "grid_fixtures.hpp"
#include "sim/simulator.hpp"

namespace polarslam {
namespace {

using test::castScan;
using test::distanceToWalls;

/// Smallest distance from the polyline to any true wall (sampled every 1 cm).
double pathClearance(const World& world, const std::vector<Vec2>& path) {
  double clearance = std::numeric_limits<double>::infinity();
  for (size_t i = 1; i < path.size(); ++i) {
    const double length = (path[i] - path[i - 1]).norm();
    const int n = std::max(1, static_cast<int>(length / 0.01));
    for (int s = 0; s <= n; ++s)
      clearance = std::min(clearance, distanceToWalls(world, path[i - 1] + (path[i] - path[i - 1]) * (double(s) / n)));
  }
  return clearance;
}

double length(const std::vector<Vec2>& path) {
  double l = 0.0;
  for (size_t i = 1; i < path.size(); ++i) l += (path[i] - path[i - 1]).norm();
  return l;
}

TEST(ObstacleClearance, MatchesBruteForce) {
  GridSlice slice;
  slice.resolution = 0.1;
  slice.width = 37;
  slice.height = 23;
  slice.probability.assign(static_cast<size_t>(slice.width) * slice.height, 0.1f);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> x(0, slice.width - 1), y(0, slice.height - 1);
  std::vector<std::pair<int, int>> obstacles;
  for (int k = 0; k < 25; ++k) {
    obstacles.push_back({x(rng), y(rng)});
    slice.probability[slice.index(obstacles.back().first, obstacles.back().second)] = 0.9f;
  }
  const std::vector<float> clearance = obstacleClearance(slice);
  for (int j = 0; j < slice.height; ++j)
    for (int i = 0; i < slice.width; ++i) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& [ox, oy] : obstacles) best = std::min(best, std::hypot(i - ox, j - oy) * slice.resolution);
      EXPECT_NEAR(clearance[slice.index(i, j)], best, 1e-5);
    }
}

TEST(Planner, FindsACollisionFreePathThroughTheDoorway) {
  const World world = test::twoRoomWorld();
  const GridSlice slice = test::twoRoomGrid().slice();
  PlannerOptions o;
  const PlanResult plan = planPath(slice, {1.0, 0.8}, {5.0, 0.8}, o);
  ASSERT_TRUE(plan.found) << plan.failure;
  EXPECT_TRUE(plan.goal_exact);
  EXPECT_EQ(plan.waypoints.front(), Vec2(1.0, 0.8));
  EXPECT_EQ(plan.waypoints.back(), Vec2(5.0, 0.8));
  // Occupied cells are where the walls are; inflation by robot_radius keeps the path that far
  // from them, less the half-diagonal of a cell for discretisation.
  EXPECT_GE(pathClearance(world, plan.waypoints), o.robot_radius - 0.5 * std::sqrt(2.0) * slice.resolution);
  // Through the doorway (y ∈ [1.42, 2.62]): never shorter than the straight lines via its lower
  // jamb, and not much longer.
  const double via_jamb = 2 * std::hypot(2.0, 1.42 + o.robot_radius - 0.8);
  EXPECT_GT(plan.length, via_jamb - 0.05);
  EXPECT_LT(plan.length, via_jamb + 1.0);
  EXPECT_NEAR(plan.length, length(plan.waypoints), 1e-9);
}

TEST(Planner, GoalInsideAWallIsReplacedByTheNearestReachableFreeCell) {
  const World world = test::twoRoomWorld();
  const GridSlice slice = test::twoRoomGrid().slice();
  const PlanResult plan = planPath(slice, {1.0, 2.0}, {3.013, 0.7}, {});
  ASSERT_TRUE(plan.found);
  EXPECT_FALSE(plan.goal_exact);
  EXPECT_LT((plan.goal - Vec2(3.013, 0.7)).norm(), 0.5);
  EXPECT_GE(distanceToWalls(world, plan.goal), 0.3);
}

TEST(Planner, GoalOutsideTheMappedAreaEndsAtTheNearestReachableCell) {
  const GridSlice slice = test::twoRoomGrid().slice();
  const PlanResult plan = planPath(slice, {1.0, 2.0}, {9.0, 2.0}, {});
  ASSERT_TRUE(plan.found);
  EXPECT_FALSE(plan.goal_exact);
  EXPECT_GT(plan.goal.x(), 5.4);  // as far east as the robot fits
}

TEST(Planner, StartTooCloseToAWallLeavesItFirst) {
  const World world = test::twoRoomWorld();
  const GridSlice slice = test::twoRoomGrid().slice();
  const PlanResult plan = planPath(slice, {0.2, 2.0}, {1.5, 2.0}, {});
  ASSERT_TRUE(plan.found) << plan.failure;
  EXPECT_EQ(plan.waypoints.front(), Vec2(0.2, 2.0));
  EXPECT_GE(pathClearance(world, {plan.waypoints.begin() + 1, plan.waypoints.end()}), 0.3);
}

TEST(Planner, EmptyGridFails) {
  const PlanResult plan = planPath(GridSlice{}, {0, 0}, {1, 1}, {});
  EXPECT_FALSE(plan.found);
  EXPECT_FALSE(plan.failure.empty());
}

TEST(PathTracker, AdvancesAndReexpressesAroundTheRobot) {
  PathTracker tracker;
  tracker.setPath({{0, 0}, {2, 0}, {2, 2}});
  const Pose2 map_pose(1.0, 0.0, 0.0), drive_pose(10.0, 5.0, std::numbers::pi / 2);
  const std::vector<Vec2> drive = tracker.update(map_pose, drive_pose);
  ASSERT_EQ(drive.size(), 3u);  // robot, (2, 0), (2, 2)
  EXPECT_NEAR((drive[0] - Vec2(10, 5)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((drive[1] - Vec2(10, 6)).norm(), 0.0, 1e-12);   // 1 m ahead of the robot
  EXPECT_NEAR((drive[2] - Vec2(8, 6)).norm(), 0.0, 1e-12);    // then 2 m to its left
  tracker.update({2.1, 0.05, 1.5}, drive_pose);                // passed (2, 0)
  EXPECT_EQ(tracker.nextWaypoint(), 2u);
  EXPECT_TRUE(tracker.update({2.0, 1.95, 1.5}, drive_pose).empty());
  EXPECT_TRUE(tracker.goalReached());
}

class NullSink : public SimSink {
 public:
  void onLaser(const LaserScan&) override {}
  void onSonar(const SonarScan&) override {}
  void onOdometry(const OdometryReading&) override {}
  void onGroundTruth(const PoseStamped&) override {}
};

struct DriveResult {
  bool reached = false;
  Vec2 final_position = Vec2::Zero();
  double travelled = 0.0;  ///< m, true path length
  double clearance = std::numeric_limits<double>::infinity();
};

/// Drives the simulated robot along a map-frame path. `world_to_estimate` is where the SLAM
/// map believes the world is (identity = a perfect map in the world frame); the tracker is fed
/// that estimate every 0.1 s, as SLAM_POSE arrives.
DriveResult drive(Simulator& sim, PathTracker& tracker, const Pose2& world_to_estimate, double seconds) {
  NullSink sink;
  DriveResult r;
  int step = 0;
  while (sim.time() < seconds) {
    if (step++ % 10 == 0) {
      const Pose2 truth = sim.truePose();
      const std::vector<Vec2> path = tracker.update(world_to_estimate * truth, truth);
      if (tracker.goalReached()) break;
      sim.setPath(path);
    }
    const Vec2 before = sim.truePose().translation();
    sim.step(sink);
    r.travelled += (sim.truePose().translation() - before).norm();
    r.clearance = std::min(r.clearance, distanceToWalls(sim.world(), sim.truePose().translation()));
  }
  r.reached = tracker.goalReached();
  r.final_position = sim.truePose().translation();
  return r;
}

/// The grid is mapped in the robot's start frame (as SLAM maps are); the tracker sees the
/// robot through an estimate that may be off by a fixed transform (a shifted SLAM map).
void planAndDriveInRoom(const Pose2& map_error) {
  World world = loadWorld(POLARSLAM_SOURCE_DIR "/config/worlds/room.yaml");
  world.path.waypoints.clear();
  const Pose2 start = *world.start;
  const Pose2 world_to_map = map_error * start.inverse();
  std::vector<LaserScan> scans;
  std::vector<Pose2> map_poses;
  for (const Pose2& p : {start, Pose2(0.5, 1.0, 2.0), Pose2(-0.5, 0.0, -1.0), Pose2(0.7, -1.5, 3.0)}) {
    scans.push_back(castScan(world, p));
    map_poses.push_back(world_to_map * p);
  }
  const GridSlice slice = buildGrid(scans, map_poses).slice();
  Simulator sim(world, RobotDescription{}, 11);
  PlannerOptions planner;
  planner.robot_radius = 0.35;
  for (const Vec2& world_goal : {Vec2(0.8, 1.3), Vec2(-0.8, -1.4)}) {
    const Vec2 map_goal = world_to_map.transform(world_goal);
    const PlanResult plan = planPath(slice, (world_to_map * sim.truePose()).translation(), map_goal, planner);
    ASSERT_TRUE(plan.found) << plan.failure;
    ASSERT_TRUE(plan.goal_exact);
    PathTracker tracker;
    tracker.setPath(plan.waypoints);
    const Vec2 from = sim.truePose().translation();
    const DriveResult r = drive(sim, tracker, world_to_map, sim.time() + 60.0);
    ASSERT_TRUE(r.reached) << "stuck at " << r.final_position.transpose();
    // The robot stops where the map says the goal is.
    EXPECT_LT((world_to_map.transform(r.final_position) - map_goal).norm(), 0.15);
    EXPECT_GT(r.clearance, 0.25);
    EXPECT_GT(r.travelled, (world_goal - from).norm() - 0.15);  // the robot body (wheel base 0.5 m) never touched a wall
  }
}

TEST(PathTracking, DrivesTheSimulatedRobotToGoalsInTheStartFrameMap) { planAndDriveInRoom(Pose2()); }

TEST(PathTracking, FollowsTheMapWhenTheMapIsShifted) { planAndDriveInRoom(Pose2(0.08, -0.05, deg2rad(2.0))); }

}  // namespace
}  // namespace polarslam
