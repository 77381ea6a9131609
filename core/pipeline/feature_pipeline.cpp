#include "pipeline/feature_pipeline.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "config/parameter_table.hpp"

namespace polarslam {
namespace {

void describeSlam(ParameterTable& t, FeatureSlamParams& p) {
  t.number("gate_probability", p.association.gate_probability, 0.5, 0.999999,
           "individual and joint χ² gates of the data association (JCBB)");
  t.number("new_feature_probability", p.new_feature_probability, 0.5, 0.999999,
           "inside this gate of a map feature an observation never starts a new one");
  t.number("tentative_gate_probability", p.tentative_gate_probability, 0.5, 0.999999,
           "gate for matching tentative features");
  t.integer("confirm_observations", p.confirm_observations, 1, 1000, "observations before a feature enters the filter");
  t.number("tentative_timeout_s", p.tentative_timeout_s, 0.0, 3600.0, "s: a tentative feature not seen again is dropped");
  t.number("min_line_distance", p.min_line_distance, 0.0, 10.0, "m: nearer lines are skipped (their normal flips)");
  t.number("max_line_extent_gap", p.max_line_extent_gap, 0.0, 1e6, "m beyond a map line's extent: another wall");
  t.number("observation_cov_scale", p.observation_cov_scale, 1e-3, 1e3, "multiplies every measurement covariance");
  t.number("anchor_radius", p.anchor_radius, 0.0, 1e3, "m: map features within this anchor a laser scan");
  t.integer("max_anchors", p.max_anchors, 0, 10000, "anchors per scan at most");
  t.number("latency_s", p.latency_s, 0.0, 60.0, "s of stream time odometry waits for feature sets");
  t.number("max_feature_lag_s", p.max_feature_lag_s, 0.0, 3600.0,
           "s of stream time odometry waits for the feature set of a scan already received");
  t.number("ambiguity_nis_margin", p.association.ambiguity_nis_margin, 0.0, 1e6,
           "a rival association within this joint NIS of the best is ambiguous");
  t.integer("max_jcbb_nodes", p.association.max_nodes, 1, 100000000, "JCBB search budget per feature set");
}

void describeFusion(ParameterTable& t, FeaturePipelineConfig& c) {
  FeatureFusionParams& f = c.fusion;
  t.number("gate_probability", f.fusion.gate_probability, 0.5, 0.999999, "χ² gate for fusing sonar and laser");
  t.number("max_sonar_offset_s", f.max_sonar_offset_s, 0.0, 10.0, "s: sonar cycles this close to a scan are fused");
  t.number("sonar_wait_s", f.sonar_wait_s, 0.0, 10.0, "s of stream time a laser set waits for sonar cycles");
  t.number("laser_wait_s", f.laser_wait_s, 0.0, 10.0, "s a sonar cycle waits for a laser set (also hint age)");
  t.number("max_laser_lag_s", f.max_laser_lag_s, 0.0, 3600.0,
           "s of stream time a sonar cycle waits for the laser set of a scan already received");
  t.boolean("laser_aided_selection", f.laser_aided_selection, "sonar targets checked against the raw laser scan");
  t.boolean("sonar_break_hints", c.sonar_break_hints, "sonar corners and edges break laser segments");
}

}  // namespace

void describeFeaturePipeline(FeaturePipelineTables& tables, FeaturePipelineConfig& config) {
  describeSlam(tables.ekf, config.slam);
  describeFusion(tables.fusion, config);
  describeLaserFeatures(tables.laser_features, config.laser);
}

namespace {

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
  c.slam.feature_set_per_scan = c.fusion.use_laser;
  c.sonar_break_hints = sensors == SlamSensors::Fused;
  c.fusion.laser_aided_selection = sensors == SlamSensors::Fused;
  // The odometry model with the robot's own wheel base and wheel-error constants (docs/algorithms.md §17.6);
  // the systematic radius and wheel-base errors are unknown to the robot, as to the odometry.
  c.slam.odometry.wheels.wheelbase = robot.robot.wheel_base;
  c.slam.odometry.wheels.k_left = robot.odometry.k_left;
  c.slam.odometry.wheels.k_right = robot.odometry.k_right;
  c.fusion.odometry = c.slam.odometry;
  // The laser's error model (2.8), as the simulator uses it.
  c.laser.errors = laserErrorParams(robot.laser);
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
  FeaturePipelineTables tables;
  describeFeaturePipeline(tables, c);
  tables.ekf.read(y, root["ekf"], "ekf");
  tables.fusion.read(y, root["fusion"], "fusion");
  tables.laser_features.read(y, root["laser_features"], "laser_features");
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
