#include "pipeline/estimator.hpp"

#include <filesystem>
#include <map>

#include "pipeline/feature_slam_estimator.hpp"
#include "pipeline/g2o_export.hpp"

namespace polarslam {

void OdometryEstimator::onOdometry(const OdometryReading& odometry) {
  if (!started_) {
    origin_inverse_ = odometry.pose.inverse();
    started_ = true;
  }
  trajectory_.push_back({odometry.utime, origin_inverse_ * odometry.pose, odometry.cov});
}

void LaserOdometryEstimator::onLaser(const LaserScan& scan) {
  if (!validateScan(scan).empty()) {
    ++unusable_scans_;
    return;
  }
  odometry_.addScan(scan);
}

void LaserOdometryEstimator::finish(const std::string&, nlohmann::json& report) {
  report["laser_odometry"] = {{"scans", odometry_.scans()},
                              {"keyframes", odometry_.keyframes()},
                              {"failed_matches", odometry_.failedMatches()},
                              {"held_scans", odometry_.heldScans()},
                              {"unusable_scans", unusable_scans_}};
}

bool RecordedEstimator::inOrder(int64_t& last, int64_t utime) {
  if (utime <= last) {
    ++out_of_order_;
    return false;
  }
  last = utime;
  return true;
}

void RecordedEstimator::onPose(const PoseStamped& pose) {
  if (inOrder(last_pose_, pose.utime)) published_.push_back(pose);
}

void RecordedEstimator::onScanAnchors(const ScanAnchors& anchors) {
  if (inOrder(last_anchors_, anchors.utime)) scan_anchors_.push_back(anchors);
}

void RecordedEstimator::onFeatureMap(const FeatureMap& map) {
  map_ = map;
  ++maps_;
}

void RecordedEstimator::onAnchoredPose(const AnchoredPose& pose) {
  if (inOrder(last_anchored_, pose.utime)) anchored_.push_back(pose);
}

void RecordedEstimator::onPoseGraph(const PoseGraph& graph) {
  graph_ = graph;
  ++graphs_;
}

void RecordedEstimator::onFinalPath(const std::vector<PoseStamped>& path) { final_path_ = path; }

void RecordedEstimator::finish(const std::string& out_dir, nlohmann::json& report) {
  if (graph_ && !out_dir.empty()) writeG2o((std::filesystem::path(out_dir) / "graph.g2o").string(), *graph_);
  std::string final_source = "published poses (nothing to re-place them with)";
  size_t missing_nodes = 0;
  online_ = scan_anchors_.empty() ? published_ : anchorPoses(scan_anchors_);
  final_ = online_;
  if (!scan_anchors_.empty() && map_) {
    final_ = regeneratedTrajectory(scan_anchors_, *map_);
    final_source = "scan anchors regenerated in the last map";
  } else if (!anchored_.empty() && graph_) {
    final_ = reanchor(anchored_, *graph_, &missing_nodes);
    final_source = "anchored poses re-placed by the last pose graph";
  } else if (final_path_) {  // localising: no graph goes out, the final trajectory does on exit
    // A process resumed from a snapshot knows the scans since: the earlier ones keep their poses.
    std::map<int64_t, Pose2> placed;
    for (const PoseStamped& p : *final_path_) placed[p.utime] = p.pose;
    for (PoseStamped& p : final_)
      if (const auto it = placed.find(p.utime); it != placed.end()) p.pose = it->second;
    final_source = "the final path published on exit";
  }
  finished_ = true;
  report["recorded"] = {{"published_poses", published_.size()},
                        {"scan_anchors", scan_anchors_.size()},
                        {"anchored_poses", anchored_.size()},
                        {"maps", maps_},
                        {"graphs", graphs_},
                        {"final_path_poses", final_path_ ? final_path_->size() : 0},
                        {"anchors_without_node", missing_nodes},
                        {"final_from", final_source},
                        {"out_of_order_dropped", out_of_order_}};
}

}  // namespace polarslam
