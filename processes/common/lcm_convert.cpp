#include "common/lcm_convert.hpp"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace polarslam {
namespace {

template <typename Vec>
bool countMatches(const Vec& v, int32_t n) { return n >= 0 && static_cast<size_t>(n) == v.size(); }

bool finite(std::initializer_list<double> values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}
template <int N>
bool finiteMatrix(const double* m) {
  for (int i = 0; i < N * N; ++i)
    if (!std::isfinite(m[i])) return false;
  return true;
}

Pose2 poseFrom(const double p[3]) { return {p[0], p[1], p[2]}; }
void poseTo(const Pose2& p, double out[3]) { out[0] = p.x; out[1] = p.y; out[2] = p.theta; }

}  // namespace

polarslam::laser_scan_t toLcm(const LaserScan& scan) {
  polarslam::laser_scan_t msg;
  msg.utime = scan.utime;
  msg.seq = scan.seq;
  msg.angle_min = scan.angle_min;
  msg.angle_increment = scan.angle_increment;
  msg.time_increment = scan.time_increment;
  msg.range_max = scan.range_max;
  poseTo(scan.laser_pose, msg.laser_pose);
  msg.num_ranges = static_cast<int32_t>(scan.ranges.size());
  msg.ranges = scan.ranges;
  return msg;
}

std::string fromLcm(const polarslam::laser_scan_t& msg, LaserScan& out) {
  if (!countMatches(msg.ranges, msg.num_ranges)) return "laser: num_ranges disagrees with ranges";
  if (!finite({msg.laser_pose[0], msg.laser_pose[1], msg.laser_pose[2]})) return "laser: non-finite laser_pose";
  out.utime = msg.utime;
  out.seq = msg.seq;
  out.angle_min = msg.angle_min;
  out.angle_increment = msg.angle_increment;
  out.time_increment = msg.time_increment;
  out.range_max = msg.range_max;
  out.laser_pose = poseFrom(msg.laser_pose);
  out.ranges = msg.ranges;
  const std::string why = validateScan(out);
  return why.empty() ? why : "laser: " + why;
}

polarslam::odometry_t toLcm(const OdometryReading& odo) {
  polarslam::odometry_t msg;
  msg.utime = odo.utime;
  msg.seq = odo.seq;
  msg.x = odo.pose.x;
  msg.y = odo.pose.y;
  msg.theta = odo.pose.theta;
  copyMatrix<3>(odo.cov, msg.cov);
  msg.left_travel = odo.left_travel;
  msg.right_travel = odo.right_travel;
  msg.v = odo.v;
  msg.omega = odo.omega;
  return msg;
}

std::string fromLcm(const polarslam::odometry_t& msg, OdometryReading& out) {
  if (!finite({msg.x, msg.y, msg.theta, msg.left_travel, msg.right_travel, msg.v, msg.omega}) ||
      !finiteMatrix<3>(msg.cov))
    return "odometry: non-finite value";
  if (std::abs(msg.x) > 1e6 || std::abs(msg.y) > 1e6) return "odometry: absurd position";
  out.utime = msg.utime;
  out.seq = msg.seq;
  out.pose = {msg.x, msg.y, wrapAngle(msg.theta)};
  out.cov = readMatrix<3>(msg.cov);
  out.left_travel = msg.left_travel;
  out.right_travel = msg.right_travel;
  out.v = msg.v;
  out.omega = msg.omega;
  return {};
}

polarslam::sonar_targets_t toLcm(const SonarScan& scan) {
  polarslam::sonar_targets_t msg;
  msg.utime = scan.utime;
  msg.seq = scan.seq;
  msg.sensor_id = scan.sensor_id;
  poseTo(scan.sensor_pose, msg.sensor_pose);
  msg.range_max = scan.range_max;
  msg.field_of_view = scan.field_of_view;
  msg.num_targets = static_cast<int32_t>(scan.targets.size());
  for (const SonarTarget& t : scan.targets) {
    polarslam::sonar_target_t m;
    m.kind = static_cast<int8_t>(t.kind);
    m.range = t.range;
    m.bearing = t.bearing;
    copyMatrix<2>(t.cov, m.cov);
    msg.targets.push_back(m);
  }
  return msg;
}

