// LiveGrid, polarslam-grid's core: inputs in any interleaving, builds that snapshot what has
// arrived, and the same grid as the offline pipelines for the same inputs.
#include <gtest/gtest.h>

#include "pipeline/live_grid.hpp"
#include "unit/grid/grid_fixtures.hpp"

namespace polarslam {
namespace {

TEST(LiveGrid, PoseGraphSourceRebuildsWhenTheGraphChangesAndMatchesTheOfflineStore) {
  const World world = test::twoRoomWorld();
  const std::vector<Pose2> poses = test::twoRoomPoses();
  LiveGridOptions options;
  options.source = GridSource::PsmGraph;
  LiveGrid live(options);
  GraphScanStore offline;
  PoseGraph graph;
  for (size_t k = 0; k < poses.size(); ++k) {
    const int64_t utime = 1000 * static_cast<int64_t>(k + 1);
    const AnchoredPose anchor{utime, static_cast<int64_t>(k), Pose2(), true};
    LaserScan scan = test::castScan(world, poses[k], 361, 2 * std::numbers::pi, utime);
    offline.add(scan, anchor);
    live.addAnchoredPose(anchor);  // before its scan: the network may deliver it first
    live.addScan(std::move(scan));
    graph.addNode({static_cast<int64_t>(k), utime, poses[k]});
  }
  EXPECT_EQ(live.storedScans(), poses.size());
  EXPECT_TRUE(live.changed());
  live.setPoseGraph(graph);
  const BuiltGrid built = live.build()();
  EXPECT_FALSE(live.changed());
  EXPECT_EQ(built.scans, static_cast<int>(poses.size()));
  const GraphGrid reference = buildGraphGrid(offline, graph, gridOptions(options.psm_map));
  ASSERT_EQ(built.slice.width, reference.slice.width);
  ASSERT_EQ(built.slice.height, reference.slice.height);
  EXPECT_EQ(built.slice.probability.size(), reference.slice.probability.size());
  for (size_t i = 0; i < built.slice.probability.size(); ++i)
    ASSERT_TRUE(built.slice.probability[i] == reference.slice.probability[i] ||
                (std::isnan(built.slice.probability[i]) && std::isnan(reference.slice.probability[i])));
  live.setPoseGraph(graph);
  EXPECT_TRUE(live.changed()) << "a new graph is a change even with the same nodes";
}

TEST(LiveGrid, AnchorSourceRegeneratesPosesInTheLatestMap) {
  const World world = test::twoRoomWorld();
  const std::vector<Pose2> poses = test::twoRoomPoses();
  LiveGridOptions options;
  options.store.min_translation = 0.0;
  LiveGrid live(options);
  for (size_t k = 0; k < poses.size(); ++k) {
    const int64_t utime = 1000 * static_cast<int64_t>(k + 1);
    live.addScan(test::castScan(world, poses[k], 361, 2 * std::numbers::pi, utime));
    ScanAnchors anchors;
    anchors.utime = utime;
    anchors.pose = {utime, poses[k], Mat3::Identity() * 1e-4};
    live.addScanAnchors(anchors);
  }
  EXPECT_EQ(live.counts().scans_stored, static_cast<int64_t>(poses.size()));
  const BuiltGrid built = live.build()();
  // No map features: every pose falls back to the stored SLAM pose, and the walls still line up.
  EXPECT_EQ(built.summary.stored, static_cast<int>(poses.size()));
  int occupied = 0, near_wall = 0;
  for (int y = 0; y < built.slice.height; ++y)
    for (int x = 0; x < built.slice.width; ++x)
      if (built.slice.occupied(x, y)) {
        ++occupied;
        near_wall += test::distanceToWalls(world, built.slice.cellCenter(x, y)) < 0.08;
      }
  EXPECT_GT(occupied, 300);
  EXPECT_GT(static_cast<double>(near_wall) / occupied, 0.97);
}

}  // namespace
}  // namespace polarslam
