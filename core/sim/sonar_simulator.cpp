#include "sim/sonar_simulator.hpp"

#include <algorithm>
#include <cmath>

namespace polarslam {
namespace {

constexpr double kOcclusionTolerance = 1e-3;  // m: surfaces this close to the target do not hide it
constexpr int kKinds = 4;

struct Polar {
  double range = 0.0, bearing = 0.0;
};

Polar inArrayFrame(const Pose2& array_pose, const Vec2& point) {
  const Vec2 local = array_pose.inverseTransform(point);
  return {local.norm(), std::atan2(local.y(), local.x())};
}

bool inView(const SonarConfig& c, const Polar& p) {
  return p.range >= c.range_min && p.range <= c.range_max && std::abs(p.bearing) <= 0.5 * c.fov;
}

/// Plane echo from segment s: the foot of the perpendicular must lie on the segment.
bool planeTarget(const World& world, const SonarConfig& c, const Pose2& array_pose, int s, TrueSonarTarget& out) {
  const WallSegment& seg = world.segments()[static_cast<size_t>(s)];
  if (!returnsEcho(seg.material, Sensor::Sonar)) return false;
  const Vec2 origin = array_pose.translation(), e = seg.b - seg.a;
  const double u = (origin - seg.a).dot(e) / e.squaredNorm();
  if (u < 0.0 || u > 1.0) return false;
  const Vec2 foot = seg.a + u * e;
  const Polar p = inArrayFrame(array_pose, foot);
  if (!inView(c, p) || !world.lineOfSight(origin, foot, Sensor::Sonar, kOcclusionTolerance)) return false;
  out = {SonarKind::Plane, p.range, p.bearing, s, -1};
  return true;
}

bool vertexTarget(const World& world, const SonarConfig& c, const Pose2& array_pose, int v, TrueSonarTarget& out) {
  const WorldVertex& vertex = world.vertices()[static_cast<size_t>(v)];
  const Vec2 origin = array_pose.translation();
  const Polar p = inArrayFrame(array_pose, vertex.position);
  if (!inView(c, p)) return false;
  const VertexAppearance look = world.vertexAppearance(vertex, origin, c.right_angle_tolerance);
  SonarKind kind;
  if (look == VertexAppearance::RightAngleCorner) kind = SonarKind::Corner;
  else if (look == VertexAppearance::Edge) kind = SonarKind::Edge;
  else return false;
  for (int s : world.wedgeSegments(vertex, origin))
    if (!returnsEcho(world.segments()[static_cast<size_t>(s)].material, Sensor::Sonar)) return false;
  if (!world.lineOfSight(origin, vertex.position, Sensor::Sonar, kOcclusionTolerance)) return false;
  out = {kind, p.range, p.bearing, -1, v};
  return true;
}

}  // namespace

SonarSimulator::SonarSimulator(const SonarConfig& config, uint64_t seed) : config_(config), rng_(seed) {}

std::vector<TrueSonarTarget> SonarSimulator::visibleTargets(const World& world, const SonarConfig& config,
                                                            const Pose2& array_pose) {
  std::vector<TrueSonarTarget> targets;
  TrueSonarTarget t;
  for (int s = 0; s < static_cast<int>(world.segments().size()); ++s)
    if (planeTarget(world, config, array_pose, s, t)) targets.push_back(t);
  for (int v = 0; v < static_cast<int>(world.vertices().size()); ++v)
    if (vertexTarget(world, config, array_pose, v, t)) targets.push_back(t);
  std::stable_sort(targets.begin(), targets.end(),
                   [](const TrueSonarTarget& a, const TrueSonarTarget& b) { return a.range < b.range; });
  return targets;
}

SonarKind SonarSimulator::otherKind(SonarKind kind) {
  const int shift = 1 + rng_.uniformInt(kKinds - 1);
  return static_cast<SonarKind>((static_cast<int>(kind) + shift) % kKinds);
}

SonarTarget SonarSimulator::measure(const TrueSonarTarget& truth) {
  SonarTarget t;
  t.kind = rng_.bernoulli(config_.misclassification_rate) ? otherKind(truth.kind) : truth.kind;
  t.range = rng_.normal(truth.range, config_.range_sigma);
  t.bearing = wrapAngle(rng_.normal(truth.bearing, config_.bearing_sigma));
  t.cov = Vec2(config_.range_sigma * config_.range_sigma, config_.bearing_sigma * config_.bearing_sigma).asDiagonal();
  return t;
}

SonarTarget SonarSimulator::spuriousTarget() {
  SonarTarget t;
  t.kind = static_cast<SonarKind>(rng_.uniformInt(kKinds));
  t.range = rng_.uniform(config_.range_min, config_.range_max);
  t.bearing = rng_.uniform(-0.5 * config_.fov, 0.5 * config_.fov);
  t.cov = Vec2(config_.range_sigma * config_.range_sigma, config_.bearing_sigma * config_.bearing_sigma).asDiagonal();
  return t;
}

SonarScan SonarSimulator::scan(const World& world, int64_t utime, const Pose2& robot_pose) {
  SonarScan out;
  out.utime = utime;
  out.seq = seq_++;
  out.sensor_id = config_.id;
  out.sensor_pose = config_.mount;
  out.range_max = config_.range_max;
  out.field_of_view = config_.fov;
  for (const TrueSonarTarget& truth : visibleTargets(world, config_, robot_pose * config_.mount)) {
    if (rng_.bernoulli(config_.miss_rate)) continue;
    out.targets.push_back(measure(truth));
  }
  const int spurious = rng_.poisson(config_.spurious_rate);
  for (int i = 0; i < spurious; ++i) out.targets.push_back(spuriousTarget());
  std::stable_sort(out.targets.begin(), out.targets.end(),
                   [](const SonarTarget& a, const SonarTarget& b) { return a.range < b.range; });
  return out;
}

}  // namespace polarslam
