#include "robot/robot_description.hpp"

#include <cmath>
#include <stdexcept>

#include "laser/laser_scan.hpp"
#include "config/yaml_fields.hpp"

namespace polarslam {
namespace {

constexpr double kMaxRate = 1000.0;       // Hz
constexpr double kMaxMountOffset = 5.0;   // m
constexpr double kMaxRange = 100.0;       // m

double degrees(const YamlFields& f, const YAML::Node& map, const char* key, const std::string& ctx,
               double fallback_rad, double lo_deg, double hi_deg) {
  return deg2rad(f.number(map, key, ctx, rad2deg(fallback_rad), lo_deg, hi_deg));
}

void readFollower(const YamlFields& f, const YAML::Node& node, PathFollowerConfig& c) {
  const std::string ctx = "robot.path_follower";
  f.requireMap(node, ctx, {"lookahead", "max_lateral_accel", "turn_in_place_deg", "heading_gain", "goal_tolerance"});
  c.lookahead = f.number(node, "lookahead", ctx, c.lookahead, 0.05, 10.0);
  c.max_lateral_accel = f.number(node, "max_lateral_accel", ctx, c.max_lateral_accel, 0.01, 20.0);
  c.turn_in_place_angle = degrees(f, node, "turn_in_place_deg", ctx, c.turn_in_place_angle, 5.0, 180.0);
  c.heading_gain = f.number(node, "heading_gain", ctx, c.heading_gain, 0.1, 100.0);
  c.goal_tolerance = f.number(node, "goal_tolerance", ctx, c.goal_tolerance, 0.001, 5.0);
}

void readRobot(const YamlFields& f, const YAML::Node& node, DriveConfig& c) {
  const std::string ctx = "robot";
  f.requireMap(node, ctx, {"wheel_base", "wheel_radius", "max_speed", "max_turn_rate_deg", "max_accel",
                           "max_angular_accel_deg", "control_period", "path_follower"});
  c.wheel_base = f.number(node, "wheel_base", ctx, c.wheel_base, 0.05, 5.0);
  c.wheel_radius = f.number(node, "wheel_radius", ctx, c.wheel_radius, 0.005, 2.0);
  c.max_speed = f.number(node, "max_speed", ctx, c.max_speed, 0.01, 10.0);
  c.max_turn_rate = degrees(f, node, "max_turn_rate_deg", ctx, c.max_turn_rate, 1.0, 1000.0);
  c.max_accel = f.number(node, "max_accel", ctx, c.max_accel, 0.01, 50.0);
  c.max_angular_accel = degrees(f, node, "max_angular_accel_deg", ctx, c.max_angular_accel, 1.0, 10000.0);
  c.control_period = f.number(node, "control_period", ctx, c.control_period, 0.001, 0.5);
  if (const YAML::Node pf = node["path_follower"]) readFollower(f, pf, c.follower);
}

void readOdometry(const YamlFields& f, const YAML::Node& node, OdometryConfig& c) {
  const std::string ctx = "odometry";
  f.requireMap(node, ctx, {"rate", "k_left", "k_right", "left_radius_error", "right_radius_error",
                           "wheel_base_error"});
  c.rate = f.number(node, "rate", ctx, c.rate, 0.1, kMaxRate);
  c.k_left = f.number(node, "k_left", ctx, c.k_left, 0.0, 1.0);
  c.k_right = f.number(node, "k_right", ctx, c.k_right, 0.0, 1.0);
  c.left_radius_error = f.number(node, "left_radius_error", ctx, c.left_radius_error, -0.5, 0.5);
  c.right_radius_error = f.number(node, "right_radius_error", ctx, c.right_radius_error, -0.5, 0.5);
  c.wheel_base_error = f.number(node, "wheel_base_error", ctx, c.wheel_base_error, -0.5, 0.5);
}

Pose2 readMount(const YamlFields& f, const YAML::Node& node, const std::string& ctx, const Pose2& fallback) {
  if (!node) return fallback;
  f.requireMap(node, ctx, {"x", "y", "theta_deg"});
  return {f.number(node, "x", ctx, fallback.x, -kMaxMountOffset, kMaxMountOffset),
          f.number(node, "y", ctx, fallback.y, -kMaxMountOffset, kMaxMountOffset),
          degrees(f, node, "theta_deg", ctx, fallback.theta, -360.0, 360.0)};
}

void readRangeErrors(const YamlFields& f, const YAML::Node& node, LaserConfig& c) {
  const std::string ctx = "laser.errors";
  f.requireMap(node, ctx, {"fixed_bias", "scan_bias_sigma", "growth", "incidence", "max_incidence_deg", "quantum",
                           "noise_sigma", "compensate_quantizer_offset", "output_noise_sigma"});
  RangeErrorParams& e = c.errors;
  e.fixed_bias = f.number(node, "fixed_bias", ctx, e.fixed_bias, -1.0, 1.0);
  e.scan_bias_sigma = f.number(node, "scan_bias_sigma", ctx, e.scan_bias_sigma, 0.0, 1.0);
  e.growth = f.number(node, "growth", ctx, e.growth, -0.5, 0.5);
  e.incidence = f.number(node, "incidence", ctx, e.incidence, -1.0, 1.0);
  e.max_incidence = degrees(f, node, "max_incidence_deg", ctx, e.max_incidence, 0.0, 89.9);
  e.quantum = f.number(node, "quantum", ctx, e.quantum, 0.0, 1.0);
  e.noise_sigma = f.number(node, "noise_sigma", ctx, e.noise_sigma, 0.0, 1.0);
  c.compensate_quantizer_offset =
      f.boolean(node, "compensate_quantizer_offset", ctx, c.compensate_quantizer_offset);
  c.output_noise_sigma = f.number(node, "output_noise_sigma", ctx, c.output_noise_sigma, 0.0, 1.0);
}

void readLaser(const YamlFields& f, const YAML::Node& node, LaserConfig& c) {
  const std::string ctx = "laser";
  f.requireMap(node, ctx, {"enabled", "beams", "fov_deg", "angle_min_deg", "rate", "range_max", "time_increment",
                           "mount", "tilt_deg", "tilt_axis_deg", "errors"});
  c.enabled = f.boolean(node, "enabled", ctx, c.enabled);
  c.beams = f.integer(node, "beams", ctx, c.beams, 1, static_cast<int>(kMaxLaserBeams));
  c.fov = degrees(f, node, "fov_deg", ctx, c.fov, 0.001, 360.0);
  c.angle_min = node["angle_min_deg"] ? degrees(f, node, "angle_min_deg", ctx, 0.0, -360.0, 360.0) : -0.5 * c.fov;
  c.rate = f.number(node, "rate", ctx, c.rate, 0.1, kMaxRate);
  c.range_max = f.number(node, "range_max", ctx, c.range_max, 0.1, kMaxRange);
  c.time_increment = f.number(node, "time_increment", ctx, c.time_increment, 0.0, 1.0);
  if (c.scanDuration() >= 1.0 / c.rate) {
    f.fail(node["time_increment"] ? node["time_increment"] : node,
           "laser.time_increment: " + std::to_string(c.beams) + " beams take " + std::to_string(c.scanDuration()) +
               " s, longer than the scan period 1/rate = " + std::to_string(1.0 / c.rate) + " s");
  }
  c.mount = readMount(f, node["mount"], "laser.mount", c.mount);
  c.tilt = degrees(f, node, "tilt_deg", ctx, c.tilt, -10.0, 10.0);
  c.tilt_axis = degrees(f, node, "tilt_axis_deg", ctx, c.tilt_axis, -360.0, 360.0);
  if (const YAML::Node errors = node["errors"]) readRangeErrors(f, errors, c);
}

SonarConfig readSonar(const YamlFields& f, const YAML::Node& node, size_t index) {
  const std::string ctx = "sonars[" + std::to_string(index) + "]";
  f.requireMap(node, ctx, {"name", "mount", "fov_deg", "rate", "range_min", "range_max", "range_sigma",
                           "bearing_sigma_deg", "misclassification_rate", "spurious_rate", "miss_rate",
                           "right_angle_tolerance_deg"});
  SonarConfig c;
  c.id = static_cast<int>(index);
  c.name = f.text(node, "name", ctx, "sonar" + std::to_string(index));
  c.mount = readMount(f, node["mount"], ctx + ".mount", c.mount);
  c.fov = degrees(f, node, "fov_deg", ctx, c.fov, 0.1, 360.0);
  c.rate = f.number(node, "rate", ctx, c.rate, 0.1, kMaxRate);
  c.range_min = f.number(node, "range_min", ctx, c.range_min, 0.0, kMaxRange);
  c.range_max = f.number(node, "range_max", ctx, c.range_max, 0.1, kMaxRange);
  if (c.range_min >= c.range_max) f.fail(node, ctx + ": range_min must be below range_max");
  c.range_sigma = f.number(node, "range_sigma", ctx, c.range_sigma, 0.0, 1.0);
  c.bearing_sigma = degrees(f, node, "bearing_sigma_deg", ctx, c.bearing_sigma, 0.0, 30.0);
  c.misclassification_rate = f.number(node, "misclassification_rate", ctx, c.misclassification_rate, 0.0, 1.0);
  c.spurious_rate = f.number(node, "spurious_rate", ctx, c.spurious_rate, 0.0, 100.0);
  c.miss_rate = f.number(node, "miss_rate", ctx, c.miss_rate, 0.0, 1.0);
  c.right_angle_tolerance = degrees(f, node, "right_angle_tolerance_deg", ctx, c.right_angle_tolerance, 0.0, 45.0);
  return c;
}

}  // namespace

std::vector<SonarConfig> RobotDescription::defaultSonars() {
  SonarConfig front, left, right;
  front.name = "front";
  front.id = 0;
  front.mount = {0.25, 0.0, 0.0};
  left.name = "left";
  left.id = 1;
  left.mount = {0.0, 0.2, 0.5 * std::numbers::pi};
  right.name = "right";
  right.id = 2;
  right.mount = {0.0, -0.2, -0.5 * std::numbers::pi};
  return {front, left, right};
}

RobotDescription loadRobotDescription(const std::string& yaml_path) {
  const YamlFields f(yaml_path);
  const YAML::Node& root = f.root();
  f.requireMap(root, "robot config", {"start_utime", "ground_truth_rate", "robot", "odometry", "laser", "sonars"});
  RobotDescription c;
  c.source = yaml_path;
  if (const YAML::Node t = root["start_utime"]) {
    try {
      c.start_utime = t.as<int64_t>();
    } catch (const YAML::Exception&) {
      f.fail(t, "start_utime: expected a whole number of microseconds");
    }
    if (c.start_utime < 0) f.fail(t, "start_utime: must not be negative");
  }
  c.ground_truth_rate = f.number(root, "ground_truth_rate", "config", c.ground_truth_rate, 0.1, kMaxRate);
  if (const YAML::Node n = root["robot"]) readRobot(f, n, c.robot);
  if (const YAML::Node n = root["odometry"]) readOdometry(f, n, c.odometry);
  if (const YAML::Node n = root["laser"]) readLaser(f, n, c.laser);
  if (const YAML::Node n = root["sonars"]) {
    f.requireSequence(n, "sonars");
    c.sonars.clear();
    for (size_t i = 0; i < n.size(); ++i) c.sonars.push_back(readSonar(f, n[i], i));
  }
  try {
    validate(c);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(yaml_path + ": " + e.what());
  }
  return c;
}

void validate(const RobotDescription& c) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument(what);
  };
  require(c.start_utime >= 0, "start_utime must not be negative");
  require(c.ground_truth_rate > 0.0 && c.ground_truth_rate <= kMaxRate, "ground_truth_rate out of range");
  const DriveConfig& r = c.robot;
  require(r.wheel_base > 0.0, "robot.wheel_base must be positive");
  require(r.wheel_radius > 0.0, "robot.wheel_radius must be positive");
  require(r.max_speed > 0.0 && r.max_turn_rate > 0.0, "robot.max_speed and max_turn_rate must be positive");
  require(r.max_accel > 0.0 && r.max_angular_accel > 0.0, "robot.max_accel and max_angular_accel must be positive");
  require(r.control_period >= 0.001 && r.control_period <= 0.5, "robot.control_period must be in [0.001, 0.5] s");
  require(r.follower.lookahead > 0.0, "robot.path_follower.lookahead must be positive");
  require(r.follower.goal_tolerance > 0.0, "robot.path_follower.goal_tolerance must be positive");
  const OdometryConfig& o = c.odometry;
  require(o.rate > 0.0 && o.rate <= kMaxRate, "odometry.rate out of range");
  require(o.k_left >= 0.0 && o.k_right >= 0.0, "odometry.k_left and k_right must not be negative");
  require(std::abs(o.left_radius_error) < 0.5 && std::abs(o.right_radius_error) < 0.5 &&
              std::abs(o.wheel_base_error) < 0.5,
          "odometry systematic errors must be below 50 %");
  const LaserConfig& l = c.laser;
  if (l.enabled) {
    require(l.beams >= 1 && static_cast<size_t>(l.beams) <= kMaxLaserBeams, "laser.beams out of range");
    require(l.fov > 0.0 && l.fov <= 2.0 * std::numbers::pi + 1e-9, "laser.fov_deg must be in (0, 360]");
    require(l.rate > 0.0 && l.rate <= kMaxRate, "laser.rate out of range");
    require(l.range_max > 0.0, "laser.range_max must be positive");
    require(l.time_increment >= 0.0 && l.scanDuration() < 1.0 / l.rate,
            "laser.time_increment: the beams of one scan must fit into the scan period");
    require(l.errors.quantum >= 0.0 && l.errors.noise_sigma >= 0.0 && l.errors.scan_bias_sigma >= 0.0 &&
                l.output_noise_sigma >= 0.0,
            "laser.errors: quantum and sigmas must not be negative");
    require(l.errors.max_incidence >= 0.0 && l.errors.max_incidence < 0.5 * std::numbers::pi,
            "laser.errors.max_incidence_deg must be in [0, 90)");
  }
  for (const SonarConfig& s : c.sonars) {
    const std::string ctx = "sonar '" + s.name + "'";
    require(s.rate > 0.0 && s.rate <= kMaxRate, ctx + ": rate out of range");
    require(s.fov > 0.0, ctx + ": fov must be positive");
    require(s.range_min >= 0.0 && s.range_min < s.range_max, ctx + ": need 0 <= range_min < range_max");
    require(s.range_sigma >= 0.0 && s.bearing_sigma >= 0.0, ctx + ": sigmas must not be negative");
    require(s.misclassification_rate >= 0.0 && s.misclassification_rate <= 1.0 && s.miss_rate >= 0.0 &&
                s.miss_rate <= 1.0,
            ctx + ": rates must be probabilities in [0, 1]");
    require(s.spurious_rate >= 0.0, ctx + ": spurious_rate must not be negative");
  }
}

LaserErrorParams laserErrorParams(const LaserConfig& laser) {
  LaserErrorParams p;
  p.range = laser.errors;
  if (!laser.compensate_quantizer_offset) p.range.fixed_bias = std::abs(p.range.fixed_bias) + laser.errors.quantum / 2;
  p.output_noise_sigma = laser.output_noise_sigma;
  p.tilt = laser.tilt;
  p.tilt_axis = laser.tilt_axis;
  return p;
}

}  // namespace polarslam
