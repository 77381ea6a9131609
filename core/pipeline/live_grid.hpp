#pragma once
// The occupancy grid a live system keeps, from either SLAM (polarslam-grid's core):
//  - EkfAnchors: every laser scan kept with its scan anchors; each build regenerates every pose
//    in the latest feature map (thesis §3.7.2);
//  - PsmGraph: PSM SLAM's reference scans kept with their anchored poses; each build places them
//    by the latest pose graph.
// Inputs arrive on separate channels in any interleaving. build() snapshots what is held so far
// into a job that can run on another thread while inputs keep arriving; changed() tells whether
// anything arrived since the last snapshot. The grid code is the offline pipelines', so the same
// inputs give the same map live and offline.
#include <cstdint>
#include <functional>
#include <vector>

#include "grid/anchored_scan_store.hpp"
#include "grid/graph_scan_store.hpp"
#include "grid/grid_outputs.hpp"
#include "pipeline/psm_slam_estimator.hpp"

namespace polarslam {

enum class GridSource { EkfAnchors, PsmGraph };

/// One rebuilt grid, whichever SLAM it came from.
struct BuiltGrid {
  OccupancyGrid grid;
  GridSlice slice;
  GridPicture picture;
  int scans = 0;
  std::vector<int64_t> utimes;               ///< EkfAnchors: scan utimes of `regenerated`
  std::vector<RegeneratedPose> regenerated;  ///< EkfAnchors only
  RegenerationSummary summary;               ///< EkfAnchors only
  double regenerate_seconds = 0.0, build_seconds = 0.0;
};

struct LiveGridOptions {
  GridSource source = GridSource::EkfAnchors;
  GridOutputOptions ekf;      ///< grid and regeneration options (EkfAnchors)
  ScanStoreOptions store;     ///< scan store bounds (EkfAnchors)
  PsmSlamMapOptions psm_map;  ///< grid options and which scans (PsmGraph), as in config/psm-slam.yaml
  /// PsmGraph: a saved map PSM SLAM continues (--load-map M --mode continue): its reference scans
  /// are in the grid from the start, placed by its graph until PSM_SLAM_GRAPH brings the live one.
  std::string load_map;
};

/// Counts for status messages.
struct LiveGridCounts {
  int64_t scans_stored = 0, scans_received = 0, anchors_received = 0, unpaired_dropped = 0, store_bytes = 0;
};

class LiveGrid {
 public:
  explicit LiveGrid(LiveGridOptions options);

  void addScan(LaserScan scan);
  void addScanAnchors(ScanAnchors anchors);   ///< EkfAnchors
  void setFeatureMap(FeatureMap map);         ///< EkfAnchors
  void addAnchoredPose(const AnchoredPose& pose);  ///< PsmGraph
  void setPoseGraph(PoseGraph graph);         ///< PsmGraph

  size_t storedScans() const;
  /// Something arrived since the last build() (and a grid can be built).
  bool changed() const { return storedScans() > 0 && version() != snapshot_version_; }
  /// A job building the grid of everything held now; marks it as built.
  std::function<BuiltGrid()> build();
  LiveGridCounts counts() const;
  GridSource source() const { return options_.source; }

 private:
  uint64_t version() const;

  LiveGridOptions options_;
  AnchoredScanStore anchored_;
  FeatureMap map_;
  GraphScanStore graph_scans_;
  PoseGraph graph_;
  uint64_t maps_and_graphs_ = 0;
  uint64_t snapshot_version_ = 0;
};

}  // namespace polarslam
