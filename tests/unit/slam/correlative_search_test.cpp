// CorrelativeMapSearch: the branch-and-bound finds what scoring every pose finds, places a scan
// in a map where it was taken, and returns every look-alike place of a symmetric map.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "slam/correlative_search.hpp"
#include "unit/slam/synthetic_run.hpp"

namespace polarslam {
namespace {

/// Points along the segments of `world`, every `step` m.
std::vector<Vec2> pointsOf(const std::vector<std::pair<Vec2, Vec2>>& walls, double step) {
  std::vector<Vec2> points;
  for (const auto& [a, b] : walls) {
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
    for (int i = 0; i <= n; ++i) points.push_back(a + (b - a) * (static_cast<double>(i) / n));
  }
  return points;
}

/// The readings of a scan from `pose` in the loop world, in the robot frame.
std::vector<Vec2> scanPoints(const Pose2& pose, uint64_t seed) {
  testing::SyntheticRunOptions options;
  std::mt19937_64 rng(seed);
  const LaserScan scan = testing::castScan(testing::makeLoopWorld(), pose, options, rng, 0);
  std::vector<Vec2> points;
  for (size_t i = 0; i < scan.size(); i += 2)
    if (scan.valid(i)) points.push_back(scan.laser_pose.transform(scan.point(i)));
  return points;
}

/// The loop world's map: the points of scans every 5 poses along its path, with their poses.
struct LoopMap {
  std::vector<Vec2> points, positions;
  LoopMap() {
    testing::SyntheticRunOptions options;
    const std::vector<Pose2> path = testing::loopPath(options);
    for (size_t k = 0; k < path.size(); k += 5) {
      for (const Vec2& p : scanPoints(path[k], k)) points.push_back(path[k].transform(p));
      positions.push_back(path[k].translation());
    }
  }
};

/// Calls `visit` with every pose the search considers for `points` (resolution 0.1 m): the lattice
/// within `radius` of `positions` (cells × cells from the origin), at every heading it takes.
template <typename Visit>
void forEverySearchedPose(const CorrelativeMapSearch& search, const std::vector<Vec2>& points,
                          const std::vector<Vec2>& positions, double radius, int cells, Visit visit) {
  double reach = 0.0;
  for (const Vec2& p : points) reach = std::max(reach, p.norm());
  const double step = std::acos(1.0 - 0.01 / (2.0 * reach * reach));
  const int headings = static_cast<int>(std::ceil(2.0 * std::numbers::pi / step));
  for (int h = 0; h < headings; ++h)
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i) {
        const Pose2 pose(search.origin().x() + 0.1 * i, search.origin().y() + 0.1 * j, wrapAngle(2.0 * std::numbers::pi * h / headings));
        if (std::any_of(positions.begin(), positions.end(), [&](const Vec2& c) { return (pose.translation() - c).norm() <= radius; }))
          visit(pose);
      }
}

TEST(CorrelativeMapSearch, FindsTheSamePoseAsScoringEveryPose) {
  // A small asymmetric room: an L of walls and a pillar.
  const std::vector<Vec2> map = pointsOf({{{0, 0}, {6, 0}}, {{6, 0}, {6, 4}}, {{0, 0}, {0, 2.5}}, {{2, 2}, {2.5, 2}}}, 0.05);
  const std::vector<Vec2> positions{{2.0, 1.0}, {4.0, 2.0}};
  const CorrelativeSearchParams params{0.1, 0.1, 1.0, 5};
  const CorrelativeMapSearch search(map, positions, params);
  const Pose2 truth(3.03, 1.12, 0.4);
  std::vector<Vec2> points;
  for (size_t i = 0; i < map.size(); i += 3) points.push_back(truth.inverseTransform(map[i]));
  const CorrelativeQuery query{.min_score = 0.3, .rival_margin = 0.0, .rival_distance = 0.5, .rival_heading = 0.5, .best_at_least = 0.0, .go_on = {}};
  const CorrelativeSearchResult found = search.find(points, query);
  ASSERT_FALSE(found.places.empty());

  // Every searched pose scored: the same lattice and headings the search uses.
  double best = 0.0;
  size_t scored = 0;
  forEverySearchedPose(search, points, positions, 0.99, 120, [&](const Pose2& pose) {
    ++scored;
    best = std::max(best, search.score(points, pose));
  });
  EXPECT_GE(found.places.front().score, best - 1e-12) << "the search missed the best pose";
  EXPECT_NEAR(found.places.front().score, search.score(points, found.places.front().pose), 1e-12);
  EXPECT_LT(found.scored_nodes, scored / 5) << "branch and bound scored nearly every pose";
  EXPECT_LT((found.places.front().pose.translation() - truth.translation()).norm(), 0.15);
  EXPECT_LT(std::abs(wrapAngle(found.places.front().pose.theta - truth.theta)), 0.05);
}

TEST(CorrelativeMapSearch, PlacesAScanOfTheLoopWhereItWasTaken) {
  const LoopMap loop;
  const CorrelativeMapSearch search(loop.points, loop.positions, CorrelativeSearchParams{});
  const Pose2 truth(-2.0, -3.0, 0.1);  // the lower corridor, between mapped scans
  const CorrelativeSearchResult found = search.find(scanPoints(truth, 99), CorrelativeQuery{});
  ASSERT_FALSE(found.places.empty());
  const CorrelativeHit& best = found.places.front();
  EXPECT_LT((best.pose.translation() - truth.translation()).norm(), 0.1);
  EXPECT_LT(std::abs(wrapAngle(best.pose.theta - truth.theta)), 0.03);
  EXPECT_GT(best.score, 0.8);
  // A point's cell moves over a group of headings in proportion to its range. Bounding each point
  // by four windows that cover its own motion scores 5 418 nodes here; by one window twice as wide,
  // 21 472; by one window for the farthest point's motion, 35 694.
  EXPECT_LT(found.scored_nodes, 7000u) << "the bound no longer follows each point's own motion";
}

TEST(CorrelativeMapSearch, RefinePlacesAScanFromAPoseNearBy) {
  const LoopMap loop;
  const CorrelativeMapSearch search(loop.points, loop.positions, CorrelativeSearchParams{});
  const Pose2 truth(-2.0, -3.0, 0.1);
  const std::vector<Vec2> points = scanPoints(truth, 98);
  const Pose2 off(truth.x + 0.15, truth.y - 0.1, truth.theta + deg2rad(5.0));
  const CorrelativeHit refined = search.refine(points, off, 0.3, deg2rad(8.0));
  EXPECT_LT((refined.pose.translation() - truth.translation()).norm(), 0.06);
  EXPECT_LT(std::abs(wrapAngle(refined.pose.theta - truth.theta)), deg2rad(0.6));
  EXPECT_GT(refined.score, search.score(points, off));
  const CorrelativeHit stay = search.refine(points, off, 0.0, 0.0);
  EXPECT_EQ(stay.score, search.score(points, off)) << "a zero window scores the pose itself";
}

// refine steps each point's cell by whole cells per heading: it must find what scoring every pose
// of its window finds, near the grid's edge (where points fall off it) as well as inside.
TEST(CorrelativeMapSearch, RefineFindsTheBestScoreOfItsWindowAsScoringEveryPoseDoes) {
  const LoopMap loop;
  const CorrelativeMapSearch search(loop.points, loop.positions, CorrelativeSearchParams{});
  const double translation = 0.2, rotation = deg2rad(3.0), res = CorrelativeSearchParams{}.resolution;
  const std::vector<Vec2> points = scanPoints(Pose2(-2.0, -3.0, 0.1), 98);
  double reach = 0.0;
  for (const Vec2& p : points) reach = std::max(reach, p.norm());
  const double step = std::acos(1.0 - res * res / (2.0 * reach * reach));
  const int cells = static_cast<int>(std::ceil(translation / res)), turns = static_cast<int>(std::ceil(rotation / step));
  for (const Pose2& from : {Pose2(-1.87, -3.13, 0.17), Pose2(search.origin().x() + 0.03, -3.0, 0.4)}) {
    double best = search.score(points, from);
    for (int t = -turns; t <= turns; ++t)
      for (int j = -cells; j <= cells; ++j)
        for (int i = -cells; i <= cells; ++i)
          best = std::max(best, search.score(points, Pose2(from.x + i * res, from.y + j * res, wrapAngle(from.theta + t * step))));
    const CorrelativeHit refined = search.refine(points, from, translation, rotation);
    EXPECT_NEAR(refined.score, best, 1e-12) << "from " << from.x << ", " << from.y;
    EXPECT_NEAR(search.score(points, refined.pose), refined.score, 1e-12) << "the pose returned has the score returned";
  }
}

// A pose far off the grid, or not finite, has nothing around it to refine: it comes back as given
// (a NaN pose's cells were an undefined conversion, found by tests/fuzz/global_search.cpp).
TEST(CorrelativeMapSearch, RefineOfAPoseOffTheGridOrNotFiniteReturnsItAsGiven) {
  const LoopMap loop;
  const CorrelativeMapSearch search(loop.points, loop.positions, CorrelativeSearchParams{});
  const std::vector<Vec2> points = scanPoints(Pose2(-2.0, -3.0, 0.1), 98);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Pose2& from : {Pose2(nan, 0.0, 0.0), Pose2(0.0, 0.0, nan), Pose2(1e12, -3.0, 0.1), Pose2(-2.0, -1e300, 0.1)}) {
    const CorrelativeHit refined = search.refine(points, from, 0.2, 0.05);
    EXPECT_EQ(refined.score, 0.0);
    EXPECT_TRUE(refined.pose.x == from.x || (std::isnan(refined.pose.x) && std::isnan(from.x)));
    EXPECT_TRUE(refined.pose.theta == from.theta || (std::isnan(refined.pose.theta) && std::isnan(from.theta)));
  }
  const CorrelativeHit huge_window = search.refine(points, Pose2(-2.0, -3.0, 0.1), 1e300, 0.0);
  EXPECT_GT(huge_window.score, 0.8) << "a window wider than the grid is the grid";
}

