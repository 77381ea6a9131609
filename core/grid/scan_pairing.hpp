#pragma once
// Laser scans and what a SLAM process says about them (scan anchors, anchored poses) arrive on
// separate channels and are paired by the scan's utime. Unpaired entries wait in queues of at
// most `max_pending` each (oldest dropped); once a pair at time t forms, unpaired entries older
// than t are dropped, because the SLAM processes describe scans in time order.
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <map>
#include <optional>
#include <utility>

#include "laser/laser_scan.hpp"

namespace polarslam {

template <typename Tag>  // Tag has `int64_t utime`, the utime of the scan it describes
class ScanPairing {
 public:
  using Pair = std::pair<LaserScan, Tag>;

  explicit ScanPairing(size_t max_pending = 200) : max_pending_(max_pending) {}

  std::optional<Pair> addScan(LaserScan scan) {
    if (auto tag = take(tags_, scan.utime)) return pairUp(std::move(scan), std::move(*tag));
    const int64_t utime = scan.utime;
    scans_[utime] = std::move(scan);
    bound(scans_);
    return std::nullopt;
  }

  std::optional<Pair> addTag(Tag tag) {
    if (auto scan = take(scans_, tag.utime)) return pairUp(std::move(*scan), std::move(tag));
    const int64_t utime = tag.utime;
    tags_[utime] = std::move(tag);
    bound(tags_);
    return std::nullopt;
  }

  int64_t unpairedDropped() const { return dropped_; }
  const std::map<int64_t, LaserScan>& scans() const { return scans_; }
  const std::map<int64_t, Tag>& tags() const { return tags_; }

 private:
  template <typename T>
  static std::optional<T> take(std::map<int64_t, T>& queue, int64_t utime) {
    const auto it = queue.find(utime);
    if (it == queue.end()) return std::nullopt;
    T value = std::move(it->second);
    queue.erase(it);
    return value;
  }

  Pair pairUp(LaserScan scan, Tag tag) {
    dropBefore(scans_, scan.utime);
    dropBefore(tags_, scan.utime);
    return {std::move(scan), std::move(tag)};
  }

  template <typename T>
  void dropBefore(std::map<int64_t, T>& queue, int64_t utime) {
    const auto end = queue.lower_bound(utime);
    dropped_ += std::distance(queue.begin(), end);
    queue.erase(queue.begin(), end);
  }

  template <typename T>
  void bound(std::map<int64_t, T>& queue) {
    while (queue.size() > max_pending_) {
      queue.erase(queue.begin());
      ++dropped_;
    }
  }

  size_t max_pending_;
  std::map<int64_t, LaserScan> scans_;
  std::map<int64_t, Tag> tags_;
  int64_t dropped_ = 0;
};

}  // namespace polarslam
