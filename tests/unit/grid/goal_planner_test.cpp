// GoalPlanner: polarslam-grid's goal logic without LCM — plan when a grid and a pose are known,
// re-plan on every newer grid, drop the goal once reached, refuse absurd goals.
#include <gtest/gtest.h>

#include <limits>

#include "grid/goal_planner.hpp"
#include "grid_fixtures.hpp"

namespace polarslam {
namespace {

TEST(GoalPlanner, WaitsForAGridAndAPoseThenPlansAroundTheWall) {
  GoalPlanner planner({}, 0.2);
  std::optional<GoalPlan> plan;
  EXPECT_EQ(planner.setGoal(Vec2(5.0, 0.8), 42, plan), "");
  EXPECT_FALSE(plan);
  EXPECT_EQ(planner.state(), "waiting for a grid");
  EXPECT_FALSE(planner.updateGrid(test::twoRoomGrid().slice())) << "no robot pose yet";
  EXPECT_EQ(planner.state(), "failed: no SLAM pose yet");
  EXPECT_FALSE(planner.updateRobot(Pose2(1.0, 0.8, 0.0)));
  plan = planner.updateGrid(test::twoRoomGrid().slice());
  ASSERT_TRUE(plan);
  EXPECT_EQ(planner.state(), "planned");
  EXPECT_EQ(plan->goal_utime, 42);
  EXPECT_TRUE(plan->goal_exact);
  EXPECT_NEAR((plan->waypoints.front() - Vec2(1.0, 0.8)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((plan->waypoints.back() - Vec2(5.0, 0.8)).norm(), 0.0, 1e-9);
  const World world = test::twoRoomWorld();
  for (size_t i = 1; i < plan->waypoints.size(); ++i)
    for (double t = 0.0; t <= 1.0; t += 0.02)
      EXPECT_GT(test::distanceToWalls(world, plan->waypoints[i - 1] + t * (plan->waypoints[i] - plan->waypoints[i - 1])),
                0.3);
  EXPECT_GT(planner.planLength(), 4.0) << "through the doorway, not through the wall";
}

TEST(GoalPlanner, ReachingTheGoalDropsItAndNewGridsNoLongerPlan) {
  GoalPlanner planner({}, 0.2);
  planner.updateRobot(Pose2(1.0, 0.8, 0.0));
  planner.updateGrid(test::twoRoomGrid().slice());
  std::optional<GoalPlan> plan;
  planner.setGoal(Vec2(2.0, 1.0), 7, plan);
  ASSERT_TRUE(plan);
  EXPECT_FALSE(planner.updateRobot(Pose2(1.7, 1.0, 0.0)));
  EXPECT_TRUE(planner.updateRobot(Pose2(1.9, 1.05, 0.0)));
  EXPECT_EQ(planner.state(), "reached");
  EXPECT_FALSE(planner.hasGoal());
  EXPECT_FALSE(planner.updateGrid(test::twoRoomGrid().slice()));
}

TEST(GoalPlanner, AGoalOutsideTheMapGoesToTheNearestReachableCellAndAbsurdGoalsAreRefused) {
  GoalPlanner planner({}, 0.2);
  planner.updateRobot(Pose2(1.0, 0.8, 0.0));
  planner.updateGrid(test::twoRoomGrid().slice());
  std::optional<GoalPlan> plan;
  EXPECT_EQ(planner.setGoal(Vec2(20.0, 2.0), 1, plan), "");
  ASSERT_TRUE(plan);
  EXPECT_FALSE(plan->goal_exact);
  EXPECT_EQ(planner.state(), "planned to nearest reachable point");
  EXPECT_NE(planner.setGoal(Vec2(std::numeric_limits<double>::quiet_NaN(), 1.0), 2, plan), "");
  EXPECT_NE(planner.setGoal(Vec2(1e9, 1.0), 3, plan), "");
  EXPECT_TRUE(planner.hasGoal()) << "a refused goal leaves the previous one";
}

}  // namespace
}  // namespace polarslam
