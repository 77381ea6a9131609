#include <gtest/gtest.h>

#include "grid/anchored_scan_store.hpp"

namespace polarslam {
namespace {

LaserScan scanAt(int64_t utime, size_t beams = 181) {
  LaserScan s;
  s.utime = utime;
  s.range_max = 8.0;
  s.angle_increment = 0.01;
  s.ranges.assign(beams, 2.0f);
  return s;
}

ScanAnchors anchorsAt(int64_t utime, const Pose2& pose, int count = 3) {
  ScanAnchors a;
  a.utime = utime;
  a.pose.pose = pose;
  for (int i = 0; i < count; ++i) a.anchors.push_back({i, MapFeatureKind::Line, Vec3(0.1 * i, 1.0, 0), Mat3::Identity()});
  return a;
}

TEST(AnchoredScanStore, PairsScansAndAnchorsInEitherOrder) {
  AnchoredScanStore store;
  store.addScan(scanAt(100));
  store.addAnchors(anchorsAt(100, {0, 0, 0}));
  store.addAnchors(anchorsAt(200, {1, 0, 0}));
  store.addScan(scanAt(200));
  store.addScan(scanAt(300));  // its anchors never come
  ASSERT_EQ(store.size(), 2u);
  EXPECT_EQ(store.scans()[0].scan.utime, 100);
  EXPECT_EQ(store.scans()[1].anchors.pose.pose.x, 1.0);
  EXPECT_EQ(store.statistics().paired, 2);
}

TEST(AnchoredScanStore, SkipsScansTakenWithoutMoving) {
  AnchoredScanStore store({.capacity = 100, .min_translation = 0.1, .min_rotation = 0.1, .max_pending = 10});
  for (int k = 0; k < 10; ++k) store.add(scanAt(k + 1), anchorsAt(k + 1, {0.03 * k, 0, 0}));
  EXPECT_EQ(store.size(), 3u);  // x = 0, 0.12, 0.24
  EXPECT_EQ(store.statistics().skipped_close, 7);
  store.add(scanAt(20), anchorsAt(20, {0.24, 0, 0.2}));  // turning counts as moving
  EXPECT_EQ(store.size(), 4u);
}

TEST(AnchoredScanStore, MemoryStaysBoundedOverALongRun) {
  ScanStoreOptions o{.capacity = 64, .min_translation = 0.05, .min_rotation = 0.05, .max_pending = 8};
  AnchoredScanStore store(o);
  size_t peak_bytes = 0;
  for (int k = 0; k < 5000; ++k) {
    if (k % 7 == 0) store.addScan(scanAt(10 * k + 5));  // scans the EKF never anchors
    if (k % 11 == 0) store.addAnchors(anchorsAt(10 * k + 7, {0, 0, 0}));  // anchors of scans lost on the way
    store.addScan(scanAt(10 * k + 10));
    store.addAnchors(anchorsAt(10 * k + 10, {0.1 * k, 0, 0}));
    peak_bytes = std::max(peak_bytes, store.memoryBytes());
    ASSERT_LE(store.size(), o.capacity);
  }
  // Bound from the header: capacity scans + max_pending unpaired ones.
  const size_t per_scan = sizeof(LaserScan) + 181 * sizeof(float) + sizeof(ScanAnchors) + 3 * sizeof(AnchorObservation);
  EXPECT_LE(peak_bytes, (o.capacity + o.max_pending) * per_scan);
  EXPECT_GT(store.statistics().thinned, 0);
  EXPECT_GT(store.statistics().unpaired_dropped, 0);
  // Thinning keeps the whole run covered evenly: first and last parts both present, in order.
  const auto& scans = store.scans();
  EXPECT_LE(scans.front().anchors.pose.pose.x, store.minTranslation());
  EXPECT_GE(scans.back().anchors.pose.pose.x, 0.1 * 4999 - store.minTranslation());
  for (size_t i = 1; i < scans.size(); ++i) EXPECT_LT(scans[i - 1].scan.utime, scans[i].scan.utime);
  EXPECT_GT(store.minTranslation(), o.min_translation);
}

TEST(AnchoredScanStore, OutOfOrderScansAreNotAdmitted) {
  AnchoredScanStore store;
  store.add(scanAt(200), anchorsAt(200, {0, 0, 0}));
  store.add(scanAt(100), anchorsAt(100, {5, 0, 0}));
  EXPECT_EQ(store.size(), 1u);
}

}  // namespace
}  // namespace polarslam
