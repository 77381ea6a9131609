// PSM SLAM's poses anchored to its reference scans: composing each scan's anchor with the final
// pose graph gives the final trajectory (what a recording of a live run is scored with), and the
// grid re-placed from the graph is the same whether scans and anchors come paired (offline) or
// on separate channels in any interleaving (polarslam-grid live).
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <random>

#include "grid/graph_scan_store.hpp"
#include "slam/psm_slam.hpp"
#include "synthetic_run.hpp"

namespace polarslam {
namespace {

double distanceToWalls(const World& world, const Vec2& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const WallSegment& s : world.segments()) {
    const Vec2 d = s.b - s.a;
    const double t = std::clamp((p - s.a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (s.a + t * d - p).norm());
  }
  return best;
}

struct AnchoredRun {
  std::vector<AnchoredPose> anchors;
  std::vector<PoseStamped> online;
  PsmSlam slam;
};

std::unique_ptr<AnchoredRun> runAnchored(const testing::SyntheticRun& run) {
  PsmSlamParams params;
  params.odometry.poses = testing::syntheticOdometryModel();
  auto out = std::make_unique<AnchoredRun>(AnchoredRun{{}, {}, PsmSlam(params)});
  for (size_t k = 0; k < run.scans.size(); ++k) {
    out->slam.addOdometry(run.odometry[k]);
    const PsmSlamScanResult r = out->slam.addScan(run.scans[k]);
    out->anchors.push_back(r.anchor);
    out->online.push_back(r.pose);
  }
  out->slam.optimize();
  return out;
}

const testing::SyntheticRun& loopRun() {
  static const testing::SyntheticRun run =
      testing::simulateLoopRun(testing::makeLoopWorld(), testing::SyntheticRunOptions{});
  return run;
}

TEST(AnchoredPoses, ReanchoredByTheFinalGraphTheyAreTheFinalTrajectory) {
  const auto result = runAnchored(loopRun());
  const std::vector<PoseStamped> final_poses = result->slam.trajectory();
  size_t missing = 99;
  const std::vector<PoseStamped> reanchored = reanchor(result->anchors, result->slam.graph(), &missing);
  EXPECT_EQ(missing, 0u);
  ASSERT_EQ(reanchored.size(), final_poses.size());
  double moved = 0.0;
  for (size_t i = 0; i < final_poses.size(); ++i) {
    EXPECT_EQ(reanchored[i].utime, final_poses[i].utime);
    EXPECT_NEAR(reanchored[i].pose.x, final_poses[i].pose.x, 1e-9);
    EXPECT_NEAR(reanchored[i].pose.y, final_poses[i].pose.y, 1e-9);
    EXPECT_NEAR(wrapAngle(reanchored[i].pose.theta - final_poses[i].pose.theta), 0.0, 1e-9);
    moved = std::max(moved, (result->online[i].pose.translation() - final_poses[i].pose.translation()).norm());
  }
  EXPECT_GT(moved, 1e-3) << "the loop closure should have moved some poses after their scan";
  const size_t new_nodes = static_cast<size_t>(
      std::count_if(result->anchors.begin(), result->anchors.end(), [](const AnchoredPose& a) { return a.new_node; }));
  EXPECT_EQ(new_nodes, result->slam.graph().nodes().size());
}

TEST(AnchoredPoses, AMissingNodeIsCountedAndLeavesThePoseRelative) {
  PoseGraph graph;
  graph.addNode({0, 0, Pose2(1.0, 2.0, 0.5)});
  const std::vector<AnchoredPose> anchors{{10, 0, Pose2(1.0, 0.0, 0.0), false}, {20, 7, Pose2(3.0, 4.0, 0.1), false},
                                          {30, -1, Pose2(5.0, 6.0, 0.2), false}};
  size_t missing = 0;
  const auto poses = reanchor(anchors, graph, &missing);
  EXPECT_EQ(missing, 1u);
  EXPECT_NEAR(poses[0].pose.x, 1.0 + std::cos(0.5), 1e-12);
  EXPECT_NEAR(poses[0].pose.y, 2.0 + std::sin(0.5), 1e-12);
  EXPECT_EQ(poses[1].pose.x, 3.0);
  EXPECT_EQ(poses[2].pose.y, 6.0);
}

TEST(GraphScanStore, ScansAndAnchorsPairedLiveInAnyOrderGiveTheOfflineGrid) {
  const testing::SyntheticRun& run = loopRun();
  const auto result = runAnchored(run);
  GraphScanStore offline, live;
  for (size_t k = 0; k < run.scans.size(); ++k) offline.add(run.scans[k], result->anchors[k]);
  // Live: each anchor comes after its scan, or a little before it, as the network delivers them.
  std::mt19937 rng(3);
  for (size_t k = 0; k < run.scans.size(); ++k) {
    if (rng() % 2) {
      live.addScan(run.scans[k]);
      live.addAnchor(result->anchors[k]);
    } else {
      live.addAnchor(result->anchors[k]);
      live.addScan(run.scans[k]);
    }
  }
  EXPECT_EQ(live.size(), result->slam.graph().nodes().size());
  ASSERT_EQ(live.size(), offline.size());
  EXPECT_EQ(live.statistics().unpaired_dropped, 0);
  const GridOptions options;
  const GraphGrid a = buildGraphGrid(offline, result->slam.graph(), options);
  const GraphGrid b = buildGraphGrid(live, result->slam.graph(), options);
  ASSERT_EQ(a.slice.width, b.slice.width);
  ASSERT_EQ(a.slice.height, b.slice.height);
  size_t occupied = 0;
  for (int y = 0; y < a.slice.height; ++y)
    for (int x = 0; x < a.slice.width; ++x) {
      EXPECT_EQ(a.slice.occupied(x, y), b.slice.occupied(x, y));
      occupied += a.slice.occupied(x, y);
    }
  EXPECT_GT(occupied, 200u);
  // The grid's occupied cells lie on the world's walls: the graph placed the scans right.
  const World world = testing::makeLoopWorld();
  const Pose2 start = testing::loopPath(testing::SyntheticRunOptions{}).front();  // the map frame in the world
  size_t near_wall = 0;
  for (int y = 0; y < a.slice.height; ++y)
    for (int x = 0; x < a.slice.width; ++x)
      if (a.slice.occupied(x, y)) near_wall += distanceToWalls(world, start.transform(a.slice.cellCenter(x, y))) < 0.1;
  EXPECT_GT(static_cast<double>(near_wall) / static_cast<double>(occupied), 0.9);
}

TEST(GraphScanStore, AScanWhoseAnchorNeverComesIsDroppedOnceALaterPairForms) {
  GraphScanStore store;
  LaserScan a, b;
  a.utime = 100;
  b.utime = 200;
  a.ranges = b.ranges = {1.0f, 1.0f, 1.0f};
  store.addScan(a);
  store.addScan(b);
  store.addAnchor({200, 0, Pose2(), true});
  EXPECT_EQ(store.size(), 1u);
  EXPECT_EQ(store.statistics().unpaired_dropped, 1);
}

}  // namespace
}  // namespace polarslam