std::string fromLcm(const polarslam::sonar_targets_t& msg, SonarScan& out) {
  if (!countMatches(msg.targets, msg.num_targets)) return "sonar: num_targets disagrees with targets";
  if (msg.targets.size() > 1000) return "sonar: too many targets";
  if (!finite({msg.sensor_pose[0], msg.sensor_pose[1], msg.sensor_pose[2], msg.range_max, msg.field_of_view}))
    return "sonar: non-finite header";
  out.utime = msg.utime;
  out.seq = msg.seq;
  out.sensor_id = msg.sensor_id;
  out.sensor_pose = poseFrom(msg.sensor_pose);
  out.range_max = msg.range_max;
  out.field_of_view = msg.field_of_view;
  out.targets.clear();
  for (const auto& m : msg.targets) {
    if (m.kind < 0 || m.kind > 3) return "sonar: unknown target kind";
    if (!finite({m.range, m.bearing}) || !finiteMatrix<2>(m.cov)) return "sonar: non-finite target";
    if (m.range < 0.0) return "sonar: negative range";
    SonarTarget t;
    t.kind = static_cast<SonarKind>(m.kind);
    t.range = m.range;
    t.bearing = m.bearing;
    t.cov = readMatrix<2>(m.cov);
    out.targets.push_back(t);
  }
  return {};
}

polarslam::pose_t toLcm(const PoseStamped& pose, const std::string& frame, int64_t seq) {
  polarslam::pose_t msg;
  msg.utime = pose.utime;
  msg.seq = seq;
  msg.frame = frame;
  msg.x = pose.pose.x;
  msg.y = pose.pose.y;
  msg.theta = pose.pose.theta;
  copyMatrix<3>(pose.cov, msg.cov);
  return msg;
}

std::string fromLcm(const polarslam::pose_t& msg, PoseStamped& out) {
  if (!finite({msg.x, msg.y, msg.theta}) || !finiteMatrix<3>(msg.cov)) return "pose: non-finite value";
  if (std::abs(msg.x) > 1e6 || std::abs(msg.y) > 1e6) return "pose: absurd position";
  out.utime = msg.utime;
  out.pose = {msg.x, msg.y, wrapAngle(msg.theta)};
  out.cov = readMatrix<3>(msg.cov);
  return {};
}

polarslam::features_t toLcm(const FeatureSet& f) {
  polarslam::features_t msg;
  msg.utime = f.utime;
  msg.seq = f.seq;
  msg.frame = f.frame;
  poseTo(f.sensor_pose, msg.sensor_pose);
  for (const LineFeature& l : f.lines) {
    polarslam::line_feature_t m;
    m.source = static_cast<int8_t>(l.source);
    m.alpha = l.alpha;
    m.d = l.d;
    copyMatrix<2>(l.cov, m.cov);
    copyMatrix<2>(l.random_cov, m.random_cov);
    m.systematic_bound[0] = l.systematic_bound.x();
    m.systematic_bound[1] = l.systematic_bound.y();
    m.endpoints[0] = l.endpoint_a.x();
    m.endpoints[1] = l.endpoint_a.y();
    m.endpoints[2] = l.endpoint_b.x();
    m.endpoints[3] = l.endpoint_b.y();
    m.num_points = l.num_points;
    msg.lines.push_back(m);
  }
  for (const CornerFeature& c : f.corners) {
    polarslam::corner_feature_t m;
    m.source = static_cast<int8_t>(c.source);
    m.convex = c.convex;
    m.x = c.x;
    m.y = c.y;
    m.gamma = c.gamma;
    copyMatrix<3>(c.cov, m.cov);
    m.num_points = c.num_points;
    msg.corners.push_back(m);
  }
  for (const PointFeature& p : f.points) {
    polarslam::point_feature_t m;
    m.source = static_cast<int8_t>(p.source);
    m.x = p.x;
    m.y = p.y;
    copyMatrix<2>(p.cov, m.cov);
    msg.points.push_back(m);
  }
  msg.num_lines = static_cast<int32_t>(msg.lines.size());
  msg.num_corners = static_cast<int32_t>(msg.corners.size());
  msg.num_points = static_cast<int32_t>(msg.points.size());
  msg.num_rejected = f.num_rejected;
  msg.break_hints = f.break_hints;
  msg.num_break_hints = static_cast<int32_t>(msg.break_hints.size());
  return msg;
}

