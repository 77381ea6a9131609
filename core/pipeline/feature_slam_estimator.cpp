#include "pipeline/feature_slam_estimator.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "grid/grid_outputs.hpp"
#include "grid/pose_regeneration.hpp"
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

}  // namespace

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

std::vector<PoseStamped> anchorPoses(const std::vector<ScanAnchors>& anchors) {
  std::vector<PoseStamped> poses;
  poses.reserve(anchors.size());
  for (const ScanAnchors& a : anchors) poses.push_back(a.pose);
  return poses;
}

std::vector<PoseStamped> regeneratedTrajectory(const std::vector<ScanAnchors>& anchors, const FeatureMap& map) {
  const std::vector<RegeneratedPose> regenerated = regeneratePoses(anchors, map);
  std::vector<PoseStamped> poses;
  poses.reserve(anchors.size());
  for (size_t i = 0; i < anchors.size(); ++i) poses.push_back({anchors[i].utime, regenerated[i].pose, regenerated[i].cov});
  return poses;
}

FeatureSlamEstimator::FeatureSlamEstimator(FeaturePipelineConfig config)
    : config_(std::move(config)), features_(config_), fusion_(config_.fusion), slam_(config_.slam) {}

// Each input goes to the stages that read it, in the order the live processes receive it.

void FeatureSlamEstimator::onOdometry(const OdometryReading& odometry) {
  features_.addOdometry(odometry);
  fusion_.addOdometry(odometry);
  if (!slam_.addOdometry(odometry).empty()) ++rejected_;
  drain();
}

void FeatureSlamEstimator::onLaser(const LaserScan& scan) {
  ++laser_scans_;
  if (!slam_.requestAnchors(scan.utime).empty()) ++rejected_;
  else grid_scans_.addScan(scan);
  fusion_.addLaserScan(scan);
  if (config_.sensors != SlamSensors::Sonar) fusion_.addLaserFeatures(features_.extract(scan));
  drain();
}

void FeatureSlamEstimator::onSonar(const SonarScan& scan) {
  ++sonar_scans_;
  features_.addSonar(scan);
  if (config_.sensors != SlamSensors::Laser) fusion_.addSonar(scan);
  drain();
}

void FeatureSlamEstimator::drain() {
  for (const FeatureSet& set : fusion_.takeReady())
    if (!slam_.addFeatures(set).empty()) ++rejected_;
  for (PoseStamped& p : slam_.takePoses()) filter_poses_.push_back(p);
  for (ScanAnchors& a : slam_.takeAnchors()) {
    grid_scans_.addAnchors(a);
    online_.push_back(a.pose);
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
  final_ = regeneratedTrajectory(anchors_, map);
  finished_ = true;
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
                   {"gave_up_waiting_for_features", s.gave_up_waiting},
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
                      {"late_inputs", f.late},
                      {"missing_laser_sets", f.missing_laser_sets}};
  report["rejected_inputs"] = rejected_;
}

}  // namespace polarslam
