#include "slam/estimator.hpp"

namespace polarslam {

void OdometryEstimator::onOdometry(const OdometryReading& odometry) {
  if (!started_) {
    origin_inverse_ = odometry.pose.inverse();
    started_ = true;
  }
  trajectory_.push_back({odometry.utime, origin_inverse_ * odometry.pose, odometry.cov});
}

}  // namespace polarslam
