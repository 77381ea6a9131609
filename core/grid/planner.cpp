#include "grid/planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace polarslam {
namespace {

constexpr double kFar = 1e20;  // "no obstacle" in squared cell units; finite so differences stay defined

/// Felzenszwalb & Huttenlocher's 1D squared distance transform of f (in place over `n` samples).
void distanceTransform1d(std::vector<double>& f, int n, std::vector<int>& v, std::vector<double>& z,
                         std::vector<double>& d) {
  int k = 0;
  v[0] = 0;
  z[0] = -kFar;
  z[1] = kFar;
  auto intersection = [&](int q, int p) {
    return ((f[q] + static_cast<double>(q) * q) - (f[p] + static_cast<double>(p) * p)) / (2.0 * q - 2.0 * p);
  };
  for (int q = 1; q < n; ++q) {
    double s = intersection(q, v[k]);
    while (s <= z[k]) {
      --k;
      s = intersection(q, v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kFar;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    d[q] = static_cast<double>(q - v[k]) * (q - v[k]) + f[v[k]];
  }
  std::copy(d.begin(), d.begin() + n, f.begin());
}

struct Cell {
  int x = 0, y = 0;
};

class SearchGrid {
 public:
  SearchGrid(const GridSlice& slice, const PlannerOptions& o) : slice_(slice), o_(o), clearance_(obstacleClearance(slice)) {}

  bool inside(Cell c) const { return slice_.inside(c.x, c.y); }
  size_t index(Cell c) const { return slice_.index(c.x, c.y); }
  float clearance(Cell c) const { return clearance_[index(c)]; }
  bool traversable(Cell c) const {
    return inside(c) && slice_.known(c.x, c.y) && !slice_.occupied(c.x, c.y) && clearance(c) >= o_.robot_radius;
  }
  /// Cost multiplier of a cell: 1 far from obstacles, up to 1 + clearance_cost at robot_radius.
  double costFactor(Cell c) const {
    const double span = std::max(1e-6, o_.comfort_distance - o_.robot_radius);
    const double t = std::clamp((o_.comfort_distance - clearance(c)) / span, 0.0, 1.0);
    return 1.0 + o_.clearance_cost * t;
  }
  Cell cellOf(const Vec2& p) const {
    Cell c;
    slice_.cellOf(p, c.x, c.y);
    return c;
  }
  Vec2 center(Cell c) const { return slice_.cellCenter(c.x, c.y); }
  const GridSlice& slice() const { return slice_; }

 private:
  const GridSlice& slice_;
  const PlannerOptions& o_;
  std::vector<float> clearance_;
};

constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};

/// A diagonal step may not cut the corner of a blocked cell.
bool stepAllowed(const SearchGrid& g, Cell from, int dir) {
  const Cell to{from.x + kDx[dir], from.y + kDy[dir]};
  if (!g.traversable(to)) return false;
  if (dir < 4) return true;
  return g.traversable({from.x + kDx[dir], from.y}) && g.traversable({from.x, from.y + kDy[dir]});
}

/// Nearest traversable cell to `p` within `radius` (m), if any.
bool nearestTraversable(const SearchGrid& g, const Vec2& p, double radius, Cell& out) {
  const Cell c = g.cellOf(p);
  const int r = static_cast<int>(std::ceil(radius / g.slice().resolution));
  double best = std::numeric_limits<double>::infinity();
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const Cell n{c.x + dx, c.y + dy};
      if (!g.traversable(n)) continue;
      const double d = (g.center(n) - p).norm();
      if (d <= radius && d < best) {
        best = d;
        out = n;
      }
    }
  return std::isfinite(best);
}

/// Cells reachable from `start` (flood fill with the same moves A* uses).
std::vector<char> reachableFrom(const SearchGrid& g, Cell start) {
  std::vector<char> seen(static_cast<size_t>(g.slice().width) * g.slice().height, 0);
  std::vector<Cell> stack{start};
  seen[g.index(start)] = 1;
  while (!stack.empty()) {
    const Cell c = stack.back();
    stack.pop_back();
    for (int dir = 0; dir < 8; ++dir) {
      if (!stepAllowed(g, c, dir)) continue;
      const Cell n{c.x + kDx[dir], c.y + kDy[dir]};
      char& s = seen[g.index(n)];
      if (!s) {
        s = 1;
        stack.push_back(n);
      }
    }
  }
  return seen;
}

Cell nearestReachable(const SearchGrid& g, const std::vector<char>& reachable, const Vec2& goal) {
  Cell best{};
  double best_distance = std::numeric_limits<double>::infinity();
  for (int y = 0; y < g.slice().height; ++y)
    for (int x = 0; x < g.slice().width; ++x) {
      if (!reachable[g.slice().index(x, y)]) continue;
      const double d = (g.center({x, y}) - goal).squaredNorm();
      if (d < best_distance) {
        best_distance = d;
        best = {x, y};
      }
    }
  return best;
}

std::vector<Cell> aStar(const SearchGrid& g, Cell start, Cell goal, int& expanded) {
  const size_t n = static_cast<size_t>(g.slice().width) * g.slice().height;
  std::vector<double> cost(n, std::numeric_limits<double>::infinity());
  std::vector<int> parent(n, -1);
  std::vector<char> closed(n, 0);
  auto heuristic = [&](Cell c) {
    const double dx = std::abs(c.x - goal.x), dy = std::abs(c.y - goal.y);
    return (std::max(dx, dy) + (std::sqrt(2.0) - 1.0) * std::min(dx, dy));
  };
  using Entry = std::pair<double, size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  const int width = g.slice().width;
  cost[g.index(start)] = 0.0;
  open.push({heuristic(start), g.index(start)});
  while (!open.empty()) {
    const size_t i = open.top().second;
    open.pop();
    if (closed[i]) continue;
    closed[i] = 1;
    ++expanded;
    const Cell c{static_cast<int>(i % width), static_cast<int>(i / width)};
    if (c.x == goal.x && c.y == goal.y) break;
    for (int dir = 0; dir < 8; ++dir) {
      if (!stepAllowed(g, c, dir)) continue;
      const Cell m{c.x + kDx[dir], c.y + kDy[dir]};
      const size_t j = g.index(m);
      const double step = (dir < 4 ? 1.0 : std::sqrt(2.0)) * 0.5 * (g.costFactor(c) + g.costFactor(m));
      if (cost[i] + step < cost[j]) {
        cost[j] = cost[i] + step;
        parent[j] = static_cast<int>(i);
        open.push({cost[j] + heuristic(m), j});
      }
    }
  }
  std::vector<Cell> path;
  if (!closed[g.index(goal)]) return path;
  for (int i = static_cast<int>(g.index(goal)); i >= 0; i = parent[static_cast<size_t>(i)])
    path.push_back({i % width, i / width});
  std::reverse(path.begin(), path.end());
  return path;
}

/// True if the straight segment a→b stays on traversable cells with at least `min_clearance`.
bool segmentClear(const SearchGrid& g, const Vec2& a, const Vec2& b, double min_clearance) {
  const double step = 0.25 * g.slice().resolution;
  const int samples = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
  for (int s = 0; s <= samples; ++s) {
    const Cell c = g.cellOf(a + (b - a) * (static_cast<double>(s) / samples));
    if (!g.traversable(c) || g.clearance(c) < min_clearance) return false;
  }
  return true;
}

/// Greedy line-of-sight shortening; a shortcut must keep the clearance of the cells it replaces.
std::vector<Vec2> shorten(const SearchGrid& g, const std::vector<Cell>& cells, double comfort) {
  std::vector<Vec2> out{g.center(cells.front())};
  size_t anchor = 0;
  while (anchor + 1 < cells.size()) {
    size_t best = anchor + 1;
    double min_clearance = g.clearance(cells[anchor + 1]);
    for (size_t j = anchor + 2; j < cells.size(); ++j) {
      min_clearance = std::min<double>(min_clearance, g.clearance(cells[j]));
      if (segmentClear(g, g.center(cells[anchor]), g.center(cells[j]), std::min(comfort, min_clearance))) best = j;
    }
    out.push_back(g.center(cells[best]));
    anchor = best;
  }
  return out;
}

double pathLength(const std::vector<Vec2>& p) {
  double length = 0.0;
  for (size_t i = 1; i < p.size(); ++i) length += (p[i] - p[i - 1]).norm();
  return length;
}

}  // namespace

