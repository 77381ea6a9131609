#include "grid/occupancy_grid.hpp"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>

namespace polarslam {
namespace {

// OctoMap addresses a cell by a 16-bit key per axis, the cell index + 32768 (tree depth 16).
// Points outside that range are dropped as insertPointCloud drops them, which also keeps every
// cell of the raster expressible in toOcTree().
constexpr int kKeyOffset = 32768;
constexpr int kMinMarginCells = 64;
constexpr int kFractionBits = 16;  // fixed point: 1/65536 cell (< 1 µm at 5 cm)
constexpr int64_t kOneCell = int64_t{1} << kFractionBits;
constexpr int64_t kFractionMask = kOneCell - 1;

int cellOf(int64_t fixed) { return static_cast<int>(fixed >> kFractionBits); }  // floor

/// `cells` (coordinate / resolution) in fixed point; false outside OctoMap's key range or NaN.
bool toFixed(double cells, int64_t& fixed) {
  if (!(std::abs(cells) < 2.0 * kKeyOffset)) return false;
  const double scaled = cells * static_cast<double>(kOneCell);  // exact: a power of two
  fixed = static_cast<int64_t>(scaled);
  fixed -= static_cast<double>(fixed) > scaled;  // floor, so the cell is floor(cells) exactly
  const int cell = cellOf(fixed);
  return cell >= -kKeyOffset && cell < kKeyOffset;
}

/// octomap::logodds, rounded to float as OctoMap stores it.
float logOdds(double probability) { return static_cast<float>(std::log(probability / (1.0 - probability))); }

/// octomap::probability.
double probability(float log_odds) { return 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(log_odds))); }

void checkOptions(const GridOptions& o) {
  if (!(o.resolution > 0.0) || !std::isfinite(o.resolution))
    throw std::invalid_argument("grid resolution must be positive");
  auto probability = [](double p) { return p > 0.0 && p < 1.0; };
  if (!probability(o.prob_hit) || !probability(o.prob_miss) || !probability(o.clamp_min) ||
      !probability(o.clamp_max) || o.clamp_min > o.clamp_max)
    throw std::invalid_argument("grid sensor model: probabilities must lie in (0, 1), clamp_min <= clamp_max");
}

