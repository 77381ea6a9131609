// loadWorld: the YAML world file format documented in config/worlds/README.md.
#include <algorithm>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "sim/world.hpp"
#include "config/yaml_fields.hpp"

namespace polarslam {
namespace {

constexpr double kCoordinateLimit = 10000.0;  // m: anything further is a typo
constexpr double kMinFeatureSize = 0.005;     // m
constexpr double kMaxBumpDepth = 2.0;         // m: bumps are small features, not rooms
constexpr double kEndClearance = 0.001;       // m: a bump may not touch its segment's ends

struct Bump {
  double at = 0.0, width = 0.0, depth = 0.0;
};

Material parseMaterial(const YamlFields& f, const YAML::Node& node, const std::string& name) {
  if (!node.IsScalar()) f.fail(node, name + ": expected a material (wall, glass, absorbing)");
  const std::string m = node.Scalar();
  if (m == "wall") return Material::Wall;
  if (m == "glass") return Material::Glass;
  if (m == "absorbing") return Material::Absorbing;
  f.fail(node, name + ": unknown material '" + m + "' (expected wall, glass or absorbing)");
}

std::vector<Material> parseSegmentMaterials(const YamlFields& f, const YAML::Node& wall,
                                            const std::string& name, size_t n_segments) {
  const Material fallback =
      wall["material"] ? parseMaterial(f, wall["material"], name + ".material") : Material::Wall;
  std::vector<Material> materials(n_segments, fallback);
  if (const YAML::Node list = wall["materials"]) {
    f.requireSequence(list, name + ".materials");
    if (list.size() != n_segments)
      f.fail(list, name + ".materials: has " + std::to_string(list.size()) + " entries but the polyline has " +
                       std::to_string(n_segments) + " segments");
    for (size_t i = 0; i < n_segments; ++i)
      materials[i] = parseMaterial(f, list[i], name + ".materials[" + std::to_string(i) + "]");
  }
  return materials;
}

std::vector<std::vector<Bump>> parseBumps(const YamlFields& f, const YAML::Node& wall, const std::string& name,
                                          const std::vector<Vec2>& points, bool closed) {
  const size_t n_segments = closed ? points.size() : points.size() - 1;
  std::vector<std::vector<Bump>> bumps(n_segments);
  const YAML::Node list = wall["bumps"];
  if (!list) return bumps;
  f.requireSequence(list, name + ".bumps");
  for (size_t k = 0; k < list.size(); ++k) {
    const YAML::Node b = list[k];
    const std::string ctx = name + ".bumps[" + std::to_string(k) + "]";
    f.requireMap(b, ctx, {"segment", "at", "width", "depth"});
    const int seg = f.integer(b, "segment", ctx, 0, 0, static_cast<int>(n_segments) - 1);
    const double length = (points[(seg + 1) % points.size()] - points[seg]).norm();
    Bump bump;
    bump.at = f.requiredNumber(b, "at", ctx, kEndClearance, length);
    bump.width = f.requiredNumber(b, "width", ctx, kMinFeatureSize, length);
    bump.depth = f.requiredNumber(b, "depth", ctx, -kMaxBumpDepth, kMaxBumpDepth);
    if (std::abs(bump.depth) < kMinFeatureSize) f.fail(b, ctx + ".depth: must be at least 5 mm (either sign)");
    if (bump.at + bump.width > length - kEndClearance)
      f.fail(b, ctx + ": bump ends beyond its segment (at + width > segment length " + std::to_string(length) + " m)");
    for (const Bump& other : bumps[seg])
      if (bump.at < other.at + other.width + kEndClearance && other.at < bump.at + bump.width + kEndClearance)
        f.fail(b, ctx + ": overlaps another bump on segment " + std::to_string(seg));
    bumps[seg].push_back(bump);
  }
  for (auto& on_segment : bumps)
    std::sort(on_segment.begin(), on_segment.end(), [](const Bump& a, const Bump& b) { return a.at < b.at; });
  return bumps;
}

/// Replaces each bump by four points: up the bump's side, along its face, back down.
void expandBumps(const std::vector<Vec2>& points, const std::vector<Material>& materials,
                 const std::vector<std::vector<Bump>>& bumps, bool closed, std::vector<Vec2>& out_points,
                 std::vector<Material>& out_materials) {
  const size_t n_segments = closed ? points.size() : points.size() - 1;
  for (size_t s = 0; s < n_segments; ++s) {
    const Vec2 a = points[s], b = points[(s + 1) % points.size()];
    const Vec2 u = (b - a).normalized(), n(-u.y(), u.x());
    out_points.push_back(a);
    out_materials.push_back(materials[s]);
    for (const Bump& bump : bumps[s]) {
      const Vec2 q0 = a + bump.at * u, q3 = q0 + bump.width * u;
      for (const Vec2& q : {q0, Vec2(q0 + bump.depth * n), Vec2(q3 + bump.depth * n), q3}) {
        out_points.push_back(q);
        out_materials.push_back(materials[s]);
      }
    }
  }
  if (!closed) out_points.push_back(points.back());
}

void parseWall(const YamlFields& f, const YAML::Node& wall, size_t index, World& world) {
  const std::string name = "walls[" + std::to_string(index) + "]";
  f.requireMap(wall, name, {"name", "points", "closed", "material", "materials", "bumps"});
  const YAML::Node pts = wall["points"];
  if (!pts) f.fail(wall, "missing key 'points' in " + name);
  f.requireSequence(pts, name + ".points");
  if (pts.size() < 2) f.fail(pts, name + ".points: a polyline needs at least 2 points, got " + std::to_string(pts.size()));
  const bool closed = f.boolean(wall, "closed", name, false);
  if (closed && pts.size() < 3) f.fail(pts, name + ".points: a closed polyline needs at least 3 points");
  std::vector<Vec2> points;
  for (size_t i = 0; i < pts.size(); ++i) {
    points.push_back(f.point(pts[i], name + ".points[" + std::to_string(i) + "]", kCoordinateLimit));
    if (i > 0 && (points[i] - points[i - 1]).norm() < 1e-3)
      f.fail(pts[i], name + ".points[" + std::to_string(i) + "]: repeats the previous point (zero-length segment)");
  }
  if (closed && (points.front() - points.back()).norm() < 1e-3)
    f.fail(pts, name + ": closed polyline repeats its first point at the end; list each corner once");
  const size_t n_segments = closed ? points.size() : points.size() - 1;
  const std::vector<Material> materials = parseSegmentMaterials(f, wall, name, n_segments);
  const auto bumps = parseBumps(f, wall, name, points, closed);
  std::vector<Vec2> expanded;
  std::vector<Material> expanded_materials;
  expandBumps(points, materials, bumps, closed, expanded, expanded_materials);
  const std::string label = f.text(wall, "name", name, name);
  try {
    world.addPolyline(expanded, expanded_materials, closed, label, wall.Mark().line + 1);
  } catch (const std::invalid_argument& e) {
    f.fail(wall, name + ": " + e.what());
  }
}

void parseBox(const YamlFields& f, const YAML::Node& box, size_t index, World& world) {
  const std::string name = "boxes[" + std::to_string(index) + "]";
  f.requireMap(box, name, {"name", "center", "size", "angle_deg", "material"});
  if (!box["center"]) f.fail(box, "missing key 'center' in " + name);
  if (!box["size"]) f.fail(box, "missing key 'size' in " + name);
  const Vec2 center = f.point(box["center"], name + ".center", kCoordinateLimit);
  const Vec2 size = f.point(box["size"], name + ".size", 100.0);
  if (size.minCoeff() < kMinFeatureSize) f.fail(box["size"], name + ".size: both sides must be at least 5 mm");
  const double angle = deg2rad(f.number(box, "angle_deg", name, 0.0, -360.0, 360.0));
  const Material material = box["material"] ? parseMaterial(f, box["material"], name + ".material") : Material::Wall;
  world.addBox(center, size, angle, material, f.text(box, "name", name, name), box.Mark().line + 1);
}

WorldPath parsePath(const YamlFields& f, const YAML::Node& node) {
  f.requireMap(node, "path", {"waypoints", "loop"});
  WorldPath path;
  path.loop = f.boolean(node, "loop", "path", false);
  const YAML::Node wps = node["waypoints"];
  if (!wps) f.fail(node, "missing key 'waypoints' in path");
  f.requireSequence(wps, "path.waypoints");
  if (wps.size() < 1) f.fail(wps, "path.waypoints: needs at least one waypoint");
  for (size_t i = 0; i < wps.size(); ++i) {
    path.waypoints.push_back(f.point(wps[i], "path.waypoints[" + std::to_string(i) + "]", kCoordinateLimit));
    if (i > 0 && (path.waypoints[i] - path.waypoints[i - 1]).norm() < 1e-3)
      f.fail(wps[i], "path.waypoints[" + std::to_string(i) + "]: repeats the previous waypoint");
  }
  if (path.loop && path.waypoints.size() < 2) f.fail(wps, "path: a looping path needs at least 2 waypoints");
  return path;
}

/// Walls enclose a point when a ray in every one of 16 directions meets one (every wall stops sound).
bool enclosedByWalls(const World& world, const Vec2& p) {
  const double reach = 2.0 * (world.boundsMax() - world.boundsMin()).norm() + 1.0;
  constexpr int kDirections = 16;
  for (int k = 0; k < kDirections; ++k)
    if (!world.castRay(p, 2.0 * std::numbers::pi * k / kDirections, reach, Sensor::Sonar).hit) return false;
  return true;
}

std::string formatPoint(const Vec2& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ")";
  return s.str();
}

/// The simulated robot drives straight from the start through each waypoint: none of that may
/// leave the walls or pass through one.
void checkStartAndPath(const YamlFields& f, const YAML::Node& root, const World& world) {
  if (world.start && !enclosedByWalls(world, world.start->translation()))
    f.fail(root["start"], "start: " + formatPoint(world.start->translation()) + " is outside the walls");
  const auto& wps = world.path.waypoints;
  for (size_t i = 0; i < wps.size(); ++i) {
    const YAML::Node at = root["path"]["waypoints"][i];
    const std::string name = "path.waypoints[" + std::to_string(i) + "]";
    if (!enclosedByWalls(world, wps[i])) f.fail(at, name + ": " + formatPoint(wps[i]) + " is outside the walls");
    const bool first_leg = i == 0;
    if (first_leg && !world.start) continue;
    const Vec2 from = first_leg ? world.start->translation() : wps[i - 1];
    if ((from - wps[i]).norm() > 1e-9 && !world.lineOfSight(from, wps[i], Sensor::Sonar, 0.0))
      f.fail(at, name + ": the way there from " + formatPoint(from) + " passes through a wall");
  }
}

}  // namespace

World loadWorld(const std::string& yaml_path) {
  const YamlFields f(yaml_path);
  const YAML::Node& root = f.root();
  f.requireMap(root, "world", {"name", "description", "walls", "boxes", "start", "path"});
  World world;
  world.source = yaml_path;
  world.name = f.text(root, "name", "world", "");
  const YAML::Node walls = root["walls"];
  if (!walls) f.fail(root, "missing key 'walls' (the list of wall polylines)");
  f.requireSequence(walls, "walls");
  if (walls.size() == 0) f.fail(walls, "walls: the world needs at least one wall");
  for (size_t i = 0; i < walls.size(); ++i) parseWall(f, walls[i], i, world);
  if (const YAML::Node boxes = root["boxes"]) {
    f.requireSequence(boxes, "boxes");
    for (size_t i = 0; i < boxes.size(); ++i) parseBox(f, boxes[i], i, world);
  }
  if (const YAML::Node start = root["start"]) world.start = f.pose(start, "start", kCoordinateLimit);
  if (const YAML::Node path = root["path"]) world.path = parsePath(f, path);
  checkStartAndPath(f, root, world);
  return world;
}

}  // namespace polarslam