std::string fromLcm(const polarslam::features_t& msg, FeatureSet& out) {
  if (!countMatches(msg.lines, msg.num_lines) || !countMatches(msg.corners, msg.num_corners) ||
      !countMatches(msg.points, msg.num_points) || !countMatches(msg.break_hints, msg.num_break_hints))
    return "features: counts disagree with arrays";
  if (msg.break_hints.size() > 5000) return "features: too many break hints";
  for (double h : msg.break_hints)
    if (!std::isfinite(h)) return "features: non-finite break hint";
  if (msg.lines.size() + msg.corners.size() + msg.points.size() > 5000) return "features: too many features";
  out = FeatureSet{};
  out.utime = msg.utime;
  out.seq = msg.seq;
  out.frame = msg.frame;
  out.sensor_pose = poseFrom(msg.sensor_pose);
  out.num_rejected = msg.num_rejected;
  out.break_hints = msg.break_hints;
  auto sourceOf = [](int8_t s) { return static_cast<FeatureSource>(s < 0 || s > 2 ? 0 : s); };
  for (const auto& m : msg.lines) {
    if (!finite({m.alpha, m.d}) || !finiteMatrix<2>(m.cov)) return "features: non-finite line";
    LineFeature l;
    l.source = sourceOf(m.source);
    l.alpha = m.alpha;
    l.d = m.d;
    l.cov = readMatrix<2>(m.cov);
    l.random_cov = readMatrix<2>(m.random_cov);
    l.systematic_bound = {m.systematic_bound[0], m.systematic_bound[1]};
    l.endpoint_a = {m.endpoints[0], m.endpoints[1]};
    l.endpoint_b = {m.endpoints[2], m.endpoints[3]};
    l.num_points = m.num_points;
    out.lines.push_back(l);
  }
  for (const auto& m : msg.corners) {
    if (!finite({m.x, m.y, m.gamma}) || !finiteMatrix<3>(m.cov)) return "features: non-finite corner";
    CornerFeature c;
    c.source = sourceOf(m.source);
    c.convex = m.convex;
    c.x = m.x;
    c.y = m.y;
    c.gamma = m.gamma;
    c.cov = readMatrix<3>(m.cov);
    c.num_points = m.num_points;
    out.corners.push_back(c);
  }
  for (const auto& m : msg.points) {
    if (!finite({m.x, m.y}) || !finiteMatrix<2>(m.cov)) return "features: non-finite point";
    PointFeature p;
    p.source = sourceOf(m.source);
    p.x = m.x;
    p.y = m.y;
    p.cov = readMatrix<2>(m.cov);
    out.points.push_back(p);
  }
  return {};
}

namespace {

bool validKind(int8_t kind) { return kind >= 0 && kind <= 2; }

}  // namespace

polarslam::slam_map_t toLcm(const FeatureMap& map, int64_t seq) {
  polarslam::slam_map_t msg;
  msg.utime = map.utime;
  msg.seq = seq;
  msg.robot = toLcm(map.robot, "map", seq);
  for (const MapFeature& f : map.features) {
    polarslam::map_feature_t m;
    m.id = f.id;
    m.kind = static_cast<int8_t>(f.kind);
    m.num_params = static_cast<int8_t>(parameterCount(f.kind));
    for (int i = 0; i < 3; ++i) m.params[i] = f.params(i);
    copyMatrix<3>(f.cov, m.cov);
    m.endpoints[0] = f.endpoint_a.x();
    m.endpoints[1] = f.endpoint_a.y();
    m.endpoints[2] = f.endpoint_b.x();
    m.endpoints[3] = f.endpoint_b.y();
    m.observations = f.observations;
    msg.features.push_back(m);
  }
  msg.num_features = static_cast<int32_t>(msg.features.size());
  return msg;
}

