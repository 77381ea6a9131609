#include "grid/graph_scan_store.hpp"

#include <chrono>
#include <stdexcept>

namespace polarslam {

void GraphScanStore::addScan(LaserScan scan) {
  ++stats_.scans_received;
  if (auto pair = pending_.addScan(std::move(scan))) keep(std::move(pair->first), pair->second);
  stats_.unpaired_dropped = pending_.unpairedDropped();
}

void GraphScanStore::addAnchor(const AnchoredPose& anchor) {
  ++stats_.anchors_received;
  if (auto pair = pending_.addTag(anchor)) keep(std::move(pair->first), pair->second);
  stats_.unpaired_dropped = pending_.unpairedDropped();
}

void GraphScanStore::add(LaserScan scan, const AnchoredPose& anchor) {
  ++stats_.scans_received;
  ++stats_.anchors_received;
  keep(std::move(scan), anchor);
}

void GraphScanStore::addStored(LaserScan scan, const AnchoredPose& anchor) {
  if (anchors_.size() > stored_) throw std::logic_error("GraphScanStore: a continued map's scans come first");
  ++stored_;
  scans_.push_back(std::move(scan));
  anchors_.push_back(anchor);
  ++version_;
}

void GraphScanStore::keep(LaserScan scan, const AnchoredPose& anchor) {
  if (!(all_scans_ || anchor.new_node)) return;
  if (anchors_.size() > stored_ && anchor.utime <= anchors_.back().utime) return;  // repeated or out of order
  scan.ranges.shrink_to_fit();
  scans_.push_back(std::move(scan));
  anchors_.push_back(anchor);
  ++stats_.kept;
  ++version_;
}

std::vector<Pose2> GraphScanStore::poses(const PoseGraph& graph, size_t* missing) const {
  std::vector<Pose2> out;
  out.reserve(anchors_.size());
  for (const PoseStamped& p : reanchor(anchors_, graph, missing)) out.push_back(p.pose);
  return out;
}

GraphGrid buildGraphGrid(const GraphScanStore& store, const PoseGraph& graph, const GridOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  GraphGrid out{OccupancyGrid(options), {}, {}, 0, 0.0};
  out.poses = store.poses(graph, &out.missing_nodes);
  out.grid = buildGrid(store.scans(), out.poses, options);
  out.slice = out.grid.slice();
  out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

GridPicture graphGridPicture(const GraphGrid& grid, const PoseGraph& graph, const std::vector<PoseStamped>& trajectory) {
  GridPicture picture;
  picture.title = "occupancy grid of the reference scans, placed by the pose graph";
  if (!trajectory.empty()) {
    PlotSeries path{"trajectory", {}, seriesColor(0), 1.2, 0};
    for (const PoseStamped& p : trajectory) path.points.push_back(p.pose.translation());
    picture.paths.push_back(path);
  }
  PlotSeries scans{"reference scans", {}, seriesColor(1), 0, 2.0};
  for (const Pose2& p : grid.poses) scans.points.push_back(p.translation());
  picture.paths.push_back(scans);
  for (const PoseGraphEdge& e : graph.edges()) {
    if (e.kind != PoseGraphEdgeKind::Loop || !e.active) continue;
    const long from = graph.indexOf(e.from), to = graph.indexOf(e.to);
    if (from < 0 || to < 0) continue;
    picture.segments.push_back({graph.nodes()[static_cast<size_t>(from)].pose.translation(),
                                graph.nodes()[static_cast<size_t>(to)].pose.translation(), Rgb{220, 60, 60}, 1.0});
  }
  return picture;
}

}  // namespace polarslam
