#include "sim/simulator.hpp"

#include <cmath>
#include <limits>
#include <memory>

#include "sim/laser_simulator.hpp"
#include "sim/odometry_simulator.hpp"
#include "sim/path_follower.hpp"
#include "sim/random.hpp"
#include "sim/sonar_simulator.hpp"
#include "sim/trajectory.hpp"

namespace polarslam {
namespace {

// Independent random streams, so that switching one sensor on or off leaves the others' noise alone.
enum Stream : uint64_t { kOdometryStream = 1, kLaserStream = 2, kFirstSonarStream = 16 };

int64_t periodMicros(double rate_hz) { return std::max<int64_t>(1, std::llround(1e6 / rate_hz)); }

Pose2 startPose(const World& world) {
  if (world.start) return *world.start;
  const auto& wp = world.path.waypoints;
  if (wp.empty()) return {};
  double heading = 0.0;
  if (wp.size() >= 2) heading = std::atan2(wp[1].y() - wp[0].y(), wp[1].x() - wp[0].x());
  return {wp[0].x(), wp[0].y(), heading};
}

}  // namespace

struct Simulator::Impl {
  /// Periodic events of one sensor, in µs since the start.
  struct Schedule {
    int64_t next_us = 0;
    int64_t period_us = 1;
  };

  Impl(World w, RobotDescription c, uint64_t seed)
      : world(std::move(w)),
        config(std::move(c)),
        trajectory(startPose(world), config.robot.wheel_base),
        follower(config.robot),
        odometry(config.odometry, config.robot, streamSeed(seed, kOdometryStream)),
        laser(config.laser, streamSeed(seed, kLaserStream)) {
    validate(config);
    for (size_t i = 0; i < config.sonars.size(); ++i)
      sonars.emplace_back(config.sonars[i], streamSeed(seed, kFirstSonarStream + i));
    follower.setPath(world.path.waypoints, world.path.loop);
    control_us = periodMicros(1.0 / config.robot.control_period);
    // Motion is simulated ahead of the emitted time by at least one laser scan's duration, so a
    // scan stamped at its first beam can be emitted in time order with every beam measured.
    const int64_t scan_us = config.laser.enabled ? std::llround(std::ceil(config.laser.scanDuration() * 1e6)) : 0;
    lead_us = (scan_us / control_us + 1) * control_us;
    odometry_schedule.period_us = periodMicros(config.odometry.rate);
    truth_schedule.period_us = periodMicros(config.ground_truth_rate);
    laser_schedule.period_us = periodMicros(config.laser.rate);
    for (const SonarConfig& s : config.sonars) sonar_schedules.push_back({0, periodMicros(s.rate)});
  }

  double seconds(int64_t us) const { return 1e-6 * static_cast<double>(us); }

  void simulateMotionUntil(int64_t until_us) {
    while (std::llround(trajectory.endTime() * 1e6) < until_us) {
      const VelocityCommand next = follower.update(trajectory.endPose(), command, seconds(control_us));
      trajectory.append(control_us, next.v, next.omega);
      command = next;
      const bool stopped = next.v == 0.0 && next.omega == 0.0;
      if (follower.finished() && stopped && stopped_at_us < 0) stopped_at_us = std::llround(trajectory.endTime() * 1e6);
    }
  }

  void emitOdometry(SimSink& sink, int64_t t_us) {
    const double dt = last_odometry_us < 0 ? 0.0 : seconds(t_us - last_odometry_us);
    last_odometry_us = t_us;
    sink.onOdometry(odometry.measure(config.start_utime + t_us, trajectory.wheelTravelAt(seconds(t_us)), dt));
  }

  void emitTruth(SimSink& sink, int64_t t_us) {
    PoseStamped truth;
    truth.utime = config.start_utime + t_us;
    truth.pose = trajectory.poseAt(seconds(t_us));
    sink.onGroundTruth(truth);
  }

