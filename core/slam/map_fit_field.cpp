#include "slam/map_fit_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace polarslam {
namespace {

/// Endpoints of the readings within max_range, in the map frame.
template <typename Visit>
void forEachEndpoint(const LaserScan& scan, const Pose2& robot, double max_range, Visit visit) {
  const Pose2 laser = robot * scan.laser_pose;
  const double c = std::cos(laser.theta), s = std::sin(laser.theta);
  for (size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i) || scan.ranges[i] > max_range) continue;
    const Vec2 p = scan.point(i);
    visit(Vec2(laser.x + c * p.x() - s * p.y(), laser.y + s * p.x() + c * p.y()));
  }
}

}  // namespace

std::vector<Vec2> mapEndpoints(const std::vector<LaserScan>& scans, const std::vector<Pose2>& poses, double max_range) {
  std::vector<Vec2> points;
  for (size_t k = 0; k < scans.size() && k < poses.size(); ++k)
    forEachEndpoint(scans[k], poses[k], max_range, [&](const Vec2& p) {
      if (p.allFinite()) points.push_back(p);
    });
  return points;
}

MapFitField::MapFitField(const std::vector<LaserScan>& scans, const std::vector<Pose2>& poses, double max_range,
                         double fit_distance, double resolution)
    : MapFitField(mapEndpoints(scans, poses, max_range), max_range, fit_distance, resolution) {}

void requireGridWithin(const Vec2& cells_wide, double resolution, size_t max_cells, const char* what) {
  const double cells = (std::ceil(cells_wide.x()) + 1.0) * (std::ceil(cells_wide.y()) + 1.0);
  if (cells <= static_cast<double>(max_cells)) return;
  char text[256];
  std::snprintf(text, sizeof text, "%s: the map spans %.4g m x %.4g m, %.3g cells at %g m, more than max_cells (%zu)", what,
                cells_wide.x() * resolution, cells_wide.y() * resolution, cells, resolution, max_cells);
  throw std::length_error(text);
}

MapFitField::MapFitField(const std::vector<Vec2>& points, double max_range, double fit_distance, double resolution,
                         size_t max_cells)
    : max_range_(max_range), resolution_(resolution) {
  if (points.empty()) return;
  Vec2 lo = points.front(), hi = points.front();
  for (const Vec2& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double margin = fit_distance + resolution;
  origin_ = lo - Vec2(margin, margin);
  const Vec2 cells_wide = ((hi - lo).array() + 2 * margin).matrix() / resolution;
  requireGridWithin(cells_wide, resolution, max_cells, "the map fit field");
  width_ = static_cast<size_t>(std::ceil(cells_wide.x())) + 1;
  height_ = static_cast<size_t>(std::ceil(cells_wide.y())) + 1;
  near_.assign(width_ * height_, 0);
  const int reach = static_cast<int>(std::ceil(fit_distance / resolution));
  const double reach2 = (fit_distance / resolution) * (fit_distance / resolution);
  for (const Vec2& p : points) {
    const int cx = static_cast<int>(std::floor((p.x() - origin_.x()) / resolution));
    const int cy = static_cast<int>(std::floor((p.y() - origin_.y()) / resolution));
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const int x = cx + dx, y = cy + dy;
        if (dx * dx + dy * dy > reach2 || x < 0 || y < 0 || x >= static_cast<int>(width_) || y >= static_cast<int>(height_))
          continue;
        near_[static_cast<size_t>(y) * width_ + static_cast<size_t>(x)] = 1;
      }
  }
}

bool MapFitField::near(const Vec2& point) const {
  const double fx = (point.x() - origin_.x()) / resolution_, fy = (point.y() - origin_.y()) / resolution_;
  if (!(fx >= 0.0 && fy >= 0.0 && fx < static_cast<double>(width_) && fy < static_cast<double>(height_))) return false;
  return near_[static_cast<size_t>(fy) * width_ + static_cast<size_t>(fx)] != 0;
}

double MapFitField::seeThrough(const LaserScan& scan, const Pose2& pose, double clearance) const {
  const Pose2 laser = pose * scan.laser_pose;
  size_t readings = 0, crossing = 0;
  for (size_t i = 0; i < scan.size(); i += 2) {
    if (!scan.valid(i) || scan.ranges[i] > max_range_) continue;
    ++readings;
    const double bearing = laser.theta + scan.bearing(i);
    const Vec2 direction(std::cos(bearing), std::sin(bearing));
    // Through a wall, not along one: the ray must enter the map's band and leave it again well
    // before its endpoint (a ray meeting a wall at a shallow angle stays in its band to the end).
    // A gap in a sparsely sampled wall is a short exit: the ray must stay out for `clearance`.
    bool entered = false;
    double left_at = -1.0;  // where the ray last left the band, < 0 while inside or before
    for (double d = clearance; d < scan.ranges[i] - clearance; d += resolution_) {
      if (near(laser.translation() + d * direction)) {
        entered = true;
        left_at = -1.0;
      } else if (entered && left_at < 0.0) {
        left_at = d;
      } else if (entered && d - left_at >= clearance) {
        ++crossing;
        break;
      }
    }
  }
  return readings ? static_cast<double>(crossing) / static_cast<double>(readings) : 0.0;
}

double MapFitField::fit(const LaserScan& scan, const Pose2& pose) const {
  size_t readings = 0, inliers = 0;
  forEachEndpoint(scan, pose, max_range_, [&](const Vec2& p) {
    ++readings;
    if (near(p)) ++inliers;
  });
  return readings ? static_cast<double>(inliers) / static_cast<double>(readings) : 0.0;
}

}  // namespace polarslam
