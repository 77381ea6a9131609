#include "grid/occupancy_grid.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace polarslam {
namespace {

std::unique_ptr<octomap::OcTree> makeTree(const GridOptions& o) {
  if (!(o.resolution > 0.0)) throw std::invalid_argument("grid resolution must be positive");
  auto tree = std::make_unique<octomap::OcTree>(o.resolution);
  tree->setProbHit(o.prob_hit);
  tree->setProbMiss(o.prob_miss);
  tree->setClampingThresMin(o.clamp_min);
  tree->setClampingThresMax(o.clamp_max);
  tree->setOccupancyThres(0.5);
  return tree;
}

struct CellBounds {
  int x0 = std::numeric_limits<int>::max(), y0 = x0;
  int x1 = std::numeric_limits<int>::min(), y1 = x1;
  bool valid() const { return x0 <= x1 && y0 <= y1; }
};

}  // namespace

OccupancyGrid::OccupancyGrid(const GridOptions& options) : options_(options), tree_(makeTree(options)) {}

OccupancyGrid::OccupancyGrid(const OccupancyGrid& other)
    : options_(other.options_),
      tree_(std::make_unique<octomap::OcTree>(*other.tree_)),
      scans_inserted_(other.scans_inserted_),
      dirty_(other.dirty_) {}

OccupancyGrid& OccupancyGrid::operator=(const OccupancyGrid& other) {
  if (this != &other) *this = OccupancyGrid(other);
  return *this;
}

void OccupancyGrid::insertScan(const LaserScan& scan, const Pose2& robot_pose) {
  const Pose2 sensor = robot_pose * scan.laser_pose;
  const double z = layerZ();
  octomap::Pointcloud cloud;
  cloud.reserve(scan.size());
  for (size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const Vec2 p = sensor.transform(scan.point(i));
    cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(z));
  }
  const double max_range = options_.max_range > 0.0 ? options_.max_range : scan.range_max;
  const octomap::point3d origin(static_cast<float>(sensor.x), static_cast<float>(sensor.y), static_cast<float>(z));
  // Lazy: inner nodes are updated once in finishUpdates(), not after every scan.
  tree_->insertPointCloud(cloud, origin, max_range, /*lazy_eval=*/true);
  dirty_ = true;
  ++scans_inserted_;
}

void OccupancyGrid::finishUpdates() {
  if (!dirty_) return;
  tree_->updateInnerOccupancy();
  tree_->prune();
  dirty_ = false;
}

GridSlice OccupancyGrid::slice() const {
  return sliceOf(*tree_, layerZ(), options_.occupied_threshold, options_.free_threshold);
}

GridSlice sliceOf(const octomap::OcTree& tree, double z, double occupied_threshold, double free_threshold) {
  GridSlice out;
  const double res = tree.getResolution();
  out.resolution = res;
  out.occupied_threshold = occupied_threshold;
  out.free_threshold = free_threshold;
  auto cellIndex = [res](double coordinate) { return static_cast<int>(std::floor(coordinate / res + 1e-6)); };
  // Leaves may be pruned blocks several cells wide: each covers [centre ± size/2] in x and y.
  auto forEachLeafInLayer = [&](auto&& visit) {
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      const double half = 0.5 * it.getSize();
      if (std::abs(it.getZ() - z) >= half) continue;
      visit(cellIndex(it.getX() - half), cellIndex(it.getY() - half),
            std::max(1, static_cast<int>(std::lround(it.getSize() / res))), it->getOccupancy());
    }
  };
  CellBounds b;
  forEachLeafInLayer([&](int x, int y, int n, double) {
    b.x0 = std::min(b.x0, x); b.y0 = std::min(b.y0, y);
    b.x1 = std::max(b.x1, x + n - 1); b.y1 = std::max(b.y1, y + n - 1);
  });
  if (!b.valid()) return out;
  out.origin = Vec2(b.x0 * res, b.y0 * res);
  out.width = b.x1 - b.x0 + 1;
  out.height = b.y1 - b.y0 + 1;
  out.probability.assign(static_cast<size_t>(out.width) * out.height, std::numeric_limits<float>::quiet_NaN());
  forEachLeafInLayer([&](int x, int y, int n, double p) {
    for (int iy = y; iy < y + n; ++iy)
      for (int ix = x; ix < x + n; ++ix) out.probability[out.index(ix - b.x0, iy - b.y0)] = static_cast<float>(p);
  });
  return out;
}

OccupancyGrid buildGrid(const std::vector<const LaserScan*>& scans, const std::vector<Pose2>& poses,
                        const GridOptions& options) {
  if (scans.size() != poses.size()) throw std::invalid_argument("buildGrid: one pose per scan needed");
  OccupancyGrid grid(options);
  for (size_t k = 0; k < scans.size(); ++k) grid.insertScan(*scans[k], poses[k]);
  grid.finishUpdates();
  return grid;
}

OccupancyGrid buildGrid(const std::vector<LaserScan>& scans, const std::vector<Pose2>& poses,
                        const GridOptions& options) {
  std::vector<const LaserScan*> pointers;
  pointers.reserve(scans.size());
  for (const LaserScan& s : scans) pointers.push_back(&s);
  return buildGrid(pointers, poses, options);
}

}  // namespace polarslam
