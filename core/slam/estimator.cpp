#include "slam/estimator.hpp"

namespace polarslam {

void OdometryEstimator::onOdometry(const OdometryReading& odometry) {
  if (!started_) {
    origin_inverse_ = odometry.pose.inverse();
    started_ = true;
  }
  trajectory_.push_back({odometry.utime, origin_inverse_ * odometry.pose, odometry.cov});
}

void RecordedEstimator::onPose(const PoseStamped& pose) {
  if (!trajectory_.empty() && pose.utime <= trajectory_.back().utime) {
    ++out_of_order_;
    return;
  }
  trajectory_.push_back(pose);
}

void RecordedEstimator::finish(const std::string&, nlohmann::json& report) {
  report["recorded"] = {{"poses", trajectory_.size()}, {"out_of_order_dropped", out_of_order_}};
}

}  // namespace polarslam
