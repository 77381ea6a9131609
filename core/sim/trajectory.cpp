#include "sim/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace polarslam {

Pose2 integrateArc(const Pose2& start, double v, double omega, double tau) {
  const double th = start.theta, dth = omega * tau;
  if (std::abs(dth) < 1e-9) {
    // Straight (second-order accurate in the tiny turn).
    const double mid = th + 0.5 * dth;
    return {start.x + v * tau * std::cos(mid), start.y + v * tau * std::sin(mid), wrapAngle(th + dth)};
  }
  const double r = v / omega;
  return {start.x + r * (std::sin(th + dth) - std::sin(th)), start.y - r * (std::cos(th + dth) - std::cos(th)),
          wrapAngle(th + dth)};
}

Trajectory::Trajectory(const Pose2& start, double wheel_base) : wheel_base_(wheel_base), end_pose_(start) {}

void Trajectory::append(int64_t duration_us, double v, double omega) {
  Period p;
  p.start_us = end_us_;
  p.duration_us = duration_us;
  p.pose = end_pose_;
  p.travel = end_travel_;
  p.v = v;
  p.omega = omega;
  periods_.push_back(p);
  const double dt = 1e-6 * static_cast<double>(duration_us);
  end_us_ += duration_us;
  end_pose_ = integrateArc(p.pose, v, omega, dt);
  end_travel_.left += (v - 0.5 * omega * wheel_base_) * dt;
  end_travel_.right += (v + 0.5 * omega * wheel_base_) * dt;
}

const Trajectory::Period* Trajectory::periodAt(double t, double& tau) const {
  if (periods_.empty()) {
    tau = 0.0;
    return nullptr;
  }
  const double t_us = t * 1e6;
  // Last period starting at or before t.
  auto it = std::upper_bound(periods_.begin(), periods_.end(), t_us,
                             [](double value, const Period& p) { return value < static_cast<double>(p.start_us); });
  if (it != periods_.begin()) --it;
  const double duration = 1e-6 * static_cast<double>(it->duration_us);
  tau = std::clamp(t - 1e-6 * static_cast<double>(it->start_us), 0.0, duration);
  return &*it;
}

Pose2 Trajectory::poseAt(double t) const {
  double tau = 0.0;
  const Period* p = periodAt(t, tau);
  if (!p) return end_pose_;
  return integrateArc(p->pose, p->v, p->omega, tau);
}

WheelTravel Trajectory::wheelTravelAt(double t) const {
  double tau = 0.0;
  const Period* p = periodAt(t, tau);
  if (!p) return end_travel_;
  return {p->travel.left + (p->v - 0.5 * p->omega * wheel_base_) * tau,
          p->travel.right + (p->v + 0.5 * p->omega * wheel_base_) * tau};
}

double Trajectory::speedAt(double t) const {
  double tau = 0.0;
  const Period* p = periodAt(t, tau);
  return p ? p->v : 0.0;
}

double Trajectory::turnRateAt(double t) const {
  double tau = 0.0;
  const Period* p = periodAt(t, tau);
  return p ? p->omega : 0.0;
}

void Trajectory::forgetBefore(double t) {
  const double t_us = t * 1e6;
  while (periods_.size() > 1 &&
         static_cast<double>(periods_.front().start_us + periods_.front().duration_us) < t_us)
    periods_.pop_front();
}

}  // namespace polarslam
