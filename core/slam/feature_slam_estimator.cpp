#include "slam/feature_slam_estimator.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "grid/grid_outputs.hpp"
#include "sim/yaml_fields.hpp"
#include "sonar/feature_frames.hpp"

namespace polarslam {
namespace {

nlohmann::json matrixJson(const Mat3& m, int n) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < n; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < n; ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

const char* kindName(MapFeatureKind kind) {
  switch (kind) {
    case MapFeatureKind::Line: return "line";
    case MapFeatureKind::Corner: return "corner";
    case MapFeatureKind::Point: return "point";
  }
  return "?";
}

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

void readFusionSection(const YamlFields& y, const YAML::Node& node, FeatureSlamConfig& c) {
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

FeatureSlamConfig configForRobot(const SimConfig& robot, SlamSensors sensors) {
  FeatureSlamConfig c;
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

FeatureSlamConfig loadFeatureSlamConfig(const std::string& path, SlamSensors sensors) {
  const YamlFields y(path);
  const YAML::Node& root = y.root();
  if (!root.IsMap()) y.fail(root, "expected a robot file or a map with robot/ekf/fusion sections");
  if (y.has(root, "laser") || y.has(root, "sonars") || y.has(root, "odometry"))
    return configForRobot(loadSimConfig(path), sensors);
  y.requireMap(root, "estimator config", {"robot", "ekf", "fusion"});
  FeatureSlamConfig c = configForRobot(SimConfig{}, sensors);
  if (y.has(root, "robot")) {
    std::filesystem::path robot = y.text(root, "robot", "estimator config", "");
    if (robot.is_relative()) robot = std::filesystem::path(path).parent_path() / robot;
    c = configForRobot(loadSimConfig(robot.string()), sensors);
  }
  if (y.has(root, "ekf")) readSlamSection(y, root["ekf"], c.slam);
  if (y.has(root, "fusion")) readFusionSection(y, root["fusion"], c);
  c.fusion.odometry = c.slam.odometry;
  return c;
}

std::string featureMapJson(const FeatureMap& map, int indent) {
  nlohmann::json j;
  j["utime"] = map.utime;
  j["frame"] = "map";
  j["robot"] = {{"x", map.robot.pose.x},
                {"y", map.robot.pose.y},
                {"theta", map.robot.pose.theta},
                {"cov", matrixJson(map.robot.cov, 3)}};
  nlohmann::json features = nlohmann::json::array();
  std::map<std::string, int> counts{{"line", 0}, {"corner", 0}, {"point", 0}};
  for (const MapFeature& f : map.features) {
    const int n = parameterCount(f.kind);
    nlohmann::json params = nlohmann::json::array();
    for (int i = 0; i < n; ++i) params.push_back(f.params(i));
    nlohmann::json item = {{"id", f.id},
                           {"kind", kindName(f.kind)},
                           {"params", params},
                           {"cov", matrixJson(f.cov, n)},
                           {"observations", f.observations}};
    if (f.kind == MapFeatureKind::Line)
      item["endpoints"] = {{f.endpoint_a.x(), f.endpoint_a.y()}, {f.endpoint_b.x(), f.endpoint_b.y()}};
    if (f.kind == MapFeatureKind::Corner) item["orientation_known"] = !cornerOrientationUnknown(f.cov);
    features.push_back(item);
    ++counts[kindName(f.kind)];
  }
  j["parameters"] = {{"line", "alpha (rad), d (m): x cos(alpha) + y sin(alpha) = d, d >= 0"},
                     {"corner", "x (m), y (m), gamma (rad): apex and bisector direction into free space"},
                     {"point", "x (m), y (m)"}};
  j["counts"] = counts;
  j["features"] = features;
  return j.dump(indent) + "\n";
}

FeatureSlamEstimator::FeatureSlamEstimator(FeatureSlamConfig config)
    : config_(std::move(config)), extractor_(config_.laser), fusion_(config_.fusion), slam_(config_.slam) {}

void FeatureSlamEstimator::onOdometry(const OdometryReading& odometry) {
  if (std::isfinite(odometry.v) && std::isfinite(odometry.omega)) twist_ = {odometry.v, odometry.omega};
  fusion_.addOdometry(odometry);
  if (!slam_.addOdometry(odometry).empty()) ++rejected_;
  drain();
}

void FeatureSlamEstimator::onLaser(const LaserScan& scan) {
  ++laser_scans_;
  if (!slam_.requestAnchors(scan.utime).empty()) ++rejected_;
  else grid_scans_.addScan(scan);
  if (config_.sensors != SlamSensors::Sonar) {
    std::vector<double> hints;
    if (config_.sonar_break_hints && config_.sensors == SlamSensors::Fused)
      for (const BreakHint& h : fusion_.breakHints(scan)) hints.push_back(h.bearing);
    fusion_.addLaserScan(scan);
    // Motion during the scan enters the lines' systematic error bound (thesis §2.3.9).
    fusion_.addLaserFeatures(
        extractor_.extract(scan, hints, sensorMotionFromBaseTwist(scan.laser_pose, twist_.x(), twist_.y())));
  }
  drain();
}

void FeatureSlamEstimator::onSonar(const SonarScan& scan) {
  ++sonar_scans_;
  if (config_.sensors != SlamSensors::Laser) fusion_.addSonar(scan);
  drain();
}

void FeatureSlamEstimator::drain() {
  for (const FeatureSet& set : fusion_.takeReady())
    if (!slam_.addFeatures(set).empty()) ++rejected_;
  for (PoseStamped& p : slam_.takePoses()) trajectory_.push_back(p);
  for (ScanAnchors& a : slam_.takeAnchors()) {
    grid_scans_.addAnchors(a);
    anchors_.push_back(std::move(a));
  }
  const int64_t revisit_us = static_cast<int64_t>(kRevisitAfterSeconds * 1e6);
  for (const auto& [utime, id] : slam_.takeMatches()) {
    auto [it, fresh] = last_seen_.try_emplace(id, utime);
    if (!fresh) {
      if (utime - it->second >= revisit_us) revisits_.emplace_back(utime, id);
      it->second = utime;
    }
  }
}

void FeatureSlamEstimator::flush() {
  fusion_.flush();
  drain();
  slam_.flush();
  drain();
}

void FeatureSlamEstimator::finish(const std::string& out_dir, nlohmann::json& report) {
  flush();
  const FeatureMap map = slam_.map();
  if (!out_dir.empty()) {
    std::ofstream file(std::filesystem::path(out_dir) / "map.json");
    file << featureMapJson(map);
    writeGridOutputs(out_dir, grid_scans_, map, report);
  }
  std::map<std::string, int> counts{{"line", 0}, {"corner", 0}, {"point", 0}};
  for (const MapFeature& f : map.features) ++counts[kindName(f.kind)];
  const FeatureSlamStats& s = slam_.stats();
  const FeatureFusionStats& f = fusion_.stats();
  report["map"] = {{"features", map.features.size()},
                   {"lines", counts["line"]},
                   {"corners", counts["corner"]},
                   {"points", counts["point"]},
                   {"tentative", slam_.tentativeCount()}};
  report["ekf"] = {{"feature_sets", s.feature_sets},
                   {"observations", s.observations},
                   {"paired", s.paired},
                   {"ambiguous", s.ambiguous},
                   {"near_existing_discarded", s.near_existing},
                   {"tentative_started", s.tentative_started},
                   {"promoted", s.promoted},
                   {"tentative_expired", s.tentative_expired},
                   {"failed_updates", s.failed_updates},
                   {"jcbb_budget_exhausted", s.jcbb_budget_exhausted},
                   {"rejected", s.reject_reasons},
                   {"updates", s.updates},
                   {"mean_update_ms", s.updates > 0 ? 1e3 * s.update_seconds / static_cast<double>(s.updates) : 0.0},
                   {"scan_anchors", anchors_.size()},
                   {"revisits", revisits_.size()}};
  report["fusion"] = {{"sensors", toString(config_.sensors)},
                      {"laser_sets", f.laser_sets},
                      {"sonar_scans", f.sonar_scans},
                      {"fused_lines", f.fusion.fused_lines},
                      {"fused_corners", f.fusion.fused_corners},
                      {"sonar_lines_alone", f.fusion.sonar_lines_alone},
                      {"sonar_corners_alone", f.fusion.sonar_corners_alone},
                      {"sonar_points", f.fusion.sonar_points},
                      {"sonar_unknown_targets", f.sonar.unknown},
                      {"sonar_invalid_targets", f.sonar.invalid},
                      {"sonar_spurious_rejected", f.selection.spurious},
                      {"sonar_points_unsupported", f.selection.unsupported},
                      {"sonar_kept_glass", f.selection.kept_glass},
                      {"late_inputs", f.late}};
  report["rejected_inputs"] = rejected_;
}

}  // namespace polarslam
