#pragma once
// Conversions between LCM messages and core structs. Conversions from LCM validate array
// sizes against their counts and return an error string (empty = ok) instead of trusting them.
#include <cstdint>
#include <string>

#include "geometry/features.hpp"
#include "grid/grid_slice.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"
#include "slam/feature_map.hpp"
#include "sonar/sonar_targets.hpp"
#include "polarslam/features_t.hpp"
#include "polarslam/grid_map_t.hpp"
#include "polarslam/laser_scan_t.hpp"
#include "polarslam/odometry_t.hpp"
#include "polarslam/pose_t.hpp"
#include "polarslam/scan_anchors_t.hpp"
#include "polarslam/slam_map_t.hpp"
#include "polarslam/sonar_targets_t.hpp"

namespace polarslam {

polarslam::laser_scan_t toLcm(const LaserScan& scan);
std::string fromLcm(const polarslam::laser_scan_t& msg, LaserScan& out);

polarslam::odometry_t toLcm(const OdometryReading& odo);
std::string fromLcm(const polarslam::odometry_t& msg, OdometryReading& out);

polarslam::sonar_targets_t toLcm(const SonarScan& scan);
std::string fromLcm(const polarslam::sonar_targets_t& msg, SonarScan& out);

polarslam::pose_t toLcm(const PoseStamped& pose, const std::string& frame, int64_t seq = 0);
std::string fromLcm(const polarslam::pose_t& msg, PoseStamped& out);

polarslam::features_t toLcm(const FeatureSet& features);
std::string fromLcm(const polarslam::features_t& msg, FeatureSet& out);

/// SLAM_MAP. fromLcm checks counts, kinds and finiteness.
polarslam::slam_map_t toLcm(const FeatureMap& map, int64_t seq = 0);
std::string fromLcm(const polarslam::slam_map_t& msg, FeatureMap& out);

/// SCAN_ANCHORS. fromLcm checks counts, kinds and finiteness.
polarslam::scan_anchors_t toLcm(const ScanAnchors& anchors, int64_t seq = 0);
std::string fromLcm(const polarslam::scan_anchors_t& msg, ScanAnchors& out);

/// Most cells a grid_map_t may hold (64 Mi: e.g. 400 m × 400 m at 5 cm). fromLcm rejects bigger
/// grids before allocating: a few kB of zlib data could otherwise inflate to gigabytes.
inline constexpr int64_t kMaxGridMapCells = int64_t{1} << 26;

/// grid_map_t of a slice in the map frame: unknown cells -1, the others their occupancy
/// probability in whole percent; `compress` deflates the cells with zlib. `source` and `scans`
/// tell a viewer what the grid was built from ("ekf-anchors" / "psm-graph", scans ray-cast).
polarslam::grid_map_t toLcmGridMap(const GridSlice& slice, int64_t utime, int64_t seq, const std::string& source,
                                   int scans, bool compress);
/// Checks sizes against width × height (and kMaxGridMapCells), resolution, origin, encoding, the
/// zlib stream and every cell value. Unknown cells become NaN, the others percent / 100; the
/// slice keeps its default thresholds.
std::string fromLcm(const polarslam::grid_map_t& msg, GridSlice& out);

template <int N>
void copyMatrix(const Eigen::Matrix<double, N, N>& m, double* out) {
  for (int r = 0; r < N; ++r)
    for (int c = 0; c < N; ++c) out[r * N + c] = m(r, c);
}
template <int N>
Eigen::Matrix<double, N, N> readMatrix(const double* in) {
  Eigen::Matrix<double, N, N> m;
  for (int r = 0; r < N; ++r)
    for (int c = 0; c < N; ++c) m(r, c) = in[r * N + c];
  return m;
}

}  // namespace polarslam
