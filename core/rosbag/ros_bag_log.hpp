#pragma once
// ROS 1 bags in (Debian's rosbag_storage): sensor_msgs/LaserScan, nav_msgs/Odometry and tf
// (tf2_msgs/TFMessage on /tf and /tf_static) become the same in-memory range log the other
// importers give (io/range_log.hpp), in bag order, stamped with the messages' header times.
//  - the laser's mount on the robot comes from tf: the transform from the odometry's child frame
//    (e.g. base_link) to the scan's frame (e.g. laser), through any chain of tf frames; without
//    one the laser sits at the robot's origin (and a note says so);
//  - ranges outside [range_min, range_max] or not finite are "no return";
//  - nav_msgs/Odometry gives the pose (x, y, yaw of the quaternion), its covariance and the twist.
#include <string>

#include "io/range_log.hpp"

namespace polarslam {

struct RosBagOptions {
  std::string laser_topic;     ///< "" = every sensor_msgs/LaserScan topic (there must be one)
  std::string odometry_topic;  ///< "" = every nav_msgs/Odometry topic (there must be at most one)
};

/// Whether the file starts with the ROS 1 bag header ("#ROSBAG V2.0").
bool looksLikeRosBag(const std::string& path);

/// Reads a ROS 1 bag. Throws std::runtime_error naming the file when it cannot be read, is not a
/// bag, or holds no laser scan.
RangeLog readRosBag(const std::string& path, const RosBagOptions& options = {});

}  // namespace polarslam
