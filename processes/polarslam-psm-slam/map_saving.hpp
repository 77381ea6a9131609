#pragma once
// Live map saving for polarslam-psm-slam (--save-map M): keeps the reference scans as they
// arrive (the same GraphScanStore `polarslam run --pipeline psm-slam` fills) and writes the map
// folder of core/map/map_store.hpp on request (SAVE_MAP) and on exit.
#include <string>

#include "grid/graph_scan_store.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "slam/psm_slam.hpp"

namespace polarslam {

class LiveMapSaver {
 public:
  LiveMapSaver(std::string dir, PsmSlamEstimatorConfig config) : dir_(std::move(dir)), config_(std::move(config)) {}

  bool enabled() const { return !dir_.empty(); }
  const std::string& folder() const { return dir_; }
  void onScan(const LaserScan& scan, const AnchoredPose& anchor) {
    if (enabled()) scans_.add(scan, anchor);
  }
  /// Saves the graph as it is now with its grid. Throws MapFormatError (nothing to save yet, or
  /// the folder cannot be written).
  void save(const PsmSlam& slam) const;

 private:
  std::string dir_;
  PsmSlamEstimatorConfig config_;
  GraphScanStore scans_;
};

}  // namespace polarslam
