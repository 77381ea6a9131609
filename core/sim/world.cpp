#include "sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace polarslam {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kVertexTolerance = 1e-3;   // m: points closer than this are the same vertex
constexpr double kFlatTolerance = deg2rad(0.5);
constexpr double kMinRayDistance = 1e-9;    // m: hits closer than this to the origin are ignored
constexpr int kMaxGridCellsPerSide = 256;

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Does segment a–b touch the axis-aligned box [lo, hi]? (separating-axis test)
bool segmentTouchesBox(const Vec2& a, const Vec2& b, const Vec2& lo, const Vec2& hi) {
  if (std::max(a.x(), b.x()) < lo.x() || std::min(a.x(), b.x()) > hi.x()) return false;
  if (std::max(a.y(), b.y()) < lo.y() || std::min(a.y(), b.y()) > hi.y()) return false;
  const Vec2 e = b - a;
  const Vec2 corners[4] = {lo, {hi.x(), lo.y()}, hi, {lo.x(), hi.y()}};
  bool any_pos = false, any_neg = false;
  for (const Vec2& c : corners) {
    const double side = cross(e, c - a);
    any_pos |= side >= 0.0;
    any_neg |= side <= 0.0;
  }
  return any_pos && any_neg;
}

/// Counter-clockwise angle from a to b in [0, 2π).
double ccwAngle(double a, double b) {
  double d = std::fmod(b - a, 2.0 * kPi);
  if (d < 0.0) d += 2.0 * kPi;
  return d;
}

}  // namespace

const char* materialName(Material m) {
  switch (m) {
    case Material::Wall: return "wall";
    case Material::Glass: return "glass";
    case Material::Absorbing: return "absorbing";
  }
  return "?";
}

bool stopsRay(Material m, Sensor s) { return !(m == Material::Glass && s == Sensor::Laser); }

bool returnsEcho(Material m, Sensor s) {
  if (s == Sensor::Laser) return m != Material::Glass;
  return m != Material::Absorbing;
}

// ---------------------------------------------------------------------------------------------
// Building

void World::addPolyline(const std::vector<Vec2>& points, const std::vector<Material>& materials,
                        bool closed, const std::string& name, int source_line) {
  if (points.size() < 2) throw std::invalid_argument("polyline '" + name + "' needs at least 2 points");
  const size_t n_segments = closed ? points.size() : points.size() - 1;
  if (materials.size() != 1 && materials.size() != n_segments)
    throw std::invalid_argument("polyline '" + name + "': need 1 or " + std::to_string(n_segments) +
                                " materials, got " + std::to_string(materials.size()));
  WallPolyline poly;
  poly.name = name;
  poly.points = points;
  poly.closed = closed;
  poly.first_segment = static_cast<int>(segments_.size());
  poly.num_segments = static_cast<int>(n_segments);
  for (size_t i = 0; i < n_segments; ++i) {
    WallSegment seg;
    seg.a = points[i];
    seg.b = points[(i + 1) % points.size()];
    if ((seg.b - seg.a).norm() < kVertexTolerance)
      throw std::invalid_argument("polyline '" + name + "': segment " + std::to_string(i) +
                                  " has (almost) zero length");
    seg.material = materials.size() == 1 ? materials[0] : materials[i];
    seg.polyline = static_cast<int>(polylines_.size());
    seg.source_line = source_line;
    segments_.push_back(seg);
  }
  polylines_.push_back(std::move(poly));
  rebuild();
}

void World::addBox(const Vec2& center, const Vec2& size, double angle, Material material,
                   const std::string& name, int source_line) {
  const Pose2 frame(center.x(), center.y(), angle);
  const double hx = 0.5 * size.x(), hy = 0.5 * size.y();
  addPolyline({frame.transform({-hx, -hy}), frame.transform({hx, -hy}), frame.transform({hx, hy}),
               frame.transform({-hx, hy})},
              {material}, /*closed=*/true, name, source_line);
}

void World::rebuild() {
  assignSurfaces();
  buildGrid();
  findVertices();  // uses the grid
}

