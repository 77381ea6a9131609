#include "pipeline/feature_pipeline.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "config/yaml_fields.hpp"

namespace polarslam {
namespace {

void readSlamSection(const YamlFields& y, const YAML::Node& node, FeatureSlamParams& p) {
  y.requireMap(node, "ekf",
               {"gate_probability", "new_feature_probability", "tentative_gate_probability", "confirm_observations",
                "tentative_timeout_s", "min_line_distance", "max_line_extent_gap", "observation_cov_scale",
                "anchor_radius", "max_anchors", "latency_s", "ambiguity_nis_margin", "max_jcbb_nodes"});
  p.association.gate_probability = y.number(node, "gate_probability", "ekf", p.association.gate_probability, 0.5, 0.999999);
  p.new_feature_probability =
      y.number(node, "new_feature_probability", "ekf", p.new_feature_probability, 0.5, 0.999999);
  p.tentative_gate_probability =
      y.number(node, "tentative_gate_probability", "ekf", p.tentative_gate_probability, 0.5, 0.999999);
  p.confirm_observations = y.integer(node, "confirm_observations", "ekf", p.confirm_observations, 1, 1000);
  p.tentative_timeout_s = y.number(node, "tentative_timeout_s", "ekf", p.tentative_timeout_s, 0.0, 3600.0);
  p.min_line_distance = y.number(node, "min_line_distance", "ekf", p.min_line_distance, 0.0, 10.0);
  p.max_line_extent_gap = y.number(node, "max_line_extent_gap", "ekf", p.max_line_extent_gap, 0.0, 1e6);
  p.observation_cov_scale = y.number(node, "observation_cov_scale", "ekf", p.observation_cov_scale, 1e-3, 1e3);
  p.anchor_radius = y.number(node, "anchor_radius", "ekf", p.anchor_radius, 0.0, 1e3);
  p.max_anchors = y.integer(node, "max_anchors", "ekf", p.max_anchors, 0, 10000);
  p.latency_s = y.number(node, "latency_s", "ekf", p.latency_s, 0.0, 60.0);
  p.association.ambiguity_nis_margin =
      y.number(node, "ambiguity_nis_margin", "ekf", p.association.ambiguity_nis_margin, 0.0, 1e6);
  p.association.max_nodes = y.integer(node, "max_jcbb_nodes", "ekf", p.association.max_nodes, 1, 100000000);
}

void readFusionSection(const YamlFields& y, const YAML::Node& node, FeaturePipelineConfig& c) {
  y.requireMap(node, "fusion",
               {"gate_probability", "max_sonar_offset_s", "sonar_wait_s", "laser_wait_s", "laser_aided_selection",
                "sonar_break_hints"});
  FeatureFusionParams& f = c.fusion;
  f.fusion.gate_probability = y.number(node, "gate_probability", "fusion", f.fusion.gate_probability, 0.5, 0.999999);
  f.max_sonar_offset_s = y.number(node, "max_sonar_offset_s", "fusion", f.max_sonar_offset_s, 0.0, 10.0);
  f.sonar_wait_s = y.number(node, "sonar_wait_s", "fusion", f.sonar_wait_s, 0.0, 10.0);
  f.laser_wait_s = y.number(node, "laser_wait_s", "fusion", f.laser_wait_s, 0.0, 10.0);
  f.laser_aided_selection = y.boolean(node, "laser_aided_selection", "fusion", f.laser_aided_selection);
  c.sonar_break_hints = y.boolean(node, "sonar_break_hints", "fusion", c.sonar_break_hints);
}

FeaturePipelineConfig configForRobotFile(const std::string& path, SlamSensors sensors) {
  return configForRobot(loadRobotDescription(path), sensors);
}

}  // namespace

SlamSensors parseSlamSensors(const std::string& name) {
  if (name == "laser") return SlamSensors::Laser;
  if (name == "sonar") return SlamSensors::Sonar;
  if (name == "fused") return SlamSensors::Fused;
  throw std::invalid_argument("sensors must be laser, sonar or fused, not '" + name + "'");
}

const char* toString(SlamSensors sensors) {
  switch (sensors) {
    case SlamSensors::Laser: return "laser";
    case SlamSensors::Sonar: return "sonar";
    case SlamSensors::Fused: return "fused";
  }
  return "?";
}

FeaturePipelineConfig configForRobot(const RobotDescription& robot, SlamSensors sensors) {
  FeaturePipelineConfig c;
  c.sensors = sensors;
  c.fusion.use_laser = sensors != SlamSensors::Sonar;
  c.fusion.use_sonar = sensors != SlamSensors::Laser;
  c.sonar_break_hints = sensors == SlamSensors::Fused;
  c.fusion.laser_aided_selection = sensors == SlamSensors::Fused;
  // The odometry model with the robot's own wheel base and wheel-error constants (notes §17.6);
  // the systematic radius and wheel-base errors are unknown to the robot, as to the odometry.
  c.slam.odometry.wheels.wheelbase = robot.robot.wheel_base;
  c.slam.odometry.wheels.k_left = robot.odometry.k_left;
  c.slam.odometry.wheels.k_right = robot.odometry.k_right;
  c.fusion.odometry = c.slam.odometry;
  // The laser's error model (2.8), as the simulator uses it.
  c.laser.errors = LaserErrorParams{};
  c.laser.errors.range = robot.laser.errors;
  if (!robot.laser.compensate_quantizer_offset)
    c.laser.errors.range.fixed_bias = std::abs(c.laser.errors.range.fixed_bias) + robot.laser.errors.quantum / 2;
  c.laser.errors.output_noise_sigma = robot.laser.output_noise_sigma;
  c.laser.errors.tilt = robot.laser.tilt;
  c.laser.errors.tilt_axis = robot.laser.tilt_axis;
  const LaserErrorModel model(c.laser.errors);
  c.fusion.selection.laser_range_sigma = model.rangeSigma();
  if (!robot.sonars.empty()) {
    double range_sigma = 0.0, bearing_sigma = 0.0;
    for (const SonarConfig& s : robot.sonars) {
      range_sigma = std::max(range_sigma, s.range_sigma);
      bearing_sigma = std::max(bearing_sigma, s.bearing_sigma);
    }
    c.fusion.sonar.range_sigma_floor = range_sigma;
    c.fusion.sonar.bearing_sigma_floor = bearing_sigma;
  }
  return c;
}

FeaturePipelineConfig loadFeaturePipelineConfig(const std::string& path, SlamSensors sensors) {
  if (path.empty()) return configForRobot(RobotDescription{}, sensors);
  const YamlFields y(path);
  const YAML::Node& root = y.root();
  if (!root.IsMap()) y.fail(root, "expected a robot file or a map with robot/ekf/fusion/laser_features sections");
  if (y.has(root, "laser") || y.has(root, "sonars") || y.has(root, "odometry")) return configForRobotFile(path, sensors);
  y.requireMap(root, "estimator config", {"robot", "ekf", "fusion", "laser_features"});
  FeaturePipelineConfig c = configForRobot(RobotDescription{}, sensors);
  if (y.has(root, "robot")) {
    std::filesystem::path robot = y.text(root, "robot", "estimator config", "");
    if (robot.is_relative()) robot = std::filesystem::path(path).parent_path() / robot;
    c = configForRobotFile(robot.string(), sensors);
  }
  if (y.has(root, "ekf")) readSlamSection(y, root["ekf"], c.slam);
  if (y.has(root, "fusion")) readFusionSection(y, root["fusion"], c);
  if (y.has(root, "laser_features")) readLaserFeatureSection(y, root["laser_features"], c.laser);
  c.fusion.odometry = c.slam.odometry;
  return c;
}

LaserFeatureStage::LaserFeatureStage(const FeaturePipelineConfig& config)
    : extractor_(config.laser),
      hints_(SonarBreakHintParams{config.fusion.sonar, config.fusion.laser_wait_s, config.slam.odometry}),
      use_hints_(config.sensors == SlamSensors::Fused && config.sonar_break_hints) {}

bool LaserFeatureStage::addOdometry(const OdometryReading& reading) {
  if (!std::isfinite(reading.v) || !std::isfinite(reading.omega)) return false;
  if (use_hints_ && !hints_.addOdometry(reading)) return false;
  latest_odometry_ = reading;
  return true;
}

void LaserFeatureStage::addSonar(const SonarScan& scan) {
  if (use_hints_) hints_.addSonar(scan);
}

FeatureSet LaserFeatureStage::extract(const LaserScan& scan) const {
  std::vector<double> hints;
  if (use_hints_)
    for (const BreakHint& h : hints_.hints(scan)) hints.push_back(h.bearing);
  SensorMotion motion;
  if (latest_odometry_ && std::llabs(latest_odometry_->utime - scan.utime) < kMaxSpeedAgeUs)
    motion = sensorMotionFromBaseTwist(scan.laser_pose, latest_odometry_->v, latest_odometry_->omega);
  FeatureSet features = extractor_.extract(scan, hints, motion);
  features.break_hints = std::move(hints);
  return features;
}

}  // namespace polarslam
