#pragma once
// Every laser scan kept with its ScanAnchors (the robot pose relative to the neighbouring map
// features, thesis §3.7.2). Scans and anchors arrive separately (LASER, then SCAN_ANCHORS once
// the EKF has processed the scan) and are paired by the scan's utime.
//
// Memory bound: at most `capacity` scans are kept. A scan is only admitted when the robot moved
// `min_translation` or turned `min_rotation` since the last kept scan; when the store is full,
// every second scan is dropped and both spacings double, so the store keeps an even coverage
// of the whole run. Ranges stay float (4 B per beam); with the defaults (5000 scans, 181 beams,
// ~10 anchors of 112 B) the store holds at most ~9 MB. Unpaired scans and anchors wait in
// queues of at most `max_pending` entries each (oldest dropped); once a pair at time t forms,
// unpaired entries older than t are dropped (the EKF anchors scans in time order).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "grid/scan_pairing.hpp"
#include "laser/laser_scan.hpp"
#include "slam/feature_map.hpp"

namespace polarslam {

struct AnchoredScan {
  LaserScan scan;
  ScanAnchors anchors;
};

struct ScanStoreOptions {
  size_t capacity = 5000;
  double min_translation = 0.05;         ///< m
  double min_rotation = deg2rad(2.0);    ///< rad
  size_t max_pending = 200;
};

struct ScanStoreStatistics {
  int64_t scans_received = 0, anchors_received = 0;
  int64_t paired = 0;          ///< scan + anchors matched
  int64_t skipped_close = 0;   ///< paired but too close to the previous kept scan
  int64_t thinned = 0;         ///< dropped when the store was full
  int64_t unpaired_dropped = 0;  ///< scans or anchors that never found their partner
};

class AnchoredScanStore {
 public:
  explicit AnchoredScanStore(ScanStoreOptions options = {});

  void addScan(LaserScan scan);
  void addAnchors(ScanAnchors anchors);
  /// Adds an already paired scan (offline pipelines that hold both).
  void add(LaserScan scan, ScanAnchors anchors);

  /// Kept scans in time order.
  const std::vector<AnchoredScan>& scans() const { return scans_; }
  size_t size() const { return scans_.size(); }
  const ScanStoreStatistics& statistics() const { return stats_; }
  /// Current admission spacing (grows when the store is thinned).
  double minTranslation() const { return min_translation_; }
  /// Bytes held by kept scans and pending queues (payload, not allocator overhead).
  size_t memoryBytes() const;
  /// Incremented whenever the kept set changes.
  uint64_t version() const { return version_; }

 private:
  void admit(LaserScan scan, ScanAnchors anchors);
  bool farEnoughFromLast(const Pose2& pose) const;
  void thin();

  ScanStoreOptions options_;
  double min_translation_, min_rotation_;
  std::vector<AnchoredScan> scans_;
  ScanPairing<ScanAnchors> pending_;
  ScanStoreStatistics stats_;
  uint64_t version_ = 0;
};

}  // namespace polarslam