TEST(CorrelativeMapSearch, ASymmetricMapGivesEveryLookAlikePlace) {
  // A square room: a scan of it fits at four headings.
  const std::vector<Vec2> map = pointsOf({{{0, 0}, {4, 0}}, {{4, 0}, {4, 4}}, {{4, 4}, {0, 4}}, {{0, 4}, {0, 0}}}, 0.05);
  const CorrelativeMapSearch search(map, {{2.0, 2.0}}, CorrelativeSearchParams{0.05, 0.1, 0.5, 6});
  std::vector<Vec2> points;
  const Pose2 truth(2.0, 2.0, 0.3);
  for (size_t i = 0; i < map.size(); i += 2) points.push_back(truth.inverseTransform(map[i]));
  const CorrelativeSearchResult found = search.find(points, CorrelativeQuery{});
  EXPECT_EQ(found.places.size(), 4u);
}

TEST(CorrelativeMapSearch, ReportsEveryPlaceWithinTheMarginAsScoringEveryPoseDoes) {
  // A rectangular room with a door gap: look-alike poses at several headings score near the best.
  const std::vector<Vec2> map =
      pointsOf({{{0, 0}, {5, 0}}, {{5, 0}, {5, 3}}, {{5, 3}, {0, 3}}, {{0, 3}, {0, 1.8}}, {{0, 1.2}, {0, 0}}}, 0.05);
  const std::vector<Vec2> positions{{2.5, 1.5}};
  const CorrelativeSearchParams params{0.1, 0.1, 0.8, 4};
  const CorrelativeMapSearch search(map, positions, params);
  const Pose2 truth(2.4, 1.6, 0.2);
  std::vector<Vec2> points;
  for (size_t i = 0; i < map.size(); i += 4) points.push_back(truth.inverseTransform(map[i]));
  const CorrelativeQuery query{.min_score = 0.3, .rival_margin = 0.15, .rival_distance = 0.4, .rival_heading = 0.4, .best_at_least = 0.0, .go_on = {}};
  const CorrelativeSearchResult found = search.find(points, query);
  ASSERT_FALSE(found.places.empty());
  const double floor = found.places.front().score - query.rival_margin;

  size_t within_margin = 0;
  forEverySearchedPose(search, points, positions, 0.79, 80, [&](const Pose2& pose) {
    const double score = search.score(points, pose);
    ASSERT_LE(score, found.places.front().score + 1e-12) << "a pose beats the search's best";
    if (score < floor) return;
    ++within_margin;
    EXPECT_TRUE(std::any_of(found.places.begin(), found.places.end(), [&](const CorrelativeHit& place) {
      return isNear(place.pose, pose, query.rival_distance, query.rival_heading);
    })) << "no place reported near " << pose.x << " " << pose.y << " " << pose.theta << " scoring " << score;
  });
  EXPECT_GT(within_margin, found.places.size()) << "the margin should hold more poses than places";
  EXPECT_GE(found.places.size(), 2u) << "the room's mirror image is a look-alike";
  for (size_t a = 0; a < found.places.size(); ++a) {
    EXPECT_GE(found.places[a].score, floor);
    for (size_t b = 0; b < a; ++b) EXPECT_FALSE(isNear(found.places[a].pose, found.places[b].pose, query.rival_distance, query.rival_heading));
  }
}

