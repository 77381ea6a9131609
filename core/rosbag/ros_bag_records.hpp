#pragma once
// The messages of a ROS 1 bag that polarslam imports, as plain records. ros_bag_records.cpp is the
// only file that includes ROS's headers: their messages need C++17 (std::allocator<void>::rebind,
// which C++20 removed), so it is compiled as C++17 and this header is C++17 as well.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace polarslam::rosbag_records {

struct Scan {
  std::string topic, frame;
  int64_t utime = 0;
  uint32_t seq = 0;
  double angle_min = 0.0, angle_increment = 0.0, time_increment = 0.0, range_min = 0.0, range_max = 0.0;
  std::vector<float> ranges;
};

struct Odometry {
  std::string topic, child_frame;
  int64_t utime = 0;
  uint32_t seq = 0;
  double x = 0.0, y = 0.0, yaw = 0.0;
  double cov[9] = {};  ///< (x, y, yaw), row-major
  double v = 0.0, omega = 0.0;
};

struct Transform {
  std::string parent, child;
  double x = 0.0, y = 0.0, yaw = 0.0;
};

struct Visitor {
  std::function<void(const std::string& datatype)> any;
  std::function<void(const Scan&)> scan;
  std::function<void(const Odometry&)> odometry;
  std::function<void(const Transform&)> transform;
};

/// Every message of the bag in bag order; throws std::runtime_error naming the file on failure.
void visitRosBag(const std::string& path, const Visitor& visitor);

/// Writes a ROS 1 bag of these records (each stamped with its utime; transforms on /tf_static at
/// `static_utime`), as a robot's driver stack would record them: for tests and for tools.
class BagWriter {
 public:
  explicit BagWriter(const std::string& path);
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  void write(const Scan& scan);
  void write(const Odometry& odometry);
  void writeStatic(const Transform& transform, int64_t utime);

 private:
  struct Bag;
  Bag* bag_;
};

}  // namespace polarslam::rosbag_records
