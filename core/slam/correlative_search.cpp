#include "slam/correlative_search.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <queue>
#include <stdexcept>

namespace polarslam {
namespace {

constexpr double kScoreScale = 255.0;

/// Level k from level k − 1: the maximum over the 2 × 2 windows of 2^(k−1) cells from each cell,
/// taken along rows (into `rows`, a cell each), then along columns (cells beyond the grid count as 0).
void poolMax(const uint8_t* finer, uint8_t* coarser, uint8_t* rows, int width, int height, int half) {
  const size_t w = static_cast<size_t>(width), h = static_cast<size_t>(height), step = static_cast<size_t>(half);
  for (size_t y = 0; y < h; ++y) {
    const uint8_t* in = &finer[y * w];
    uint8_t* out = &rows[y * w];
    const size_t inside = w > step ? w - step : 0;
    for (size_t x = 0; x < inside; ++x) out[x] = std::max(in[x], in[x + step]);
    for (size_t x = inside; x < w; ++x) out[x] = in[x];
  }
  const size_t inside = h > step ? h - step : 0;
  for (size_t y = 0; y < inside; ++y) {
    const uint8_t* a = &rows[y * w];
    const uint8_t* b = &rows[(y + step) * w];
    uint8_t* out = &coarser[y * w];
    for (size_t x = 0; x < w; ++x) out[x] = std::max(a[x], b[x]);
  }
  std::copy(rows + inside * w, rows + h * w, coarser + inside * w);
}

/// Items by an integer key in [min_key, max_key], highest first: a bucket per key, so that adding one
/// and taking the best cost O(1) (a heap of the millions of nodes a search holds spends its time in
/// cache misses). Items of equal key come out last in, first out. A bit per bucket marks the ones
/// holding items, so that finding the next key down skips 64 empty buckets at a time.
template <typename T>
class BucketQueue {
 public:
  BucketQueue(int min_key, int max_key)
      : min_key_(min_key),
        buckets_(static_cast<size_t>(std::max(max_key - min_key + 1, 0))),
        held_((buckets_.size() + 63) / 64, 0) {}
  /// `key` must lie in [min_key, max_key].
  void push(int key, const T& item) {
    const size_t b = static_cast<size_t>(key - min_key_);
    buckets_[b].push_back(item);
    held_[b / 64] |= uint64_t{1} << (b % 64);
    top_ = std::max(top_, static_cast<long>(b));
  }
  /// The highest key held, or -1 when empty.
  int topKey() {
    while (top_ >= 0) {
      const size_t word = static_cast<size_t>(top_) / 64;
      const uint64_t below = held_[word] & (~uint64_t{0} >> (63 - static_cast<size_t>(top_) % 64));
      if (below != 0) {
        top_ = static_cast<long>(word * 64) + 63 - std::countl_zero(below);
        return static_cast<int>(top_) + min_key_;
      }
      top_ = static_cast<long>(word * 64) - 1;
    }
    return -1;
  }
  /// An item of the highest key; only when not empty.
  T pop() {
    topKey();
    const size_t b = static_cast<size_t>(top_);
    std::vector<T>& bucket = buckets_[b];
    const T item = bucket.back();
    bucket.pop_back();
    if (bucket.empty()) held_[b / 64] &= ~(uint64_t{1} << (b % 64));
    return item;
  }