// A search that needs its best place to score best_at_least sets lower nodes aside and takes them
// up again once it has one, those that may reach the rivals' threshold: the same places as a
// search from min_score; none if no pose scores that much; the best alone when no rivals are wanted.
TEST(CorrelativeMapSearch, ABestPlaceThresholdFindsTheSamePlacesOrNone) {
  const std::vector<Vec2> map =
      pointsOf({{{0, 0}, {5, 0}}, {{5, 0}, {5, 3}}, {{5, 3}, {0, 3}}, {{0, 3}, {0, 1.8}}, {{0, 1.2}, {0, 0}}}, 0.05);
  const CorrelativeMapSearch search(map, {{2.5, 1.5}}, CorrelativeSearchParams{0.1, 0.1, 0.8, 4});
  const Pose2 truth(2.4, 1.6, 0.2);
  std::vector<Vec2> points;
  for (size_t i = 0; i < map.size(); i += 4) points.push_back(truth.inverseTransform(map[i]));
  CorrelativeQuery query{.min_score = 0.3, .rival_margin = 0.15, .rival_distance = 0.4, .rival_heading = 0.4, .best_at_least = 0.0, .go_on = {}};
  const CorrelativeSearchResult all = search.find(points, query);
  ASSERT_GE(all.places.size(), 2u);
  const double best = all.places.front().score;

  query.best_at_least = best - 0.01;
  const CorrelativeSearchResult from_best = search.find(points, query);
  ASSERT_EQ(from_best.places.size(), all.places.size());
  for (size_t i = 0; i < all.places.size(); ++i) {
    EXPECT_NEAR(from_best.places[i].score, all.places[i].score, 1e-12);
    EXPECT_TRUE(isNear(from_best.places[i].pose, all.places[i].pose, query.rival_distance, query.rival_heading));
  }
  // Where the rivals' threshold (best − rival_margin) is above best_at_least, what was set aside
  // scored too little for it: nothing is scored twice.
  query.best_at_least = best - 0.2;
  const CorrelativeSearchResult from_below = search.find(points, query);
  ASSERT_EQ(from_below.places.size(), all.places.size());
  for (size_t i = 0; i < all.places.size(); ++i) EXPECT_NEAR(from_below.places[i].score, all.places[i].score, 1e-12);
  EXPECT_LE(from_below.scored_nodes, all.scored_nodes);
  query.best_at_least = best + 0.01;
  EXPECT_TRUE(search.find(points, query).places.empty()) << "no pose scores more than the best";
  query.best_at_least = 0.0;
  query.go_on = [](const std::vector<CorrelativeHit>&) { return false; };
  const CorrelativeSearchResult alone = search.find(points, query);
  ASSERT_EQ(alone.places.size(), 1u);
  EXPECT_NEAR(alone.places.front().score, best, 1e-12);
  EXPECT_LT(alone.scored_nodes, all.scored_nodes);
  // Places come best first, and a search told to stop at the second has the first two of all's.
  for (size_t i = 1; i < all.places.size(); ++i) EXPECT_LE(all.places[i].score, all.places[i - 1].score);
  query.go_on = [](const std::vector<CorrelativeHit>& places) { return places.size() < 2; };
  const CorrelativeSearchResult two = search.find(points, query);
  ASSERT_EQ(two.places.size(), 2u);
  EXPECT_NEAR(two.places[1].score, all.places[1].score, 1e-12);
  EXPECT_LE(two.scored_nodes, all.scored_nodes);
}

