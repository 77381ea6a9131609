#pragma once
// Grid path planning (thesis §3.7.1): A* over the 2D occupancy slice inflated by the robot's
// radius, with an extra cost near obstacles so paths keep to the middle of corridors, then
// shortened by line-of-sight shortcuts that never come closer to obstacles than the A* path
// did. Only observed free space is driven through: a goal in unknown space or in an obstacle
// is replaced by the reachable free cell nearest to it, so an exploring robot moves towards
// it and a re-plan on a newer grid takes it further.
#include <string>
#include <vector>

#include "grid/occupancy_grid.hpp"

namespace polarslam {

struct PlannerOptions {
  double robot_radius = 0.35;       ///< m: cells nearer an occupied cell are not entered
  double comfort_distance = 0.7;    ///< m: closer than this, cells cost extra
  double clearance_cost = 3.0;      ///< extra cost per metre at robot_radius, falling to 0 at comfort_distance
  double start_search_radius = 1.0; ///< m: a start in a blocked cell moves to free space this near
};

/// Distance (m) from each cell's centre to the nearest occupied cell's centre (exact Euclidean
/// distance transform); +inf when the slice has no occupied cell.
std::vector<float> obstacleClearance(const GridSlice& slice);

struct PlanResult {
  bool found = false;
  std::vector<Vec2> waypoints;   ///< map frame, from the start to the (possibly substituted) goal
  Vec2 goal = Vec2::Zero();      ///< where the path ends
  bool goal_exact = false;       ///< false: the requested goal was not reachable free space
  double length = 0.0;           ///< m
  int expanded = 0;              ///< A* nodes expanded
  std::string failure;           ///< why not found
};

PlanResult planPath(const GridSlice& slice, const Vec2& start, const Vec2& goal, const PlannerOptions& options = {});

}  // namespace polarslam