  void emitLaser(SimSink& sink, int64_t t_us) {
    const double t0 = seconds(t_us);
    sink.onLaser(laser.scan(world, config.start_utime + t_us,
                            [&](double tau) { return trajectory.poseAt(t0 + tau); }));
  }

  void emitSonar(SimSink& sink, size_t i, int64_t t_us) {
    sink.onSonar(sonars[i].scan(world, config.start_utime + t_us, trajectory.poseAt(seconds(t_us))));
  }

  /// Emits every event due before `end_us`, in time order (ties: odometry, truth, laser, sonars).
  void emitEventsBefore(SimSink& sink, int64_t end_us) {
    while (true) {
      int64_t best_us = end_us;
      int which = -1;  // 0 odometry, 1 truth, 2 laser, 3 + i sonar i
      auto consider = [&](const Schedule& s, int id) {
        if (s.next_us < best_us) {
          best_us = s.next_us;
          which = id;
        }
      };
      consider(odometry_schedule, 0);
      consider(truth_schedule, 1);
      if (config.laser.enabled) consider(laser_schedule, 2);
      for (size_t i = 0; i < sonar_schedules.size(); ++i) consider(sonar_schedules[i], 3 + static_cast<int>(i));
      if (which < 0) return;
      switch (which) {
        case 0: emitOdometry(sink, best_us); odometry_schedule.next_us += odometry_schedule.period_us; break;
        case 1: emitTruth(sink, best_us); truth_schedule.next_us += truth_schedule.period_us; break;
        case 2: emitLaser(sink, best_us); laser_schedule.next_us += laser_schedule.period_us; break;
        default: {
          const size_t i = static_cast<size_t>(which - 3);
          emitSonar(sink, i, best_us);
          sonar_schedules[i].next_us += sonar_schedules[i].period_us;
        }
      }
    }
  }

  void step(SimSink& sink) {
    const int64_t end_us = now_us + control_us;
    simulateMotionUntil(end_us + lead_us);
    emitEventsBefore(sink, end_us);
    now_us = end_us;
    trajectory.forgetBefore(seconds(now_us) - 1.0);
  }

  World world;
  RobotDescription config;
  Trajectory trajectory;
  PathFollower follower;
  VelocityCommand command;
  OdometrySimulator odometry;
  LaserSimulator laser;
  std::vector<SonarSimulator> sonars;
  int64_t control_us = 10000;
  int64_t lead_us = 0;
  int64_t now_us = 0;            ///< events before this time (µs since start) have been emitted
  int64_t stopped_at_us = -1;    ///< when the robot came to rest at the end of its path
  int64_t last_odometry_us = -1;
  Schedule odometry_schedule, truth_schedule, laser_schedule;
  std::vector<Schedule> sonar_schedules;
};

Simulator::Simulator(World world, RobotDescription config, uint64_t seed)
    : impl_(new Impl(std::move(world), std::move(config), seed)) {}
Simulator::~Simulator() { delete impl_; }
Simulator::Simulator(Simulator&& other) noexcept : impl_(other.impl_) { other.impl_ = nullptr; }
Simulator& Simulator::operator=(Simulator&& other) noexcept {
  if (this != &other) {
    delete impl_;
    impl_ = other.impl_;
    other.impl_ = nullptr;
  }
  return *this;
}

void Simulator::step(SimSink& sink) { impl_->step(sink); }
double Simulator::time() const { return impl_->seconds(impl_->now_us); }
int64_t Simulator::utime() const { return impl_->config.start_utime + impl_->now_us; }
bool Simulator::finished() const {
  return impl_->stopped_at_us >= 0 && impl_->now_us >= impl_->stopped_at_us;
}
void Simulator::setPath(const std::vector<Vec2>& waypoints) {
  impl_->follower.setPath(waypoints, false);
  impl_->stopped_at_us = -1;
}
Pose2 Simulator::truePose() const { return impl_->trajectory.poseAt(time()); }
const World& Simulator::world() const { return impl_->world; }
const RobotDescription& Simulator::config() const { return impl_->config; }

}  // namespace polarslam