TEST(CorrelativeMapSearch, AGridBeyondMaxCellsIsRefused) {
  const std::vector<Vec2> map = pointsOf({{{0, 0}, {5, 0}}, {{5, 0}, {5, 3}}}, 0.05);
  CorrelativeSearchParams params{0.1, 0.1, 0.8, 4};
  EXPECT_NO_THROW(CorrelativeMapSearch(map, {{2.5, 1.5}}, params));
  params.max_cells = 1000;  // the map and its margins span about 80 × 60 cells at 0.1 m
  EXPECT_THROW(CorrelativeMapSearch(map, {{2.5, 1.5}}, params), std::length_error);
}

TEST(CorrelativeMapSearch, NothingToSearchFindsNothing) {
  const CorrelativeMapSearch empty_map({}, {{0.0, 0.0}}, CorrelativeSearchParams{});
  EXPECT_TRUE(empty_map.find({{1.0, 0.0}}, CorrelativeQuery{}).places.empty());
  const CorrelativeMapSearch search({{1.0, 0.0}, {1.0, 0.1}}, {{0.0, 0.0}}, CorrelativeSearchParams{});
  EXPECT_TRUE(search.find({}, CorrelativeQuery{}).places.empty());
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(search.find({{nan, 0.0}, {inf, 1.0}}, CorrelativeQuery{}).places.empty());
  EXPECT_EQ(search.score({{nan, 0.0}}, Pose2()), 0.0);
  EXPECT_EQ(search.score({{1e300, 0.0}}, Pose2()), 0.0) << "a point far off the grid scores nothing";
}

}  // namespace
}  // namespace polarslam
