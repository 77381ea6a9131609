#pragma once
// The whole §3.7.2 chain for anyone holding anchored scans and a feature map: regenerate every
// stored pose in the current map, ray-cast the scans at those poses, write the grid files.
// The EKF estimator calls writeGridOutputs() from finish(); polarslam-grid calls
// regenerateGrid() + writeGridFiles() live.
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "grid/anchored_scan_store.hpp"
#include "grid/grid_files.hpp"
#include "grid/occupancy_grid.hpp"
#include "grid/pose_regeneration.hpp"

namespace polarslam {

struct GridOutputOptions {
  GridOptions grid;
  RegenerationOptions regeneration;
};

struct RegeneratedGrid {
  OccupancyGrid grid;
  GridSlice slice;
  std::vector<RegeneratedPose> poses;  ///< one per stored scan, in store order
  std::vector<int64_t> utimes;         ///< scan utimes, same order
  RegenerationSummary summary;
  double regenerate_seconds = 0.0, build_seconds = 0.0;
};

/// Regenerates the pose of every scan in `map` and builds the grid from those poses.
RegeneratedGrid regenerateGrid(const std::vector<AnchoredScan>& scans, const FeatureMap& map,
                               const GridOutputOptions& options = {});

/// map.png content: the regenerated trajectory, chained poses marked, and the map's features.
GridPicture gridPictureOf(const RegeneratedGrid& result, const FeatureMap& map);

/// Figures of a regenerated grid for report.json.
nlohmann::json gridReportJson(const RegeneratedGrid& result, const GridFiles& files);

/// Regenerates, builds and writes map.{ot,bt,pgm,yaml,png} into out_dir; adds report["grid"].
RegeneratedGrid writeGridOutputs(const std::string& out_dir, const AnchoredScanStore& store, const FeatureMap& map,
                                 nlohmann::json& report, const GridOutputOptions& options = {});
/// Same for scans and anchors held in separate lists (paired by utime; unpaired ones ignored).
RegeneratedGrid writeGridOutputs(const std::string& out_dir, const std::vector<LaserScan>& scans,
                                 const std::vector<ScanAnchors>& anchors, const FeatureMap& map,
                                 nlohmann::json& report, const GridOutputOptions& options = {});

}  // namespace polarslam