std::string fromLcm(const polarslam::slam_map_t& msg, FeatureMap& out) {
  if (!countMatches(msg.features, msg.num_features)) return "slam map: num_features disagrees with features";
  if (msg.features.size() > 1000000) return "slam map: too many features";
  FeatureMap map;
  map.utime = msg.utime;
  if (const std::string why = fromLcm(msg.robot, map.robot); !why.empty()) return "slam map: robot " + why;
  for (const auto& m : msg.features) {
    if (!validKind(m.kind)) return "slam map: unknown feature kind";
    if (!finite({m.params[0], m.params[1], m.params[2], m.endpoints[0], m.endpoints[1], m.endpoints[2],
                 m.endpoints[3]}) ||
        !finiteMatrix<3>(m.cov))
      return "slam map: non-finite feature";
    MapFeature f;
    f.id = m.id;
    f.kind = static_cast<MapFeatureKind>(m.kind);
    f.params = {m.params[0], m.params[1], m.params[2]};
    f.cov = readMatrix<3>(m.cov);
    f.endpoint_a = {m.endpoints[0], m.endpoints[1]};
    f.endpoint_b = {m.endpoints[2], m.endpoints[3]};
    f.observations = m.observations;
    map.features.push_back(f);
  }
  out = std::move(map);
  return {};
}

polarslam::scan_anchors_t toLcm(const ScanAnchors& anchors, int64_t seq) {
  polarslam::scan_anchors_t msg;
  msg.utime = anchors.utime;
  msg.seq = seq;
  msg.pose = toLcm(anchors.pose, "map", seq);
  for (const AnchorObservation& a : anchors.anchors) {
    polarslam::anchor_observation_t m;
    m.feature_id = a.feature_id;
    m.kind = static_cast<int8_t>(a.kind);
    for (int i = 0; i < 3; ++i) m.z[i] = a.z(i);
    copyMatrix<3>(a.cov, m.cov);
    msg.anchors.push_back(m);
  }
  msg.num_anchors = static_cast<int32_t>(msg.anchors.size());
  return msg;
}

std::string fromLcm(const polarslam::scan_anchors_t& msg, ScanAnchors& out) {
  if (!countMatches(msg.anchors, msg.num_anchors)) return "scan anchors: num_anchors disagrees with anchors";
  if (msg.anchors.size() > 100000) return "scan anchors: too many anchors";
  ScanAnchors anchors;
  anchors.utime = msg.utime;
  if (const std::string why = fromLcm(msg.pose, anchors.pose); !why.empty()) return "scan anchors: pose " + why;
  for (const auto& m : msg.anchors) {
    if (!validKind(m.kind)) return "scan anchors: unknown feature kind";
    if (!finite({m.z[0], m.z[1], m.z[2]}) || !finiteMatrix<3>(m.cov)) return "scan anchors: non-finite anchor";
    AnchorObservation a;
    a.feature_id = m.feature_id;
    a.kind = static_cast<MapFeatureKind>(m.kind);
    a.z = {m.z[0], m.z[1], m.z[2]};
    a.cov = readMatrix<3>(m.cov);
    anchors.anchors.push_back(a);
  }
  out = std::move(anchors);
  return {};
}

