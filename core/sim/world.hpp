#pragma once
// A simulated 2D world: wall polylines whose segments each have a material, optional start
// pose and waypoint path, and fast ray casting for the laser and the advanced sonar.
//
//   World w = loadWorld("config/worlds/room.yaml");
//   RayHit h = w.castRay({0, 0}, /*direction=*/0.3, /*max_range=*/8.0, Sensor::Laser);
//   if (h.hit && h.echo) use(h.range, h.incidence);
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

/// What a surface does to each sensor.
enum class Material : int8_t {
  Wall = 0,       ///< laser and sonar see it
  Glass = 1,      ///< sonar sees it (sound reflects); the laser passes through
  Absorbing = 2,  ///< laser sees it; sound is absorbed, so the sonar gets no echo (and nothing behind it)
};
enum class Sensor : int8_t { Laser = 0, Sonar = 1 };

const char* materialName(Material m);
/// True if the surface stops this sensor's ray (everything except glass for the laser).
bool stopsRay(Material m, Sensor s);
/// True if the surface returns an echo to this sensor.
bool returnsEcho(Material m, Sensor s);

struct WallSegment {
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();
  Material material = Material::Wall;
  int polyline = -1;  ///< index into World::polylines()
  int surface = -1;   ///< segments of one polyline on one straight line share a surface id
  int source_line = 0;  ///< line of the world file that defined it (0 if built in code)

  double length() const { return (b - a).norm(); }
  Vec2 direction() const { return (b - a).normalized(); }
  /// Unit normal pointing to the left of a→b.
  Vec2 normal() const { const Vec2 d = direction(); return {-d.y(), d.x()}; }
};

struct WallPolyline {
  std::string name;
  std::vector<Vec2> points;  ///< after expanding bumps
  bool closed = false;
  int first_segment = 0;
  int num_segments = 0;
};

/// A point where wall segments end or meet, with the directions of the segments leaving it.
/// The sonar sees it as a corner (concave right angle, seen from inside) or an edge (convex
/// vertex or free wall end), see World::vertexAppearance().
struct WorldVertex {
  Vec2 position = Vec2::Zero();
  struct Arm {
    double angle = 0.0;  ///< world-frame direction of the segment leaving the vertex
    int segment = -1;
  };
  std::vector<Arm> arms;  ///< sorted by angle in (-π, π]
};

enum class VertexAppearance : int8_t { None = 0, ConcaveCorner = 1, RightAngleCorner = 2, Edge = 3 };

struct RayHit {
  bool hit = false;    ///< the ray stopped at a surface within max_range
  bool echo = false;   ///< that surface returns an echo to the sensor (false: sonar on absorbing)
  double range = std::numeric_limits<double>::infinity();  ///< m, distance to the hit
  int segment = -1;    ///< index into World::segments()
  double incidence = 0.0;  ///< rad in [0, π/2]: angle between the ray and the surface normal
  Vec2 point = Vec2::Zero();
};

struct WorldPath {
  std::vector<Vec2> waypoints;  ///< world frame, m
  bool loop = false;            ///< after the last waypoint, continue with the first again
};

class World {
 public:
  World() = default;

  /// Adds a polyline; `materials` has one entry per segment (size 1 = the same for all).
  /// Throws std::invalid_argument on fewer than 2 points or zero-length segments.
  void addPolyline(const std::vector<Vec2>& points, const std::vector<Material>& materials,
                   bool closed, const std::string& name = {}, int source_line = 0);
  /// Adds a closed rectangle centred at `center`, sides size.x() × size.y(), rotated by `angle`.
  void addBox(const Vec2& center, const Vec2& size, double angle, Material material,
              const std::string& name = {}, int source_line = 0);

  /// First surface along the ray from `origin` in direction `direction` (rad, world frame)
  /// that stops this sensor's ray, within max_range. Glass is transparent to the laser;
  /// absorbing surfaces stop sound but give no echo (RayHit::echo == false).
  RayHit castRay(const Vec2& origin, double direction, double max_range, Sensor sensor) const;
  /// Same result computed by testing every segment (reference for tests; slow).
  RayHit castRayAllSegments(const Vec2& origin, double direction, double max_range, Sensor sensor) const;
  /// True if nothing that stops this sensor lies strictly between `from` and `to`
  /// (surfaces within `tolerance` of `to` do not count).
  bool lineOfSight(const Vec2& from, const Vec2& to, Sensor sensor, double tolerance = 1e-4) const;

  /// How a vertex looks from `observer`: the wedge between the two arms around the observer's
  /// direction decides (< 180°: concave, ~90° of it: right-angle corner; > 180°: edge).
  VertexAppearance vertexAppearance(const WorldVertex& v, const Vec2& observer,
                                    double right_angle_tolerance) const;
  /// Segments of the wedge around `observer` at vertex v (one entry for a free end).
  std::vector<int> wedgeSegments(const WorldVertex& v, const Vec2& observer) const;

  const std::vector<WallSegment>& segments() const { return segments_; }
  const std::vector<WallPolyline>& polylines() const { return polylines_; }
  const std::vector<WorldVertex>& vertices() const { return vertices_; }
  Vec2 boundsMin() const { return bounds_min_; }
  Vec2 boundsMax() const { return bounds_max_; }

  std::string name;
  std::string source;            ///< file it was loaded from, if any
  std::optional<Pose2> start;    ///< default robot start pose
  WorldPath path;                ///< default robot path (may be empty)

 private:
  void rebuild();
  void assignSurfaces();
  void findVertices();
  void buildGrid();
  template <typename Visit>
  void traverseGrid(const Vec2& origin, const Vec2& dir, double max_range, Visit&& visit) const;
  bool rayHitsSegment(const Vec2& origin, const Vec2& dir, int segment, double& t) const;
  RayHit makeHit(const Vec2& origin, const Vec2& dir, int segment, double t, Sensor sensor) const;

  std::vector<WallSegment> segments_;
  std::vector<WallPolyline> polylines_;
  std::vector<WorldVertex> vertices_;
  Vec2 bounds_min_ = Vec2::Zero(), bounds_max_ = Vec2::Zero();
  // Uniform grid: cell (i, j) lists the segments that touch it.
  double cell_size_ = 1.0;
  int grid_nx_ = 0, grid_ny_ = 0;
  Vec2 grid_origin_ = Vec2::Zero();
  std::vector<std::vector<int>> cells_;
};

/// Free-function form of World::castRay.
inline RayHit castRay(const World& world, const Vec2& origin, double direction, double max_range,
                      Sensor sensor) {
  return world.castRay(origin, direction, max_range, sensor);
}

/// Loads a world file (format: config/worlds/README.md). Throws std::runtime_error naming the
/// file and line on anything malformed.
World loadWorld(const std::string& yaml_path);

}  // namespace polarslam
