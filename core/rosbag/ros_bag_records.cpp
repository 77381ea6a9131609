#include "rosbag/ros_bag_records.hpp"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <stdexcept>

namespace polarslam::rosbag_records {
namespace {

int64_t utimeOf(const ros::Time& t) {
  return static_cast<int64_t>(t.sec) * 1'000'000 + static_cast<int64_t>(t.nsec) / 1000;
}

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

std::string withoutLeadingSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

Scan scanOf(const std::string& topic, const sensor_msgs::LaserScan& m) {
  return {topic,           withoutLeadingSlash(m.header.frame_id), utimeOf(m.header.stamp), m.header.seq, m.angle_min,
          m.angle_increment, m.time_increment, m.range_min, m.range_max, m.ranges};
}

Odometry odometryOf(const std::string& topic, const nav_msgs::Odometry& m) {
  Odometry o;
  o.topic = topic;
  o.child_frame = withoutLeadingSlash(m.child_frame_id);
  o.utime = utimeOf(m.header.stamp);
  o.seq = m.header.seq;
  o.x = m.pose.pose.position.x;
  o.y = m.pose.pose.position.y;
  o.yaw = yawOf(m.pose.pose.orientation);
  const int index[3] = {0, 1, 5};  // x, y, yaw of ROS's 6×6 (x, y, z, roll, pitch, yaw)
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) o.cov[i * 3 + j] = m.pose.covariance[static_cast<size_t>(index[i] * 6 + index[j])];
  o.v = m.twist.twist.linear.x;
  o.omega = m.twist.twist.angular.z;
  return o;
}

ros::Time timeOf(int64_t utime) {
  return ros::Time(static_cast<uint32_t>(utime / 1'000'000), static_cast<uint32_t>(utime % 1'000'000) * 1000);
}

geometry_msgs::Quaternion quaternionOf(double yaw) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(0.5 * yaw);
  q.w = std::cos(0.5 * yaw);
  return q;
}

}  // namespace

struct BagWriter::Bag {
  rosbag::Bag bag;
};

BagWriter::BagWriter(const std::string& path) : bag_(new Bag) {
  try {
    bag_->bag.open(path, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    delete bag_;
    throw std::runtime_error(path + ": cannot write the bag: " + e.what());
  }
}

BagWriter::~BagWriter() {
  bag_->bag.close();
  delete bag_;
}

void BagWriter::write(const Scan& s) {
  sensor_msgs::LaserScan m;
  m.header.stamp = timeOf(s.utime);
  m.header.seq = s.seq;
  m.header.frame_id = s.frame;
  m.angle_min = static_cast<float>(s.angle_min);
  m.angle_increment = static_cast<float>(s.angle_increment);
  m.angle_max = static_cast<float>(s.angle_min + s.angle_increment * static_cast<double>(s.ranges.size() - 1));
  m.time_increment = static_cast<float>(s.time_increment);
  m.range_min = static_cast<float>(s.range_min);
  m.range_max = static_cast<float>(s.range_max);
  m.ranges = s.ranges;
  bag_->bag.write(s.topic, m.header.stamp, m);
}

void BagWriter::write(const Odometry& o) {
  nav_msgs::Odometry m;
  m.header.stamp = timeOf(o.utime);
  m.header.seq = o.seq;
  m.header.frame_id = "odom";
  m.child_frame_id = o.child_frame;
  m.pose.pose.position.x = o.x;
  m.pose.pose.position.y = o.y;
  m.pose.pose.orientation = quaternionOf(o.yaw);
  const int index[3] = {0, 1, 5};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m.pose.covariance[static_cast<size_t>(index[i] * 6 + index[j])] = o.cov[i * 3 + j];
  m.twist.twist.linear.x = o.v;
  m.twist.twist.angular.z = o.omega;
  bag_->bag.write(o.topic, m.header.stamp, m);
}

void BagWriter::writeStatic(const Transform& t, int64_t utime) {
  tf2_msgs::TFMessage m;
  geometry_msgs::TransformStamped ts;
  ts.header.stamp = timeOf(utime);
  ts.header.frame_id = t.parent;
  ts.child_frame_id = t.child;
  ts.transform.translation.x = t.x;
  ts.transform.translation.y = t.y;
  ts.transform.rotation = quaternionOf(t.yaw);
  m.transforms.push_back(ts);
  bag_->bag.write("/tf_static", ts.header.stamp, m);
}

void visitRosBag(const std::string& path, const Visitor& visitor) {
  try {
    rosbag::Bag bag(path, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (visitor.any) visitor.any(m.getDataType());
      if (const auto scan = m.instantiate<sensor_msgs::LaserScan>()) {
        if (visitor.scan) visitor.scan(scanOf(m.getTopic(), *scan));
      } else if (const auto odometry = m.instantiate<nav_msgs::Odometry>()) {
        if (visitor.odometry) visitor.odometry(odometryOf(m.getTopic(), *odometry));
      } else if (const auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
        if (!visitor.transform) continue;
        for (const geometry_msgs::TransformStamped& t : tf->transforms)
          visitor.transform({withoutLeadingSlash(t.header.frame_id), withoutLeadingSlash(t.child_frame_id),
                             t.transform.translation.x, t.transform.translation.y, yawOf(t.transform.rotation)});
      }
    }
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error(path + ": cannot read the bag: " + e.what());
  }
}

}  // namespace polarslam::rosbag_records
