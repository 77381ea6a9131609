#pragma once
// Laser scans anchored to the nodes of a pose graph (PSM SLAM's reference scans): each scan is
// stored with its pose relative to a node, so the whole set can be re-placed whenever the graph
// changes — thesis §3.7.2's regeneration idea applied to a pose graph. By default only the
// reference scans themselves are kept (they cover the map by construction); `all_scans` keeps
// every scan that has an anchor.
//
// Live (polarslam-grid): LASER and PSM_SLAM_ANCHORS arrive separately and are paired by utime;
// offline (`polarslam run --pipeline psm-slam`) scans are added already paired. Both build the
// grid with the same code, so the same graph gives the same map.
#include <cstdint>
#include <vector>

#include "grid/grid_files.hpp"
#include "grid/occupancy_grid.hpp"
#include "grid/scan_pairing.hpp"
#include "slam/pose_graph.hpp"

namespace polarslam {

struct GraphScanStoreStatistics {
  int64_t scans_received = 0, anchors_received = 0, kept = 0, unpaired_dropped = 0;
};

class GraphScanStore;

/// A grid of the stored scans placed by one pose graph.
struct GraphGrid {
  OccupancyGrid grid;
  GridSlice slice;
  std::vector<Pose2> poses;  ///< one per stored scan
  size_t missing_nodes = 0;  ///< scans whose node the graph lacked (placed at their relative pose)
  double build_seconds = 0.0;
};

GraphGrid buildGraphGrid(const GraphScanStore& store, const PoseGraph& graph, const GridOptions& options);
/// map.png content: the scan poses, the graph's loop-closure edges, and `trajectory` if given.
GridPicture graphGridPicture(const GraphGrid& grid, const PoseGraph& graph,
                             const std::vector<PoseStamped>& trajectory = {});

class GraphScanStore {
 public:
  explicit GraphScanStore(bool all_scans = false) : all_scans_(all_scans) {}

  void addScan(LaserScan scan);
  void addAnchor(const AnchoredPose& anchor);
  /// An already paired scan.
  void add(LaserScan scan, const AnchoredPose& anchor);
  /// A reference scan of a continued map (before any other): kept whatever its time, which may
  /// well be that of this run's scans when the same log is replayed.
  void addStored(LaserScan scan, const AnchoredPose& anchor);

  size_t size() const { return scans_.size(); }
  /// Incremented whenever the kept set changes.
  uint64_t version() const { return version_; }
  const GraphScanStoreStatistics& statistics() const { return stats_; }
  const std::vector<LaserScan>& scans() const { return scans_; }
  const std::vector<AnchoredPose>& anchors() const { return anchors_; }
  /// Map-frame pose of every kept scan in `graph`; `missing` counts scans whose node it lacks.
  std::vector<Pose2> poses(const PoseGraph& graph, size_t* missing = nullptr) const;

 private:
  void keep(LaserScan scan, const AnchoredPose& anchor);

  bool all_scans_;
  ScanPairing<AnchoredPose> pending_;
  std::vector<LaserScan> scans_;
  std::vector<AnchoredPose> anchors_;
  size_t stored_ = 0;  ///< scans of a continued map, at the front
  GraphScanStoreStatistics stats_;
  uint64_t version_ = 0;
};

}  // namespace polarslam