std::vector<float> obstacleClearance(const GridSlice& slice) {
  const int w = slice.width, h = slice.height;
  std::vector<double> grid(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) grid[slice.index(x, y)] = slice.occupied(x, y) ? 0.0 : kFar;
  const int n = std::max(w, h);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (int x = 0; x < w; ++x) {
    for (int y = 0; y < h; ++y) f[y] = grid[slice.index(x, y)];
    distanceTransform1d(f, h, v, z, d);
    for (int y = 0; y < h; ++y) grid[slice.index(x, y)] = f[y];
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) f[x] = grid[slice.index(x, y)];
    distanceTransform1d(f, w, v, z, d);
    for (int x = 0; x < w; ++x) grid[slice.index(x, y)] = f[x];
  }
  std::vector<float> out(grid.size());
  for (size_t i = 0; i < grid.size(); ++i)
    out[i] = grid[i] >= 0.5 * kFar ? std::numeric_limits<float>::infinity()
                                   : static_cast<float>(std::sqrt(grid[i]) * slice.resolution);
  return out;
}

PlanResult planPath(const GridSlice& slice, const Vec2& start, const Vec2& goal, const PlannerOptions& options) {
  PlanResult result;
  if (slice.width == 0 || slice.height == 0) {
    result.failure = "empty grid";
    return result;
  }
  const SearchGrid g(slice, options);
  Cell start_cell;
  if (!nearestTraversable(g, start, options.start_search_radius, start_cell)) {
    result.failure = "no free space near the start";
    return result;
  }
  const std::vector<char> reachable = reachableFrom(g, start_cell);
  Cell goal_cell = g.cellOf(goal);
  result.goal_exact = g.inside(goal_cell) && reachable[g.index(goal_cell)];
  if (!result.goal_exact) goal_cell = nearestReachable(g, reachable, goal);
  const std::vector<Cell> cells = aStar(g, start_cell, goal_cell, result.expanded);
  if (cells.empty()) {
    result.failure = "no path";
    return result;
  }
  std::vector<Vec2> waypoints = shorten(g, cells, options.comfort_distance);
  // Start exactly at the robot; end exactly at the goal when it is reachable.
  const Cell robot_cell = g.cellOf(start);
  if (robot_cell.x == start_cell.x && robot_cell.y == start_cell.y) waypoints.front() = start;
  else waypoints.insert(waypoints.begin(), start);
  if (waypoints.size() == 1) waypoints.push_back(waypoints.front());
  if (result.goal_exact) waypoints.back() = goal;
  result.waypoints = std::move(waypoints);
  result.goal = result.waypoints.back();
  result.length = pathLength(result.waypoints);
  result.found = true;
  return result;
}

}  // namespace polarslam