 private:
  int min_key_;
  std::vector<std::vector<T>> buckets_;
  std::vector<uint64_t> held_;  ///< bit b % 64 of word b / 64: bucket b holds items
  long top_ = -1;               ///< no bucket above this one holds items
};

}  // namespace

CorrelativeMapSearch::CorrelativeMapSearch(const std::vector<Vec2>& map_points,
                                           const std::vector<Vec2>& reference_positions, CorrelativeSearchParams params)
    : params_(params) {
  params_.levels = std::clamp(params_.levels, 1, 12);
  std::vector<Vec2> finite_points, finite_references;
  std::copy_if(map_points.begin(), map_points.end(), std::back_inserter(finite_points),
               [](const Vec2& p) { return p.allFinite(); });
  std::copy_if(reference_positions.begin(), reference_positions.end(), std::back_inserter(finite_references),
               [](const Vec2& p) { return p.allFinite(); });
  if (finite_points.empty() || finite_references.empty() || !(params_.resolution > 0.0) || !(params_.sigma > 0.0))
    return;
  Vec2 lo = finite_points.front(), hi = lo;
  for (const std::vector<Vec2>* set : {&finite_points, &finite_references})
    for (const Vec2& p : *set) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  const double res = params_.resolution;
  const double margin = params_.region_radius + 3.0 * params_.sigma + 2.0 * res;
  origin_ = lo - Vec2(margin, margin);
  const Vec2 cells_wide = ((hi - lo).array() + 2.0 * margin).matrix() / res;
  requireGridWithin(cells_wide, res, params_.max_cells, "the global search");
  width_ = static_cast<int>(std::ceil(cells_wide.x())) + 1;
  height_ = static_cast<int>(std::ceil(cells_wide.y())) + 1;
  const size_t cells = static_cast<size_t>(width_) * static_cast<size_t>(height_);

  // Both rasters go by a cell's distance d to the nearest of a set of points (its centre to the
  // point): the score grid is exp(-d²/2σ²) out to 3σ, the region the reference positions' discs.
  // Each point visits the cells of its disc's bounding box, in loops the compiler vectorises.
  const auto stamp = [&](const std::vector<Vec2>& centres, double radius, auto&& visit_row) {
    const double r2 = (radius / res) * (radius / res);
    const int reach = static_cast<int>(std::ceil(radius / res)) + 1;
    for (const Vec2& p : centres) {
      const double cx = (p.x() - origin_.x()) / res, cy = (p.y() - origin_.y()) / res;
      const int x0 = std::max(0, static_cast<int>(cx) - reach), x1 = std::min(width_ - 1, static_cast<int>(cx) + reach);
      const int y0 = std::max(0, static_cast<int>(cy) - reach), y1 = std::min(height_ - 1, static_cast<int>(cy) + reach);
      for (int y = y0; y <= y1; ++y) visit_row(static_cast<size_t>(y) * static_cast<size_t>(width_), x0, x1, y + 0.5 - cy, cx, r2);
    }
  };
  // The score is looked up by d², finely binned: the table falls with d², so the nearest point
  // gives the largest value. Each point stamps its d² on the cells within 3σ (a minimum), then each
  // cell takes its value once.
  constexpr int kBins = 4096;
  const double sigma = params_.sigma, score_radius = 3.0 * sigma;
  std::vector<uint8_t> likelihood(kBins);
  for (int i = 0; i < kBins; ++i) {
    const double d2 = score_radius * score_radius * i / (kBins - 1);  // in m²
    likelihood[static_cast<size_t>(i)] = static_cast<uint8_t>(std::lround(kScoreScale * std::exp(-0.5 * d2 / (sigma * sigma))));
  }
  LargePageVector<double> nearest_d2(cells, std::numeric_limits<double>::infinity());
  stamp(finite_points, score_radius, [&](size_t row_start, int x0, int x1, double ey, double cx, double) {
    double* row = &nearest_d2[row_start];
    for (int x = x0; x <= x1; ++x) {
      const double ex = x + 0.5 - cx;
      row[x] = std::min(row[x], ex * ex + ey * ey);
    }
  });
  // One score level more than nodes have: a node's headings widen the window its bound needs.
  cells_ = cells;
  score_levels_ = params_.levels + 1;
  grids_.assign(cells * static_cast<size_t>(score_levels_), 0);
  uint8_t* score = grids_.data();
  const double score_r2 = (score_radius / res) * (score_radius / res), bins_per_d2 = (kBins - 1) / score_r2;
  for (size_t c = 0; c < cells; ++c)
    if (nearest_d2[c] <= score_r2) score[c] = likelihood[static_cast<size_t>(nearest_d2[c] * bins_per_d2)];
  nearest_d2 = {};
  LargePageVector<uint8_t> rows(cells);
  for (int k = 1; k < score_levels_; ++k)
    poolMax(scoreLevel(k - 1), &grids_[static_cast<size_t>(k) * cells], rows.data(), width_, height_, 1 << (k - 1));

  // A robot position is a cell corner (origin + cell · resolution): shift by half a cell.
  std::vector<Vec2> shifted_references;
  for (const Vec2& p : finite_references) shifted_references.push_back(p + Vec2(0.5 * res, 0.5 * res));
  LargePageVector<uint8_t> region(cells, 0);
  stamp(shifted_references, params_.region_radius, [&](size_t row_start, int x0, int x1, double ey, double cx, double r2) {
    uint8_t* row = &region[row_start];
    for (int x = x0; x <= x1; ++x) {
      const double ex = x + 0.5 - cx;
      row[x] |= static_cast<uint8_t>(ex * ex + ey * ey <= r2);
    }
  });
  buildRegionLevels(std::move(region));
}

void CorrelativeMapSearch::buildRegionLevels(LargePageVector<uint8_t> region) {
  // Level k holds a bit per block of 2^k × 2^k cells (a node's translations: nodes of level k start
  // at multiples of 2^k), set where any cell of the block is in the region.
  int width = width_, height = height_;
  for (int k = 0; k < params_.levels; ++k) {
    if (k > 0) {
      const int coarser_width = (width + 1) / 2, coarser_height = (height + 1) / 2;
      LargePageVector<uint8_t> coarser(static_cast<size_t>(coarser_width) * static_cast<size_t>(coarser_height), 0);
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
          coarser[static_cast<size_t>(y / 2) * static_cast<size_t>(coarser_width) + static_cast<size_t>(x / 2)] |=
              region[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
      region = std::move(coarser);
      width = coarser_width;
      height = coarser_height;
    }
    RegionLevel bits{width, height, std::vector<uint64_t>((static_cast<size_t>(width) * static_cast<size_t>(height) + 63) / 64, 0)};
    for (size_t c = 0; c < static_cast<size_t>(width) * static_cast<size_t>(height); ++c)
      bits.bits[c / 64] |= uint64_t{region[c] != 0} << (c % 64);
    region_.push_back(std::move(bits));
  }
}

int CorrelativeMapSearch::cellValue(int level, int x, int y) const {
  // A window starting left of (below) the grid but reaching into it: its part in the grid is
  // within the window starting at 0, whose maximum bounds it.
  const int window = 1 << level;
  if (x <= -window || y <= -window || x >= width_ || y >= height_) return 0;
  x = std::max(x, 0);
  y = std::max(y, 0);
  return scoreLevel(level)[static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)];
}

bool CorrelativeMapSearch::regionAllows(int level, int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return false;
  return region_[static_cast<size_t>(level)].allows(x >> level, y >> level);
}

int CorrelativeMapSearch::nodeSum(const HeadingGroups& groups, int group_index, int level, int x, int y,
                                  int max_deficit) const {
  const HeadingGroup& group = groups[static_cast<size_t>(group_index)];
  const int scale = static_cast<int>(kScoreScale);
  const size_t n = groups.points, begin = static_cast<size_t>(group_index) * n;
  const int* extents = &groups.extents[begin];
  // Over the node, a point lands in the cells from its lowest one to 2^level − 1 + e beyond it on
  // each axis (the node's translations and its own motion e over the group's headings: a near point
  // barely moves as the heading turns). The windows of 2^L cells from its lowest cell and from e
  // cells on cover them, L the least level ≥ level with 2^L ≥ e: its bound is their maximum.
  const auto window_level = [level](unsigned e) { return std::max(level, static_cast<int>(std::bit_width(e - 1U))); };
  // Most nodes scored are pruned: once the points so far fall short of a perfect score by more
  // than max_deficit, the sum so far plus a perfect score for the rest is returned (a bound, below
  // what the node needs, as the whole is).
  const auto sum_of = [&](auto&& point_bound) {
    constexpr size_t kBatch = 8;
    int sum = 0;
    size_t i = 0;
    for (; i + kBatch <= n; i += kBatch) {
      for (size_t k = i; k < i + kBatch; ++k) sum += point_bound(k);
      if (scale * static_cast<int>(i + kBatch) - sum > max_deficit) return sum + scale * static_cast<int>(n - i - kBatch);
    }
    for (; i < n; ++i) sum += point_bound(i);
    return sum;
  };
  if (x + group.min_dx >= 0 && y + group.min_dy >= 0 && x + group.max_reach_x < width_ && y + group.max_reach_y < height_) {
    // Every window starts in the grid (the usual case): no clamping.
    const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(y) * width_ + x;
    const std::ptrdiff_t* offsets = &groups.offsets[begin];
    return sum_of([&](size_t k) {
      const unsigned e = static_cast<unsigned>(extents[k]);
      if (e == 0) return static_cast<int>(scoreLevel(level)[at + offsets[k]]);
      const int point_level = window_level(e);
      if (point_level >= score_levels_) return scale;
      const uint8_t* cell = scoreLevel(point_level) + at + offsets[k];
      const std::ptrdiff_t up = static_cast<std::ptrdiff_t>(e) * width_;
      return static_cast<int>(std::max({cell[0], cell[e], cell[up], cell[up + e]}));
    });
  }
  const int* dx = &groups.dx[begin];
  const int* dy = &groups.dy[begin];
  return sum_of([&](size_t k) {
    const int e = extents[k], cx = x + dx[k], cy = y + dy[k];
    if (e == 0) return cellValue(level, cx, cy);
    const int point_level = window_level(static_cast<unsigned>(e));
    if (point_level >= score_levels_) return scale;
    return std::max({cellValue(point_level, cx, cy), cellValue(point_level, cx + e, cy), cellValue(point_level, cx, cy + e),
                     cellValue(point_level, cx + e, cy + e)});
  });
}

// A heading step that moves a point `reach` away by at most one cell (Hess et al., (7)).
double CorrelativeMapSearch::headingStep(double reach) const {
  const double res = params_.resolution, r = std::max(reach, res);
  return std::acos(std::clamp(1.0 - res * res / (2.0 * r * r), -1.0, 1.0));
}

Pose2 CorrelativeMapSearch::poseOf(int heading, int headings, int x, int y) const {
  return Pose2(origin_.x() + x * params_.resolution, origin_.y() + y * params_.resolution,
               wrapAngle(2.0 * std::numbers::pi * heading / headings));
}

CorrelativeMapSearch::HeadingGroups CorrelativeMapSearch::headingGroups(const std::vector<Vec2>& points,
                                                                       int headings) const {
  HeadingGroups all;
  const size_t n = points.size();
  all.points = n;
  std::vector<size_t> level_sizes{static_cast<size_t>(headings)};
  while (level_sizes.back() > 1) level_sizes.push_back((level_sizes.back() + 1) / 2);
  size_t total = 0;
  for (const size_t count : level_sizes) total += count;
  all.groups.resize(total);
  all.dx.resize(total * n);
  all.dy.resize(total * n);
  all.offsets.resize(total * n);
  all.extents.assign(total * n, 0);
  const auto finish = [&](size_t g) {
    HeadingGroup& group = all.groups[g];
    const int* dx = &all.dx[g * n];
    const int* dy = &all.dy[g * n];
    std::ptrdiff_t* offsets = &all.offsets[g * n];
    for (size_t i = 0; i < n; ++i) offsets[i] = static_cast<std::ptrdiff_t>(dy[i]) * width_ + dx[i];
    group.min_dx = *std::min_element(dx, dx + n);
    group.min_dy = *std::min_element(dy, dy + n);
    const int* extents = &all.extents[g * n];
    group.max_reach_x = dx[0] + extents[0];
    group.max_reach_y = dy[0] + extents[0];
    for (size_t i = 1; i < n; ++i) {
      group.max_reach_x = std::max(group.max_reach_x, dx[i] + extents[i]);
      group.max_reach_y = std::max(group.max_reach_y, dy[i] + extents[i]);
    }
  };
  // Per group of the level below and of the one being built, and point: the highest cell over the
  // group's headings (the lowest is dx, dy). A single heading's highest is its own.
  std::vector<int> below_x(static_cast<size_t>(headings) * n), below_y(below_x.size()), high_x, high_y;
  for (int h = 0; h < headings; ++h) {
    const size_t g = static_cast<size_t>(h);
    all.groups[g].first = h;
    const double theta = 2.0 * std::numbers::pi * h / headings, c = std::cos(theta), s = std::sin(theta);
    for (size_t i = 0; i < n; ++i) {
      const Vec2& p = points[i];
      below_x[g * n + i] = all.dx[g * n + i] = static_cast<int>(std::floor((c * p.x() - s * p.y()) / params_.resolution));
      below_y[g * n + i] = all.dy[g * n + i] = static_cast<int>(std::floor((s * p.x() + c * p.y()) / params_.resolution));
    }
    finish(g);
  }
  size_t begin = 0;
  for (size_t k = 1; k < level_sizes.size(); ++k) {
    const size_t end = begin + level_sizes[k - 1];
    high_x.assign(level_sizes[k] * n, 0);
    high_y.assign(level_sizes[k] * n, 0);
    for (size_t a = begin, g = end; a < end; a += 2, ++g) {
      const size_t b = a + 1 < end ? a + 1 : a;  // an odd group out is its own parent's only child
      HeadingGroup& parent = all.groups[g];
      parent.level = all.groups[a].level + 1;
      parent.first = all.groups[a].first;
      parent.children[0] = static_cast<int>(a);
      if (b != a) parent.children[1] = static_cast<int>(b);
      const size_t ha = (a - begin) * n, hb = (b - begin) * n, hp = (g - end) * n;
      for (size_t i = 0; i < n; ++i) {
        const int dx = std::min(all.dx[a * n + i], all.dx[b * n + i]);
        const int dy = std::min(all.dy[a * n + i], all.dy[b * n + i]);
        const int hx = std::max(below_x[ha + i], below_x[hb + i]);
        const int hy = std::max(below_y[ha + i], below_y[hb + i]);
        all.dx[g * n + i] = dx;
        all.dy[g * n + i] = dy;
        all.extents[g * n + i] = std::max(hx - dx, hy - dy);
        high_x[hp + i] = hx;
        high_y[hp + i] = hy;
        parent.extent = std::max({parent.extent, hx - dx, hy - dy});
      }
      finish(g);
    }
    below_x.swap(high_x);
    below_y.swap(high_y);
    begin = end;
  }
  return all;
}

CorrelativeSearchResult CorrelativeMapSearch::find(const std::vector<Vec2>& points, const CorrelativeQuery& query) const {
  CorrelativeSearchResult result;
  if (score_levels_ == 0) return result;
  // A point farther than the grid is wide cannot land on the map from any searched position.
  const double max_reach = params_.resolution * std::hypot(width_, height_);
  double reach = 0.0;
  std::vector<Vec2> usable;
  for (const Vec2& p : points)
    if (p.allFinite() && p.norm() <= max_reach) {
      usable.push_back(p);
      reach = std::max(reach, p.norm());
    }
  if (usable.empty()) return result;
  const int headings = std::max(1, static_cast<int>(std::ceil(2.0 * std::numbers::pi / headingStep(reach))));
  const HeadingGroups groups = headingGroups(usable, headings);
  const int top = params_.levels - 1, span = 1 << top;
  // The root groups: those of the highest level whose points all move within a top node's span
  // (groups are stored level by level; a level's extents are at least those below it).
  size_t roots_begin = 0;
  for (size_t begin = 0; begin < groups.size();) {
    size_t end = begin;
    bool fits = true;
    for (; end < groups.size() && groups[end].level == groups[begin].level; ++end) fits = fits && groups[end].extent <= span;
    if (!fits) break;
    roots_begin = begin;
    begin = end;
  }
  // Best first (§V.B searches depth first per heading; best first scores fewer nodes when most
  // headings are hopeless): the first leaf taken is the best pose. A node's key is its score's sum
  // of cell values.
  const int points_count = static_cast<int>(usable.size());
  const auto score_of = [&](int sum) { return sum / (kScoreScale * points_count); };
  const int perfect = static_cast<int>(kScoreScale) * points_count;
  // The largest shortfall of a node's sum from a perfect one that still scores `threshold`.
  const auto allowed_deficit = [&](double threshold) {
    int deficit = static_cast<int>(std::clamp(std::floor((1.0 - threshold) * perfect), -1.0, static_cast<double>(perfect)));
    while (deficit >= 0 && score_of(perfect - deficit) < threshold) --deficit;
    while (deficit < perfect && score_of(perfect - deficit - 1) >= threshold) ++deficit;
    return deficit;
  };
  // Only nodes scoring at least min_score are ever queued (the threshold never falls below it).
  BucketQueue<Node> open(perfect - allowed_deficit(query.min_score), perfect);
  double threshold = std::max(query.min_score, query.best_at_least);
  int max_deficit = allowed_deficit(threshold);
  bool setting_aside = threshold > query.min_score;
  std::vector<Node> set_aside;  // scored below best_at_least before any place was found
  const auto consider = [&](int x, int y, int level, int group) {
    ++result.scored_nodes;
    const int sum = nodeSum(groups, group, level, x, y, max_deficit);
    if (score_of(sum) >= threshold) open.push(sum, {x, y, level, group, sum});
    else if (setting_aside) set_aside.push_back({x, y, level, group, sum});
  };
  const int root_level = groups[roots_begin].level;
  for (size_t g = roots_begin; g < groups.size() && groups[g].level == root_level; ++g)
    for (int y = 0; y < height_; y += span)
      for (int x = 0; x < width_; x += span)
        if (regionAllows(top, x, y)) consider(x, y, top, static_cast<int>(g));
  // Leaves come out best first: the first of each place is its best pose. A node whose every pose
  // is near a place found already can add none: it is not expanded.
  const auto within_a_place = [&](const Node& node, const HeadingGroup& group) {
    if (result.places.empty()) return false;
    const double first = 2.0 * std::numbers::pi * group.first / headings;
    const double turn = 2.0 * std::numbers::pi * (std::min(group.first + (1 << group.level), headings) - 1 - group.first) / headings;
    const double size = ((1 << node.level) - 1) * params_.resolution;
    const Vec2 corner = poseOf(group.first, headings, node.x, node.y).translation();
    return std::any_of(result.places.begin(), result.places.end(), [&](const CorrelativeHit& place) {
      const double from = wrapAngle(first - place.pose.theta);
      if (from < -query.rival_heading || from + turn > query.rival_heading) return false;
      for (const Vec2& offset : {Vec2(0.0, 0.0), Vec2(size, 0.0), Vec2(0.0, size), Vec2(size, size)})
        if ((corner + offset - place.pose.translation()).norm() > query.rival_distance) return false;
      return true;
    });
  };
  while (open.topKey() >= 0 && score_of(open.topKey()) >= threshold) {
    const Node node = open.pop();
    const HeadingGroup& group = groups[static_cast<size_t>(node.group)];
    if (within_a_place(node, group)) continue;
    if (node.level == 0 && group.level == 0) {
      result.places.push_back({poseOf(group.first, headings, node.x, node.y), score_of(node.sum)});
      if (query.go_on && !query.go_on(result.places)) break;
      threshold = std::max(query.min_score, result.places.front().score - query.rival_margin);
      max_deficit = allowed_deficit(threshold);
      if (setting_aside) {
        setting_aside = false;
        for (const Node& aside : set_aside)
          if (score_of(aside.sum) >= threshold) consider(aside.x, aside.y, aside.level, aside.group);
        set_aside = {};
      }
      continue;
    }
    // Branch on what loosens the bound more: the headings' spread or the translations'.
    if (group.level > 0 && (node.level == 0 || group.extent > (1 << node.level))) {
      for (const int child : group.children)
        if (child >= 0) consider(node.x, node.y, node.level, child);
      continue;
    }
    const int level = node.level - 1, half = 1 << level;
    for (const auto& [ox, oy] : {std::pair{0, 0}, {half, 0}, {0, half}, {half, half}}) {
      const int x = node.x + ox, y = node.y + oy;
      if (regionAllows(level, x, y)) consider(x, y, level, node.group);
    }
  }
  return result;
}

CorrelativeHit CorrelativeMapSearch::refine(const std::vector<Vec2>& points, const Pose2& pose, double translation,
                                            double rotation) const {
  CorrelativeHit best{pose, score(points, pose)};
  std::vector<Vec2> finite;
  double reach = 0.0;
  for (const Vec2& p : points)
    if (p.allFinite()) {
      finite.push_back(p);
      reach = std::max(reach, p.norm());
    }
  if (score_levels_ == 0 || finite.empty() || !finitePose(pose)) return best;
  const double res = params_.resolution, step = headingStep(reach), scale = kScoreScale * static_cast<double>(points.size());
  // A pose whose window and points lie wholly off the grid has nothing to refine (and its cells
  // would not fit an int).
  const double beyond = reach + std::max(0.0, translation) + res;
  const Vec2 from_origin = pose.translation() - origin_;
  if (from_origin.x() < -beyond || from_origin.y() < -beyond || from_origin.x() > width_ * res + beyond ||
      from_origin.y() > height_ * res + beyond)
    return best;
  const int cells = static_cast<int>(std::min(std::ceil(std::max(0.0, translation) / res), static_cast<double>(width_ + height_)));
  const int turns = std::min(static_cast<int>(std::ceil(std::max(0.0, rotation) / step)), 10000);
  // Per heading each point's cell is found once; the translations step it by whole cells.
  std::vector<int> cx(finite.size()), cy(finite.size());
  std::vector<std::ptrdiff_t> offsets(finite.size());
  for (int t = -turns; t <= turns; ++t) {
    const double theta = wrapAngle(pose.theta + t * step), c = std::cos(theta), s = std::sin(theta);
    for (size_t k = 0; k < finite.size(); ++k) {
      const Vec2& p = finite[k];
      cx[k] = static_cast<int>(std::floor((pose.x + c * p.x() - s * p.y() - origin_.x()) / res));
      cy[k] = static_cast<int>(std::floor((pose.y + s * p.x() + c * p.y() - origin_.y()) / res));
      offsets[k] = static_cast<std::ptrdiff_t>(cy[k]) * width_ + cx[k];
    }
    const auto [lo_x, hi_x] = std::minmax_element(cx.begin(), cx.end());
    const auto [lo_y, hi_y] = std::minmax_element(cy.begin(), cy.end());
    const bool inside = *lo_x - cells >= 0 && *lo_y - cells >= 0 && *hi_x + cells < width_ && *hi_y + cells < height_;
    for (int j = -cells; j <= cells; ++j)
      for (int i = -cells; i <= cells; ++i) {
        int sum = 0;
        if (inside) {
          const uint8_t* base = scoreLevel(0) + static_cast<std::ptrdiff_t>(j) * width_ + i;
          for (const std::ptrdiff_t offset : offsets) sum += base[offset];
        } else {
          for (size_t k = 0; k < finite.size(); ++k) sum += cellValue(0, cx[k] + i, cy[k] + j);
        }
        if (sum / scale > best.score) best = {Pose2(pose.x + i * res, pose.y + j * res, theta), sum / scale};
      }
  }
  return best;
}

double CorrelativeMapSearch::score(const std::vector<Vec2>& points, const Pose2& pose) const {
  if (score_levels_ == 0 || points.empty()) return 0.0;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta), res = params_.resolution;
  int sum = 0;
  for (const Vec2& p : points) {
    const double fx = (pose.x + c * p.x() - s * p.y() - origin_.x()) / res;
    const double fy = (pose.y + s * p.x() + c * p.y() - origin_.y()) / res;
    if (fx >= 0.0 && fy >= 0.0 && fx < width_ && fy < height_) sum += cellValue(0, static_cast<int>(fx), static_cast<int>(fy));
  }
  return sum / (kScoreScale * static_cast<double>(points.size()));
}

}  // namespace polarslam
