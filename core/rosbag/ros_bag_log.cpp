#include "rosbag/ros_bag_log.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include "rosbag/ros_bag_records.hpp"

namespace polarslam {
namespace {

namespace records = rosbag_records;

/// The latest tf transform to each child frame: its parent and its pose in the parent.
class FrameTree {
 public:
  void add(const records::Transform& t) { parent_of_[t.child] = {t.parent, Pose2(t.x, t.y, t.yaw)}; }

  /// Pose of `frame` in `base`, walking up from `frame`; nullopt when `base` is not above it.
  std::optional<Pose2> poseIn(const std::string& base, std::string frame) const {
    Pose2 pose;
    for (size_t depth = 0; depth <= parent_of_.size() && frame != base; ++depth) {
      const auto it = parent_of_.find(frame);
      if (it == parent_of_.end()) return std::nullopt;
      pose = it->second.second * pose;
      frame = it->second.first;
    }
    if (frame != base) return std::nullopt;
    return pose;
  }

 private:
  std::map<std::string, std::pair<std::string, Pose2>> parent_of_;
};

LaserScan laserScanOf(const records::Scan& m, const Pose2& mount) {
  LaserScan scan;
  scan.utime = m.utime;
  scan.seq = m.seq;
  scan.angle_min = m.angle_min;
  scan.angle_increment = m.angle_increment;
  scan.time_increment = m.time_increment;
  scan.range_max = m.range_max;
  scan.laser_pose = mount;
  scan.ranges.reserve(m.ranges.size());
  for (float r : m.ranges)
    scan.ranges.push_back(std::isfinite(r) && r >= m.range_min && r <= m.range_max ? r
                                                                                   : std::numeric_limits<float>::infinity());
  return scan;
}

OdometryReading odometryOf(const records::Odometry& m) {
  OdometryReading r;
  r.utime = m.utime;
  r.seq = m.seq;
  r.pose = Pose2(m.x, m.y, m.yaw);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.cov(i, j) = m.cov[i * 3 + j];
  r.v = m.v;
  r.omega = m.omega;
  return r;
}

/// A bag orders messages of equal time arbitrarily; odometry goes first, as in the CARMEN reader,
/// so that a consumer has the prior when the scan of the same time arrives.
void odometryFirstAtEqualTimes(std::vector<RangeLogEvent>& events) {
  for (size_t begin = 0; begin < events.size();) {
    size_t end = begin + 1;
    while (end < events.size() && events[end].utime() == events[begin].utime()) ++end;
    std::stable_partition(events.begin() + static_cast<std::ptrdiff_t>(begin),
                          events.begin() + static_cast<std::ptrdiff_t>(end),
                          [](const RangeLogEvent& e) { return !e.isLaser(); });
    begin = end;
  }
  for (size_t i = 0; i < events.size(); ++i) events[i].line = static_cast<int64_t>(i) + 1;
}

bool wanted(const std::string& topic, const std::string& only) { return only.empty() || topic == only; }

/// The first pass: the frame tree and the robot's frame (the odometry's child frame).
struct BagLayout {
  FrameTree frames;
  std::string base_frame;
  std::set<std::string> odometry_topics;
};

BagLayout readLayout(const std::string& path, const RosBagOptions& options) {
  BagLayout layout;
  records::Visitor visitor;
  visitor.transform = [&](const records::Transform& t) { layout.frames.add(t); };
  visitor.odometry = [&](const records::Odometry& o) {
    if (!wanted(o.topic, options.odometry_topic)) return;
    layout.base_frame = o.child_frame;
    layout.odometry_topics.insert(o.topic);
  };
  records::visitRosBag(path, visitor);
  if (layout.odometry_topics.size() > 1)
    throw std::runtime_error(path + ": several nav_msgs/Odometry topics; choose one (--odometry-topic)");
  return layout;
}

}  // namespace

bool looksLikeRosBag(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char header[13] = {0};
  in.read(header, 12);
  return std::string(header, static_cast<size_t>(in.gcount())) == "#ROSBAG V2.0";
}

RangeLog readRosBag(const std::string& path, const RosBagOptions& options) {
  if (!looksLikeRosBag(path)) throw std::runtime_error(path + ": not a ROS 1 bag (no '#ROSBAG V2.0' header)");
  const BagLayout layout = readLayout(path, options);
  RangeLog log;
  log.format = "rosbag";
  std::map<std::string, Pose2> mounts;
  auto mountOf = [&](const std::string& frame) {
    if (const auto known = mounts.find(frame); known != mounts.end()) return known->second;
    const std::string base = layout.base_frame.empty() ? "the robot" : layout.base_frame;
    const std::optional<Pose2> mount =
        layout.base_frame.empty() ? std::nullopt : layout.frames.poseIn(layout.base_frame, frame);
    log.notes.push_back(mount ? "laser frame '" + frame + "' placed on '" + base + "' by tf"
                              : "no tf from '" + base + "' to laser frame '" + frame + "': laser at the robot's origin");
    return mounts[frame] = mount.value_or(Pose2());
  };
  records::Visitor visitor;
  visitor.any = [&](const std::string& datatype) { ++log.line_kinds[datatype]; };
  visitor.scan = [&](const records::Scan& s) {
    if (wanted(s.topic, options.laser_topic))
      log.events.push_back({static_cast<int64_t>(log.events.size()) + 1, laserScanOf(s, mountOf(s.frame))});
  };
  visitor.odometry = [&](const records::Odometry& o) {
    if (wanted(o.topic, options.odometry_topic))
      log.events.push_back({static_cast<int64_t>(log.events.size()) + 1, odometryOf(o)});
  };
  records::visitRosBag(path, visitor);
  odometryFirstAtEqualTimes(log.events);
  log.lines = static_cast<int64_t>(log.events.size());
  if (log.laserCount() == 0)
    throw std::runtime_error(path + ": no sensor_msgs/LaserScan messages" +
                             (options.laser_topic.empty() ? std::string() : " on " + options.laser_topic));
  return log;
}

}  // namespace polarslam
