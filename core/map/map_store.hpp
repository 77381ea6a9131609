#pragma once
// A saved PSM SLAM map (issue 15): a versioned folder that outlives the process that built it.
//
//   M/manifest.json   format name and version, the laser geometry, and per file its size and
//                     zlib CRC32
//   M/graph.txt       the pose graph: nodes, edges with covariance, kind and outlier flag
//   M/scans.txt       the reference scans (ranges and beam geometry) with their graph anchors
//   M/parameters.yaml the effective psm-slam configuration the map was built with
//   M/uncertainty.json each node's marginal covariance when the map was saved, where known
//   M/resume.json     only in a crash-recovery snapshot: where the process was (docs/maps.md)
//   M/map.*           the occupancy grid (core/grid writers), when one is given
//
// saveMap writes into a sibling temporary folder, fsyncs every file and the folder, then swaps
// it in with one rename: an existing map is replaced only by a complete one, and a crash leaves
// either the old map or the new one. loadMap checks the manifest, every checksum and every
// record, and refuses a bad map with a MapFormatError naming the file.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"
#include "slam/map_localizer.hpp"
#include "slam/pose_graph.hpp"

namespace polarslam {

class OccupancyGrid;

inline constexpr int kMapFormatVersion = 1;
inline constexpr const char* kMapFormatName = "polarslam-map";

/// The beam layout and mount of a laser; a map only serves a laser with the same geometry.
struct LaserGeometry {
  double angle_min = 0.0;        ///< rad
  double angle_increment = 0.0;  ///< rad
  size_t beams = 0;
  double range_max = 0.0;        ///< m
  Pose2 mount;                   ///< laser pose in the robot base frame
};
LaserGeometry laserGeometryOf(const LaserScan& scan);
/// Empty when `actual` matches `expected` (angles within 1e-6 rad, ranges and mount within
/// 1e-6 m / rad), otherwise what differs.
std::string laserGeometryMismatch(const LaserGeometry& expected, const LaserGeometry& actual);

/// A reference scan (the laser frame's readings) and where it sits in the graph.
struct MapReferenceScan {
  LaserScan scan;
  AnchoredPose anchor;  ///< robot pose of the scan relative to its graph node
};

struct StoredMap {
  LaserGeometry laser;
  PoseGraph graph;
  std::vector<MapReferenceScan> scans;
  std::string parameters_yaml;  ///< the effective configuration (ParameterTable::yaml())
  /// A crash-recovery snapshot's process state (resume.json; empty in a map saved for users).
  std::string resume_json;
  /// A snapshot's filter state (resume-filter.bin): raw doubles of the machine that wrote it,
  /// whose layout resume.json describes.
  std::string resume_filter;
  /// The filter's marginal covariance of each node's pose in the map frame, where known
  /// (uncertainty.json): how far the map itself may be off, for continuing it.
  std::vector<std::pair<int64_t, Mat3>> node_covariances;
};

/// A map that cannot be saved or loaded; what() names the file at fault.
class MapFormatError : public std::runtime_error {
 public:
  MapFormatError(const std::string& file, const std::string& message);
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

/// Writes `map` (and `grid`'s files, if given) to the folder `dir` atomically, replacing an
/// existing map there only once the new one is complete. Refuses a map whose scans do not match
/// its laser geometry or whose anchors name nodes the graph lacks. Throws MapFormatError.
void saveMap(const std::string& dir, const StoredMap& map, const OccupancyGrid* grid = nullptr);

/// Reads and validates a map folder. With `expected_laser`, also refuses a map made with
/// another laser geometry. Throws MapFormatError naming the offending file.
StoredMap loadMap(const std::string& dir, const std::optional<LaserGeometry>& expected_laser = std::nullopt);

/// The map of a SLAM run: the scans whose anchor made them a new graph node (the reference
/// scans) with `graph`. Throws MapFormatError when there is none (nothing to localise against)
/// or when the scans disagree on the laser geometry.
StoredMap storedMapOf(const PoseGraph& graph, const std::vector<LaserScan>& scans,
                      const std::vector<AnchoredPose>& anchors, std::string parameters_yaml);

/// The reference scans of a map with their robot poses in the map frame (node pose ⊕ anchor), for
/// localisation (slam/map_localizer.hpp).
std::vector<MapReference> mapReferences(const StoredMap& map);

/// zlib's CRC32 of `bytes` (the manifest's per-file checksum).
uint32_t mapCrc32(const std::string& bytes);

}  // namespace polarslam