std::unique_ptr<octomap::OcTree> makeTree(const GridOptions& o) {
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

void OccupancyGrid::CellBox::add(int x, int y) {
  if (empty()) {
    x0 = x1 = x;
    y0 = y1 = y;
    return;
  }
  x0 = std::min(x0, x);
  y0 = std::min(y0, y);
  x1 = std::max(x1, x);
  y1 = std::max(y1, y);
}

void OccupancyGrid::CellBox::add(const CellBox& b) {
  if (b.empty()) return;
  add(b.x0, b.y0);
  add(b.x1, b.y1);
}

OccupancyGrid::OccupancyGrid(const GridOptions& options)
    : options_(options),
      hit_delta_(logOdds(options.prob_hit)),
      miss_delta_(logOdds(options.prob_miss)),
      clamp_min_(logOdds(options.clamp_min)),
      clamp_max_(logOdds(options.clamp_max)) {
  checkOptions(options);
}

void OccupancyGrid::insertScan(const LaserScan& scan, const Pose2& robot_pose) {
  const ScanPlan plan = planScan(scan, robot_pose);
  growToContain(plan.reach, /*with_margin=*/true);
  ++stamp_;
  // End points first: a cell that is some beam's end point and another beam's free space in the
  // same scan is updated as occupied only (the stamp then stops the free update).
  const CellUpdate hit = updateFor(hit_delta_);
  for (const Beam& beam : beams_) {
    if (!beam.hit) continue;
    const int x = cellOf(beam.end.x), y = cellOf(beam.end.y);
    hit(cells_[indexOf(x, y)]);
    observed_.add(x, y);
  }
  if (plan.rays)
    for (const Beam& beam : beams_) clearRay(plan.sensor, beam.end);
  ++scans_inserted_;
}

void OccupancyGrid::reserve(const std::vector<const LaserScan*>& scans, const std::vector<Pose2>& poses) {
  CellBox reach;
  for (size_t k = 0; k < scans.size() && k < poses.size(); ++k) reach.add(planScan(*scans[k], poses[k]).reach);
  growToContain(reach, /*with_margin=*/false);
}

OccupancyGrid::ScanPlan OccupancyGrid::planScan(const LaserScan& scan, const Pose2& robot_pose) {
  const Pose2 sensor = robot_pose * scan.laser_pose;
  const double cells_per_metre = 1.0 / options_.resolution;
  const Vec2 origin = sensor.translation() * cells_per_metre;
  ScanPlan plan;
  // As in OctoMap, a sensor outside the addressable range casts no rays; its end points still count.
  plan.rays = toFixed(origin.x(), plan.sensor.x) && toFixed(origin.y(), plan.sensor.y);
  const double max_range = options_.max_range > 0.0 ? options_.max_range : scan.range_max;
  const double c = std::cos(sensor.theta), s = std::sin(sensor.theta);
  const std::vector<Vec2>& directions = beamDirections(scan);
  beams_.clear();
  for (size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const double range = scan.ranges[i];
    const bool hit = range <= max_range;
    const Vec2& d = directions[i];
    const Vec2 direction(c * d.x() - s * d.y(), s * d.x() + c * d.y());
    const Vec2 end = origin + ((hit ? range : max_range) * cells_per_metre) * direction;
    Beam beam{{}, hit};
    if (!toFixed(end.x(), beam.end.x) || !toFixed(end.y(), beam.end.y)) continue;
    if (!hit && !plan.rays) continue;  // it could only have cleared cells
    beams_.push_back(beam);
    plan.reach.add(cellOf(beam.end.x), cellOf(beam.end.y));
  }
  if (plan.rays && !beams_.empty()) plan.reach.add(cellOf(plan.sensor.x), cellOf(plan.sensor.y));
  return plan;
}

const std::vector<Vec2>& OccupancyGrid::beamDirections(const LaserScan& scan) {
  // Scans of one laser share their bearings: the cosines and sines are computed once.
  if (directions_.size() != scan.size() || directions_angle_min_ != scan.angle_min ||
      directions_increment_ != scan.angle_increment) {
    directions_.resize(scan.size());
    for (size_t i = 0; i < scan.size(); ++i) directions_[i] = Vec2(std::cos(scan.bearing(i)), std::sin(scan.bearing(i)));
    directions_angle_min_ = scan.angle_min;
    directions_increment_ = scan.angle_increment;
  }
  return directions_;
}

void OccupancyGrid::growToContain(const CellBox& box, bool with_margin) {
  if (box.empty() || bounds_.contains(box)) return;
  CellBox needed = bounds_;
  needed.add(box);
  // A margin on every side that had to grow (half the extent, at least 64 cells) keeps the
  // number of reallocations logarithmic in the map's size.
  CellBox target = needed;
  if (with_margin) {
    const int margin_x = static_cast<int>(std::max<int64_t>(kMinMarginCells, needed.width() / 2));
    const int margin_y = static_cast<int>(std::max<int64_t>(kMinMarginCells, needed.height() / 2));
    if (bounds_.empty() || needed.x0 < bounds_.x0) target.x0 = std::max(needed.x0 - margin_x, -kKeyOffset);
    if (bounds_.empty() || needed.x1 > bounds_.x1) target.x1 = std::min(needed.x1 + margin_x, kKeyOffset - 1);
    if (bounds_.empty() || needed.y0 < bounds_.y0) target.y0 = std::max(needed.y0 - margin_y, -kKeyOffset);
    if (bounds_.empty() || needed.y1 > bounds_.y1) target.y1 = std::min(needed.y1 + margin_y, kKeyOffset - 1);
  }
  const auto cellCount = [](const CellBox& b) { return static_cast<uint64_t>(b.width()) * static_cast<uint64_t>(b.height()); };
  if (cellCount(target) > options_.max_cells) target = needed;
  if (cellCount(target) > options_.max_cells)
    throw std::length_error("occupancy grid: the scans span " + std::to_string(needed.width()) + " x " +
                            std::to_string(needed.height()) + " cells, more than max_cells (" +
                            std::to_string(options_.max_cells) + ")");

  std::vector<Cell> cells(cellCount(target));
  const size_t target_width = static_cast<size_t>(target.width());
  for (int y = observed_.y0; y <= observed_.y1; ++y) {  // nothing outside observed_ was ever updated
    const auto row = cells_.begin() + static_cast<ptrdiff_t>(indexOf(observed_.x0, y));
    const size_t to = static_cast<size_t>(y - target.y0) * target_width + static_cast<size_t>(observed_.x0 - target.x0);
    std::copy(row, row + observed_.width(), cells.begin() + static_cast<ptrdiff_t>(to));
  }
  cells_.swap(cells);
  bounds_ = target;
}

size_t OccupancyGrid::indexOf(int ix, int iy) const {
  return static_cast<size_t>(iy - bounds_.y0) * static_cast<size_t>(bounds_.width()) + static_cast<size_t>(ix - bounds_.x0);
}

void OccupancyGrid::clearRay(const FixedPoint& from, FixedPoint to) {
  // Amanatides & Woo's traversal, as OctoMap's computeRayKeys runs it: every cell the segment
  // crosses, from the sensor's cell to the end cell (excluded), a tie stepping in y. In exact
  // integers: e < 0 exactly when the next x border comes before the next y border.
  // An end exactly on its cell's lower border, on a ray running towards lower values, is moved
  // 1/65536 cell into the cell: the crossing out of the end cell then comes strictly after every
  // crossing on the way, so the walk reaches the end cell in exactly |Δx| + |Δy| steps.
  if (to.x < from.x && (to.x & kFractionMask) == 0) ++to.x;
  if (to.y < from.y && (to.y & kFractionMask) == 0) ++to.y;
  const int x = cellOf(from.x), y = cellOf(from.y);
  const int end_x = cellOf(to.x), end_y = cellOf(to.y);
  const int steps = std::abs(end_x - x) + std::abs(end_y - y);
  if (steps == 0) return;
  const int step_x = to.x >= from.x ? 1 : -1, step_y = to.y >= from.y ? 1 : -1;
  const int64_t dx = std::abs(to.x - from.x), dy = std::abs(to.y - from.y);
  // From the start to the first border ahead in x and in y (≥ 0, in fixed point).
  const int64_t ahead_x = step_x > 0 ? (x + 1) * kOneCell - from.x : from.x - x * kOneCell;
  const int64_t ahead_y = step_y > 0 ? (y + 1) * kOneCell - from.y : from.y - y * kOneCell;
  int64_t e = ahead_x * dy - ahead_y * dx;
  const int64_t e_after_x = dy * kOneCell, e_after_y = dx * kOneCell;
  const ptrdiff_t row = step_y * static_cast<ptrdiff_t>(bounds_.width());
  const CellUpdate miss = updateFor(miss_delta_);
  Cell* cell = &cells_[indexOf(x, y)];
  miss(*cell);
  for (int left = steps; left > 1; --left) {
    const bool along_x = e < 0;
    cell += along_x ? step_x : row;
    e += along_x ? e_after_x : -e_after_y;
    miss(*cell);
  }
  observed_.add(x, y);
  // The last cell cleared: one step short of the end cell, on the axis the last step takes.
  observed_.add(end_x - (e < 0 ? step_x : 0), end_y - (e < 0 ? 0 : step_y));
}

GridSlice OccupancyGrid::slice() const {
  GridSlice out;
  out.resolution = options_.resolution;
  out.occupied_threshold = options_.occupied_threshold;
  out.free_threshold = options_.free_threshold;
  if (observed_.empty()) return out;
  out.origin = options_.resolution * Vec2(observed_.x0, observed_.y0);
  out.width = static_cast<int>(observed_.width());
  out.height = static_cast<int>(observed_.height());
  out.probability.resize(static_cast<size_t>(out.width) * static_cast<size_t>(out.height));
  // Neighbouring cells mostly hold the same few clamped values: reuse the last exp().
  float last_log_odds = 0.0f;
  auto last_probability = static_cast<float>(probability(0.0f));
  for (int iy = 0; iy < out.height; ++iy) {
    const Cell* row = &cells_[indexOf(observed_.x0, observed_.y0 + iy)];
    float* probabilities = &out.probability[out.index(0, iy)];
    for (int ix = 0; ix < out.width; ++ix) {
      const Cell& cell = row[ix];
      if (cell.stamp == 0) {
        probabilities[ix] = std::numeric_limits<float>::quiet_NaN();
        continue;
      }
      if (cell.log_odds != last_log_odds) {
        last_log_odds = cell.log_odds;
        last_probability = static_cast<float>(probability(cell.log_odds));
      }
      probabilities[ix] = last_probability;
    }
  }
  return out;
}

std::unique_ptr<octomap::OcTree> OccupancyGrid::toOcTree() const {
  auto tree = makeTree(options_);
  const octomap::key_type z = tree->coordToKey(layerZ());
  auto key = [](int index) { return static_cast<octomap::key_type>(index + kKeyOffset); };
  for (int iy = observed_.y0; iy <= observed_.y1; ++iy)
    for (int ix = observed_.x0; ix <= observed_.x1; ++ix) {
      const Cell& cell = cells_[indexOf(ix, iy)];
      if (cell.stamp != 0) tree->setNodeValue(octomap::OcTreeKey(key(ix), key(iy), z), cell.log_odds, /*lazy_eval=*/true);
    }
  tree->updateInnerOccupancy();
  tree->prune();
  return tree;
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
  grid.reserve(scans, poses);
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