void World::assignSurfaces() {
  int next_surface = 0;
  for (const WallPolyline& poly : polylines_) {
    const int first = poly.first_segment, last = first + poly.num_segments;
    for (int i = first; i < last; ++i) {
      WallSegment& si = segments_[i];
      si.surface = -1;
      for (int j = first; j < i && si.surface < 0; ++j) {
        const WallSegment& sj = segments_[j];
        const Vec2 dj = sj.direction();
        const bool parallel = std::abs(cross(si.direction(), dj)) < 1e-6;
        const bool on_line = std::abs(cross(dj, si.a - sj.a)) < kVertexTolerance;
        if (parallel && on_line && sj.material == si.material) si.surface = sj.surface;
      }
      if (si.surface < 0) si.surface = next_surface++;
    }
  }
}

void World::findVertices() {
  vertices_.clear();
  // Segments and vertices near p, looked up through the grid (built first).
  auto cellsAround = [&](const Vec2& p, auto&& visit) {
    const int i0 = std::max(0, static_cast<int>(std::floor((p.x() - kVertexTolerance - grid_origin_.x()) / cell_size_)));
    const int i1 = std::min(grid_nx_ - 1, static_cast<int>(std::floor((p.x() + kVertexTolerance - grid_origin_.x()) / cell_size_)));
    const int j0 = std::max(0, static_cast<int>(std::floor((p.y() - kVertexTolerance - grid_origin_.y()) / cell_size_)));
    const int j1 = std::min(grid_ny_ - 1, static_cast<int>(std::floor((p.y() + kVertexTolerance - grid_origin_.y()) / cell_size_)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) visit(static_cast<size_t>(j) * grid_nx_ + i);
  };
  std::vector<std::vector<int>> vertices_in_cell(cells_.size());
  auto known = [&](const Vec2& p) {
    bool found = false;
    cellsAround(p, [&](size_t cell) {
      for (int v : vertices_in_cell[cell]) found |= (vertices_[v].position - p).norm() < kVertexTolerance;
    });
    return found;
  };
  auto addArm = [](WorldVertex& v, const Vec2& towards, int segment) {
    const Vec2 d = towards - v.position;
    v.arms.push_back({std::atan2(d.y(), d.x()), segment});
  };
  std::vector<int> nearby;
  for (const WallSegment& candidate : segments_) {
    for (const Vec2& p : {candidate.a, candidate.b}) {
      if (known(p)) continue;
      nearby.clear();
      cellsAround(p, [&](size_t cell) { nearby.insert(nearby.end(), cells_[cell].begin(), cells_[cell].end()); });
      std::sort(nearby.begin(), nearby.end());
      nearby.erase(std::unique(nearby.begin(), nearby.end()), nearby.end());
      WorldVertex v;
      v.position = p;
      for (int j : nearby) {
        const WallSegment& s = segments_[j];
        if ((s.a - p).norm() < kVertexTolerance) {
          addArm(v, s.b, j);
        } else if ((s.b - p).norm() < kVertexTolerance) {
          addArm(v, s.a, j);
        } else if (distanceToSegment(p, s.a, s.b) < kVertexTolerance) {  // T-junction
          addArm(v, s.a, j);
          addArm(v, s.b, j);
        }
      }
      std::sort(v.arms.begin(), v.arms.end(),
                [](const WorldVertex::Arm& x, const WorldVertex::Arm& y) { return x.angle < y.angle; });
      const bool straight_through =
          v.arms.size() == 2 && std::abs(ccwAngle(v.arms[0].angle, v.arms[1].angle) - kPi) < kFlatTolerance;
      if (straight_through) continue;
      const int index = static_cast<int>(vertices_.size());
      vertices_.push_back(std::move(v));
      cellsAround(p, [&](size_t cell) { vertices_in_cell[cell].push_back(index); });
    }
  }
}

void World::buildGrid() {
  cells_.clear();
  grid_nx_ = grid_ny_ = 0;
  if (segments_.empty()) return;
  bounds_min_ = bounds_max_ = segments_[0].a;
  for (const WallSegment& s : segments_)
    for (const Vec2& p : {s.a, s.b}) {
      bounds_min_ = bounds_min_.cwiseMin(p);
      bounds_max_ = bounds_max_.cwiseMax(p);
    }
  const Vec2 margin = Vec2::Constant(0.05);
  grid_origin_ = bounds_min_ - margin;
  const Vec2 extent = bounds_max_ + margin - grid_origin_;
  cell_size_ = std::max(0.5, extent.maxCoeff() / kMaxGridCellsPerSide);
  grid_nx_ = static_cast<int>(std::ceil(extent.x() / cell_size_));
  grid_ny_ = static_cast<int>(std::ceil(extent.y() / cell_size_));
  cells_.assign(static_cast<size_t>(grid_nx_) * grid_ny_, {});
  const double pad = 1e-6;
  for (int k = 0; k < static_cast<int>(segments_.size()); ++k) {
    const WallSegment& s = segments_[k];
    const Vec2 lo = s.a.cwiseMin(s.b), hi = s.a.cwiseMax(s.b);
    const int i0 = std::max(0, static_cast<int>(std::floor((lo.x() - grid_origin_.x()) / cell_size_)) - 1);
    const int i1 = std::min(grid_nx_ - 1, static_cast<int>(std::floor((hi.x() - grid_origin_.x()) / cell_size_)) + 1);
    const int j0 = std::max(0, static_cast<int>(std::floor((lo.y() - grid_origin_.y()) / cell_size_)) - 1);
    const int j1 = std::min(grid_ny_ - 1, static_cast<int>(std::floor((hi.y() - grid_origin_.y()) / cell_size_)) + 1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Vec2 cell_lo = grid_origin_ + cell_size_ * Vec2(i, j) - Vec2::Constant(pad);
        const Vec2 cell_hi = cell_lo + Vec2::Constant(cell_size_ + 2 * pad);
        if (segmentTouchesBox(s.a, s.b, cell_lo, cell_hi)) cells_[static_cast<size_t>(j) * grid_nx_ + i].push_back(k);
      }
  }
}

// ---------------------------------------------------------------------------------------------
// Ray casting

bool World::rayHitsSegment(const Vec2& o, const Vec2& d, int segment, double& t) const {
  const WallSegment& s = segments_[segment];
  const Vec2 e = s.b - s.a;
  const double denom = cross(d, e);
  if (std::abs(denom) < 1e-15 * e.norm()) return false;  // parallel
  const Vec2 w = s.a - o;
  t = cross(w, e) / denom;
  const double u = cross(w, d) / denom;  // position along the segment, 0..1
  return t > kMinRayDistance && u >= -1e-12 && u <= 1.0 + 1e-12;
}

RayHit World::makeHit(const Vec2& o, const Vec2& d, int segment, double t, Sensor sensor) const {
  const WallSegment& s = segments_[segment];
  RayHit hit;
  hit.hit = true;
  hit.echo = returnsEcho(s.material, sensor);
  hit.range = t;
  hit.segment = segment;
  hit.point = o + t * d;
  hit.incidence = std::acos(std::min(1.0, std::abs(d.dot(s.normal()))));
  return hit;
}

/// Amanatides–Woo traversal of the grid cells the ray crosses, in order, up to max_range.
/// visit(cell_segments, t_exit) returns true to stop.
template <typename Visit>
void World::traverseGrid(const Vec2& o, const Vec2& d, double max_range, Visit&& visit) const {
  if (cells_.empty()) return;
  // Clip [0, max_range] to the grid box.
  const Vec2 lo = grid_origin_, hi = grid_origin_ + cell_size_ * Vec2(grid_nx_, grid_ny_);
  double t0 = 0.0, t1 = max_range;
  for (int axis = 0; axis < 2; ++axis) {
    if (std::abs(d[axis]) < 1e-300) {
      if (o[axis] < lo[axis] || o[axis] > hi[axis]) return;
      continue;
    }
    double ta = (lo[axis] - o[axis]) / d[axis], tb = (hi[axis] - o[axis]) / d[axis];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return;
  const Vec2 entry = o + t0 * d;
  int i = std::clamp(static_cast<int>(std::floor((entry.x() - lo.x()) / cell_size_)), 0, grid_nx_ - 1);
  int j = std::clamp(static_cast<int>(std::floor((entry.y() - lo.y()) / cell_size_)), 0, grid_ny_ - 1);
  const int step_i = d.x() > 0 ? 1 : -1, step_j = d.y() > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  auto nextBoundary = [&](int axis, int index, int step) {
    if (std::abs(d[axis]) < 1e-300) return inf;
    const double boundary = lo[axis] + cell_size_ * (index + (step > 0 ? 1 : 0));
    return (boundary - o[axis]) / d[axis];
  };
  double t_max_x = nextBoundary(0, i, step_i), t_max_y = nextBoundary(1, j, step_j);
  const double t_delta_x = std::abs(d.x()) < 1e-300 ? inf : cell_size_ / std::abs(d.x());
  const double t_delta_y = std::abs(d.y()) < 1e-300 ? inf : cell_size_ / std::abs(d.y());
  while (true) {
    const double t_exit = std::min(t_max_x, t_max_y);
    if (visit(cells_[static_cast<size_t>(j) * grid_nx_ + i], t_exit)) return;
    if (t_exit > t1) return;
    if (t_max_x < t_max_y) {
      i += step_i;
      t_max_x += t_delta_x;
    } else {
      j += step_j;
      t_max_y += t_delta_y;
    }
    if (i < 0 || j < 0 || i >= grid_nx_ || j >= grid_ny_) return;
  }
}

RayHit World::castRay(const Vec2& origin, double direction, double max_range, Sensor sensor) const {
  const Vec2 d(std::cos(direction), std::sin(direction));
  double best_t = max_range;
  int best = -1;
  traverseGrid(origin, d, max_range, [&](const std::vector<int>& cell, double t_exit) {
    for (int k : cell) {
      double t = 0.0;
      if (!stopsRay(segments_[k].material, sensor) || !rayHitsSegment(origin, d, k, t)) continue;
      if (t < best_t || (t == best_t && (best < 0 || k < best))) {
        best_t = t;
        best = k;
      }
    }
    return best >= 0 && best_t <= t_exit + 1e-9;
  });
  if (best < 0) return {};
  return makeHit(origin, d, best, best_t, sensor);
}

RayHit World::castRayAllSegments(const Vec2& origin, double direction, double max_range,
                                 Sensor sensor) const {
  const Vec2 d(std::cos(direction), std::sin(direction));
  double best_t = max_range;
  int best = -1;
  for (int k = 0; k < static_cast<int>(segments_.size()); ++k) {
    double t = 0.0;
    if (!stopsRay(segments_[k].material, sensor) || !rayHitsSegment(origin, d, k, t)) continue;
    if (t < best_t || (t == best_t && best < 0)) {
      best_t = t;
      best = k;
    }
  }
  if (best < 0) return {};
  return makeHit(origin, d, best, best_t, sensor);
}

bool World::lineOfSight(const Vec2& from, const Vec2& to, Sensor sensor, double tolerance) const {
  const Vec2 delta = to - from;
  const double dist = delta.norm();
  if (dist <= tolerance) return true;
  return !castRay(from, std::atan2(delta.y(), delta.x()), dist - tolerance, sensor).hit;
}

// ---------------------------------------------------------------------------------------------
// Vertices as the sonar sees them

namespace {

/// Index i of the arm such that the observer direction lies counter-clockwise between
/// arms[i] and arms[i+1] (cyclic).
size_t wedgeStart(const WorldVertex& v, double observer_angle) {
  const size_t n = v.arms.size();
  for (size_t i = 0; i < n; ++i) {
    const double width = n == 1 ? 2.0 * kPi : ccwAngle(v.arms[i].angle, v.arms[(i + 1) % n].angle);
    if (ccwAngle(v.arms[i].angle, observer_angle) < width) return i;
  }
  return n - 1;
}

}  // namespace

VertexAppearance World::vertexAppearance(const WorldVertex& v, const Vec2& observer,
                                         double right_angle_tolerance) const {
  if (v.arms.empty()) return VertexAppearance::None;
  if (v.arms.size() == 1) return VertexAppearance::Edge;  // free end of a wall
  const Vec2 o = observer - v.position;
  const size_t i = wedgeStart(v, std::atan2(o.y(), o.x()));
  const double width = ccwAngle(v.arms[i].angle, v.arms[(i + 1) % v.arms.size()].angle);
  if (width < kPi - kFlatTolerance) {
    return std::abs(width - 0.5 * kPi) <= right_angle_tolerance ? VertexAppearance::RightAngleCorner
                                                                 : VertexAppearance::ConcaveCorner;
  }
  if (width > kPi + kFlatTolerance) return VertexAppearance::Edge;
  return VertexAppearance::None;
}

std::vector<int> World::wedgeSegments(const WorldVertex& v, const Vec2& observer) const {
  if (v.arms.empty()) return {};
  if (v.arms.size() == 1) return {v.arms[0].segment};
  const Vec2 o = observer - v.position;
  const size_t i = wedgeStart(v, std::atan2(o.y(), o.x()));
  return {v.arms[i].segment, v.arms[(i + 1) % v.arms.size()].segment};
}

}  // namespace polarslam
