#include "grid/anchored_scan_store.hpp"

#include <algorithm>
#include <cmath>

namespace polarslam {

AnchoredScanStore::AnchoredScanStore(ScanStoreOptions options)
    : options_(options),
      min_translation_(options.min_translation),
      min_rotation_(options.min_rotation),
      pending_(options.max_pending) {
  options_.capacity = std::max<size_t>(options_.capacity, 2);
}

void AnchoredScanStore::addScan(LaserScan scan) {
  ++stats_.scans_received;
  if (auto pair = pending_.addScan(std::move(scan))) admit(std::move(pair->first), std::move(pair->second));
  stats_.unpaired_dropped = pending_.unpairedDropped();
}

void AnchoredScanStore::addAnchors(ScanAnchors anchors) {
  ++stats_.anchors_received;
  if (auto pair = pending_.addTag(std::move(anchors))) admit(std::move(pair->first), std::move(pair->second));
  stats_.unpaired_dropped = pending_.unpairedDropped();
}

void AnchoredScanStore::add(LaserScan scan, ScanAnchors anchors) {
  ++stats_.scans_received;
  ++stats_.anchors_received;
  admit(std::move(scan), std::move(anchors));
}

bool AnchoredScanStore::farEnoughFromLast(const Pose2& pose) const {
  if (scans_.empty()) return true;
  const Pose2& last = scans_.back().anchors.pose.pose;
  return (pose.translation() - last.translation()).norm() >= min_translation_ ||
         std::abs(wrapAngle(pose.theta - last.theta)) >= min_rotation_;
}

void AnchoredScanStore::admit(LaserScan scan, ScanAnchors anchors) {
  ++stats_.paired;
  if (!scans_.empty() && scan.utime <= scans_.back().scan.utime) {
    ++stats_.skipped_close;  // out of order or repeated: keep the store in time order
    return;
  }
  if (!farEnoughFromLast(anchors.pose.pose)) {
    ++stats_.skipped_close;
    return;
  }
  scan.ranges.shrink_to_fit();
  scans_.push_back({std::move(scan), std::move(anchors)});
  if (scans_.size() > options_.capacity) thin();
  ++version_;
}

void AnchoredScanStore::thin() {
  // Keep every second scan, always including the newest.
  std::vector<AnchoredScan> kept;
  kept.reserve(scans_.size() / 2 + 1);
  const size_t n = scans_.size();
  for (size_t i = (n - 1) % 2; i < n; i += 2) kept.push_back(std::move(scans_[i]));
  stats_.thinned += static_cast<int64_t>(n - kept.size());
  scans_ = std::move(kept);
  min_translation_ *= 2.0;
  min_rotation_ *= 2.0;
}

size_t AnchoredScanStore::memoryBytes() const {
  auto scanBytes = [](const LaserScan& s) { return sizeof(LaserScan) + s.ranges.capacity() * sizeof(float); };
  auto anchorBytes = [](const ScanAnchors& a) {
    return sizeof(ScanAnchors) + a.anchors.capacity() * sizeof(AnchorObservation);
  };
  size_t bytes = 0;
  for (const auto& s : scans_) bytes += scanBytes(s.scan) + anchorBytes(s.anchors);
  for (const auto& [t, s] : pending_.scans()) bytes += scanBytes(s);
  for (const auto& [t, a] : pending_.tags()) bytes += anchorBytes(a);
  return bytes;
}

}  // namespace polarslam