namespace {

constexpr int8_t kUnknownCell = -1;

uint8_t cellOf(float probability) {
  if (std::isnan(probability)) return static_cast<uint8_t>(kUnknownCell);
  return static_cast<uint8_t>(std::lround(std::clamp(100.0 * probability, 0.0, 100.0)));
}

std::vector<uint8_t> deflateCells(const std::vector<uint8_t>& cells) {
  uLongf size = compressBound(static_cast<uLong>(cells.size()));
  std::vector<uint8_t> out(size);
  // Fastest level: grids are mostly long runs of equal cells, which it already squeezes well.
  if (compress2(out.data(), &size, cells.data(), static_cast<uLong>(cells.size()), Z_BEST_SPEED) != Z_OK)
    throw std::runtime_error("grid map: zlib compression failed");
  out.resize(size);
  return out;
}

/// Inflates `data` into exactly `count` cells; the reason when it is not such a zlib stream.
std::string inflateCells(const std::vector<uint8_t>& data, size_t count, std::vector<uint8_t>& cells) {
  cells.assign(std::max<size_t>(count, 1), 0);
  uLongf produced = count;
  uLong consumed = static_cast<uLong>(data.size());
  const int status = uncompress2(cells.data(), &produced, data.data(), &consumed);
  if (status == Z_BUF_ERROR) return "grid map: zlib data inflates to more than width*height cells";
  if (status == Z_MEM_ERROR) return "grid map: out of memory inflating the cells";
  if (status != Z_OK) return "grid map: bad zlib data (corrupt or truncated)";
  if (produced != count) return "grid map: zlib data inflates to fewer than width*height cells";
  if (consumed != data.size()) return "grid map: bytes after the end of the zlib stream";
  cells.resize(count);
  return {};
}

std::string checkGridHeader(const polarslam::grid_map_t& msg) {
  if (!countMatches(msg.data, msg.num_bytes)) return "grid map: num_bytes disagrees with data";
  if (!std::isfinite(msg.resolution) || !(msg.resolution > 0.0)) return "grid map: resolution must be finite and positive";
  if (!finite({msg.origin[0], msg.origin[1], msg.origin[2]})) return "grid map: non-finite origin";
  if (msg.origin[2] != 0.0) return "grid map: rotated grids (origin yaw != 0) are not supported";
  if (msg.width < 0 || msg.height < 0) return "grid map: negative width or height";
  if ((msg.width == 0) != (msg.height == 0)) return "grid map: width and height must both be zero or both positive";
  if (int64_t{msg.width} * msg.height > kMaxGridMapCells)
    return "grid map: " + std::to_string(msg.width) + " x " + std::to_string(msg.height) + " cells, more than the " +
           std::to_string(kMaxGridMapCells) + " accepted";
  return {};
}

}  // namespace

polarslam::grid_map_t toLcmGridMap(const GridSlice& slice, int64_t utime, int64_t seq, const std::string& source,
                                   int scans, bool compress) {
  polarslam::grid_map_t msg;
  msg.utime = utime;
  msg.seq = seq;
  msg.frame = "map";
  msg.resolution = slice.resolution;
  msg.origin[0] = slice.origin.x();
  msg.origin[1] = slice.origin.y();
  msg.origin[2] = 0.0;
  msg.width = slice.width;
  msg.height = slice.height;
  msg.scans = scans;
  msg.source = source;
  std::vector<uint8_t> cells(slice.probability.size());
  std::transform(slice.probability.begin(), slice.probability.end(), cells.begin(), cellOf);
  msg.encoding = compress ? polarslam::grid_map_t::ENCODING_ZLIB : polarslam::grid_map_t::ENCODING_RAW;
  msg.data = compress ? deflateCells(cells) : std::move(cells);
  msg.num_bytes = static_cast<int32_t>(msg.data.size());
  return msg;
}

std::string fromLcm(const polarslam::grid_map_t& msg, GridSlice& out) {
  if (std::string why = checkGridHeader(msg); !why.empty()) return why;
  const auto count = static_cast<size_t>(int64_t{msg.width} * msg.height);
  std::vector<uint8_t> inflated;
  const std::vector<uint8_t>* cells = &msg.data;
  if (msg.encoding == polarslam::grid_map_t::ENCODING_ZLIB) {
    if (std::string why = inflateCells(msg.data, count, inflated); !why.empty()) return why;
    cells = &inflated;
  } else if (msg.encoding != polarslam::grid_map_t::ENCODING_RAW) {
    return "grid map: unknown encoding " + std::to_string(msg.encoding);
  } else if (msg.data.size() != count) {
    return "grid map: " + std::to_string(msg.data.size()) + " bytes for " + std::to_string(count) + " cells";
  }
  GridSlice slice;
  slice.resolution = msg.resolution;
  slice.origin = Vec2(msg.origin[0], msg.origin[1]);
  slice.width = msg.width;
  slice.height = msg.height;
  slice.probability.resize(count);
  for (size_t i = 0; i < count; ++i) {
    const auto value = static_cast<int8_t>((*cells)[i]);
    if (value < kUnknownCell || value > 100) return "grid map: cell value " + std::to_string(value) + " outside -1..100";
    slice.probability[i] = value == kUnknownCell ? std::numeric_limits<float>::quiet_NaN() : 0.01f * value;
  }
  out = std::move(slice);
  return {};
}

}  // namespace polarslam
