#include "common/foxglove_messages.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

#include "geometry/chi_squared.hpp"

namespace polarslam::foxglove {
namespace {

using Json = nlohmann::json;

constexpr int kLineStrip = 0, kLineLoop = 1, kLineList = 2;
constexpr int kEllipseSegments = 24;
constexpr double kCornerArm = 0.3;  // m

Json point3(const Vec2& p) { return {{"x", p.x()}, {"y", p.y()}, {"z", 0.0}}; }
Json rgba(double r, double g, double b, double a) { return {{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }
Json identityPose() { return pose(Pose2()); }

Json linePrimitive(int type, const std::vector<Vec2>& points, const Json& color, double thickness) {
  Json pts = Json::array();
  for (const Vec2& p : points) pts.push_back(point3(p));
  return {{"type", type},         {"pose", identityPose()}, {"thickness", thickness}, {"scale_invariant", false},
          {"points", pts},        {"color", color},         {"colors", Json::array()}, {"indices", Json::array()}};
}

Json sphere(const Vec2& at, double diameter, const Json& color) {
  return {{"pose", pose(Pose2(at.x(), at.y(), 0.0))},
          {"size", {{"x", diameter}, {"y", diameter}, {"z", diameter}}},
          {"color", color}};
}

Json entity(const std::string& id, int64_t utime, Json lines, Json spheres) {
  return {{"timestamp", timestamp(utime)}, {"frame_id", "map"},          {"id", id},
          {"lifetime", {{"sec", 0}, {"nsec", 0}}}, {"frame_locked", false}, {"metadata", Json::array()},
          {"arrows", Json::array()},       {"cubes", Json::array()},     {"spheres", std::move(spheres)},
          {"cylinders", Json::array()},    {"lines", std::move(lines)},  {"triangles", Json::array()},
          {"texts", Json::array()},        {"models", Json::array()}};
}

Json sceneUpdate(Json entity) {
  return {{"deletions", Json::array()}, {"entities", Json::array({std::move(entity)})}};
}

/// The 95 % ellipse of a 2×2 position covariance as LINE_LIST segments appended to `out`.
void appendEllipse(const Vec2& centre, const Eigen::Matrix2d& cov, std::vector<Vec2>& out) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(0.5 * (cov + cov.transpose()));
  if (eigen.info() != Eigen::Success) return;
  const double scale = std::sqrt(chiSquaredQuantile(0.95, 2));
  const Eigen::Vector2d axes = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt() * scale;
  const Eigen::Matrix2d rotation = eigen.eigenvectors();
  auto at = [&](int k) {
    const double t = 2.0 * M_PI * k / kEllipseSegments;
    return Vec2(centre + rotation * Eigen::Vector2d(axes.x() * std::cos(t), axes.y() * std::sin(t)));
  };
  for (int k = 0; k < kEllipseSegments; ++k) {
    out.push_back(at(k));
    out.push_back(at(k + 1));
  }
}

/// A line's segment moved by ±2σ_d (95 %) along its normal: the band the wall may lie in.
void appendLineBand(const MapFeature& f, std::vector<Vec2>& out) {
  const double sigma_d = std::sqrt(std::max(f.cov(1, 1), 0.0));
  const Vec2 normal(std::cos(f.params.x()), std::sin(f.params.x()));
  for (const double side : {-2.0, 2.0}) {
    out.push_back(f.endpoint_a + side * sigma_d * normal);
    out.push_back(f.endpoint_b + side * sigma_d * normal);
  }
}

void appendCorner(const MapFeature& f, bool convex, std::vector<Vec2>& out) {
  const Vec2 apex(f.params.x(), f.params.y());
  // Walls run at ±45° from the bisector: into free space for a concave corner, behind it for a convex one.
  const double base = f.params.z() + (convex ? M_PI : 0.0);
  for (const double side : {-M_PI / 4.0, M_PI / 4.0}) {
    out.push_back(apex);
    out.push_back(apex + kCornerArm * Vec2(std::cos(base + side), std::sin(base + side)));
  }
}

}  // namespace

Json timestamp(int64_t utime) {
  if (utime < 0) utime = 0;
  return {{"sec", utime / 1000000}, {"nsec", (utime % 1000000) * 1000}};
}

Json pose(const Pose2& p) {
  return {{"position", {{"x", p.x}, {"y", p.y}, {"z", 0.0}}},
          {"orientation", {{"x", 0.0}, {"y", 0.0}, {"z", std::sin(p.theta / 2.0)}, {"w", std::cos(p.theta / 2.0)}}}};
}

std::string base64(const std::string& bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t chunk = 0;
    for (size_t k = 0; k < 3; ++k)
      chunk = (chunk << 8) | (k < n ? static_cast<uint8_t>(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(chunk >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

Json grid(const GridSlice& slice, int64_t utime, const std::string& frame) {
  std::string cells(slice.probability.size(), '\0');
  for (size_t i = 0; i < cells.size(); ++i) {
    const float p = slice.probability[i];
    cells[i] = static_cast<char>(std::isnan(p) ? -1 : static_cast<int>(std::lround(std::clamp(p, 0.0f, 1.0f) * 100.0f)));
  }
  return {{"timestamp", timestamp(utime)},
          {"frame_id", frame},
          {"pose", pose(Pose2(slice.origin.x(), slice.origin.y(), 0.0))},
          {"column_count", slice.width},
          {"cell_size", {{"x", slice.resolution}, {"y", slice.resolution}}},
          {"row_stride", slice.width},
          {"cell_stride", 1},
          {"fields", Json::array({{{"name", "occupancy"}, {"offset", 0}, {"type", 2}}})},
          {"data", base64(cells)}};
}

Json laserScan(const LaserScan& scan) {
  Json ranges = Json::array();
  for (size_t i = 0; i < scan.size(); ++i) ranges.push_back(scan.valid(i) ? static_cast<double>(scan.ranges[i]) : 0.0);
  const double last = scan.size() > 0 ? scan.bearing(scan.size() - 1) : scan.angle_min;
  return {{"timestamp", timestamp(scan.utime)}, {"frame_id", kLaserFrame}, {"pose", identityPose()},
          {"start_angle", scan.angle_min},      {"end_angle", last},       {"ranges", ranges},
          {"intensities", Json::array()}};
}

Json poseInFrame(const PoseStamped& p, const std::string& frame) {
  return {{"timestamp", timestamp(p.utime)}, {"frame_id", frame}, {"pose", pose(p.pose)}};
}

Json posesInFrame(const std::vector<Pose2>& poses, int64_t utime, const std::string& frame) {
  Json list = Json::array();
  for (const Pose2& p : poses) list.push_back(pose(p));
  return {{"timestamp", timestamp(utime)}, {"frame_id", frame}, {"poses", list}};
}

Json frameTransform(const Pose2& child_in_parent, int64_t utime, const std::string& parent, const std::string& child) {
  const Json p = pose(child_in_parent);
  return {{"timestamp", timestamp(utime)}, {"parent_frame_id", parent}, {"child_frame_id", child},
          {"translation", p["position"]}, {"rotation", p["orientation"]}};
}

Json featureMapScene(const FeatureMap& map) {
  std::vector<Vec2> segments, corners, ellipses, bands;
  Json spheres = Json::array();
  const Json point_colour = rgba(1.0, 0.55, 0.0, 1.0);
  for (const MapFeature& f : map.features) {
    switch (f.kind) {
      case MapFeatureKind::Line:
        segments.push_back(f.endpoint_a);
        segments.push_back(f.endpoint_b);
        appendLineBand(f, bands);
        break;
      case MapFeatureKind::Corner:
        // slam_map_t carries no convexity; an inside corner is the common case in a building.
        appendCorner(f, false, corners);
        appendEllipse(Vec2(f.params.x(), f.params.y()), f.cov.topLeftCorner<2, 2>(), ellipses);
        break;
      case MapFeatureKind::Point:
        spheres.push_back(sphere(Vec2(f.params.x(), f.params.y()), 0.1, point_colour));
        appendEllipse(Vec2(f.params.x(), f.params.y()), f.cov.topLeftCorner<2, 2>(), ellipses);
        break;
    }
  }
  Json lines = Json::array({linePrimitive(kLineList, segments, rgba(0.1, 0.4, 1.0, 1.0), 0.04),
                            linePrimitive(kLineList, corners, rgba(0.0, 0.7, 0.2, 1.0), 0.04),
                            linePrimitive(kLineList, ellipses, rgba(0.9, 0.1, 0.6, 0.9), 0.015),
                            linePrimitive(kLineList, bands, rgba(0.5, 0.5, 0.5, 0.6), 0.01)});
  return sceneUpdate(entity("slam_map", map.utime, std::move(lines), std::move(spheres)));
}

Json poseGraphScene(const PoseGraph& graph, int64_t utime) {
  Json spheres = Json::array();
  std::vector<Vec2> chain, loops, rejected, trail;
  const Json node_colour = rgba(0.2, 0.2, 0.2, 0.9);
  for (const PoseGraphNode& n : graph.nodes()) spheres.push_back(sphere(n.pose.translation(), 0.08, node_colour));
  for (const PoseGraphEdge& e : graph.edges()) {
    const long from = graph.indexOf(e.from), to = graph.indexOf(e.to);
    if (from < 0 || to < 0) continue;
    std::vector<Vec2>& out = !e.active ? rejected : e.kind == PoseGraphEdgeKind::Loop ? loops : chain;
    out.push_back(graph.nodes()[static_cast<size_t>(from)].pose.translation());
    out.push_back(graph.nodes()[static_cast<size_t>(to)].pose.translation());
  }
  Json lines = Json::array({linePrimitive(kLineList, chain, rgba(0.4, 0.4, 0.4, 0.8), 0.02),
                            linePrimitive(kLineList, loops, rgba(0.9, 0.1, 0.1, 1.0), 0.03),
                            linePrimitive(kLineList, rejected, rgba(0.9, 0.1, 0.1, 0.25), 0.02)});
  return sceneUpdate(entity("pose_graph", utime, std::move(lines), std::move(spheres)));
}

Json processLog(const ProcessState& s, const std::string& previous_state) {
  constexpr int kInfo = 2, kWarning = 3, kError = 4;
  const int level = s.state == "crashed" ? kError : s.state == "restarting" ? kWarning : kInfo;
  const std::string from = previous_state.empty() ? "(new)" : previous_state;
  return {{"timestamp", timestamp(s.utime)},
          {"level", level},
          {"message", s.name + "@" + s.host + " (pid " + std::to_string(s.pid) + "): " + from + " -> " + s.state},
          {"name", s.name},
          {"file", ""},
          {"line", 0}};
}

Json processStatus(const ProcessState& s) {
  auto finite = [](double x) { return std::isfinite(x) ? x : 0.0; };
  return {{"timestamp", timestamp(s.utime)}, {"name", s.name},
          {"host", s.host},                  {"pid", s.pid},
          {"state", s.state},                {"restarts", s.restarts},
          {"messages_handled", s.handled},   {"messages_rejected", s.rejected},
          {"messages_dropped", s.dropped},   {"cpu_percent", finite(s.cpu_percent)},
          {"rss_mb", finite(s.rss_mb)}};
}

std::string goalFromJson(const Json& payload, Vec2& position, double& theta) {
  const Json* p = &payload;
  if (payload.contains("pose") && payload["pose"].is_object()) p = &payload["pose"];
  if (p->contains("position") && (*p)["position"].is_object()) p = &(*p)["position"];
  else if (payload.contains("point") && payload["point"].is_object()) p = &payload["point"];
  auto finiteNumber = [](const Json& o, const char* key) {
    return o.contains(key) && o[key].is_number() && std::isfinite(o[key].get<double>());
  };
  if (!finiteNumber(*p, "x") || !finiteNumber(*p, "y")) return "goal: needs finite numbers x and y";
  position = Vec2((*p)["x"].get<double>(), (*p)["y"].get<double>());
  theta = finiteNumber(payload, "theta") ? payload["theta"].get<double>() : std::nan("");
  return {};
}

}  // namespace polarslam::foxglove
