#include "pipeline/psm_slam_session.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "map/map_store.hpp"

namespace polarslam {

Pose2 parseInitialPose(const std::string& text) {
  std::istringstream in(text);
  double v[3];
  char comma1 = 0, comma2 = 0;
  if (!(in >> v[0] >> comma1 >> v[1] >> comma2 >> v[2]) || comma1 != ',' || comma2 != ',' || !(in >> std::ws).eof() ||
      !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
    throw std::runtime_error("--initial-pose '" + text + "': expected x,y,theta (m, m, rad), three finite numbers");
  return Pose2(v[0], v[1], v[2]);
}

std::unique_ptr<Estimator> makePsmSlamEstimator(PsmSlamEstimatorConfig config, const SavedMapOptions& o) {
  if (o.load_map.empty()) {
    if (o.initial_pose) throw std::runtime_error("--initial-pose goes with --load-map");
    auto estimator = std::make_unique<PsmSlamEstimator>(std::move(config));
    estimator->saveMapTo(o.save_map);
    return estimator;
  }
  if (o.mode == "continue") {
    auto estimator = std::make_unique<MapContinuationEstimator>(loadMap(o.load_map), std::move(config), o.initial_pose);
    estimator->saveMapTo(o.save_map);
    return estimator;
  }
  if (o.mode != "localize") throw std::runtime_error("--mode must be localize or continue, not '" + o.mode + "'");
  if (!o.save_map.empty()) throw std::runtime_error("--mode localize adds nothing to the map: no --save-map");
  return std::make_unique<MapLocalizationEstimator>(loadMap(o.load_map), std::move(config), o.initial_pose);
}

PsmSlamSession::PsmSlamSession(PsmSlamEstimatorConfig config, const SavedMapOptions& options)
    : estimator_(makePsmSlamEstimator(std::move(config), options)), save_map_(options.save_map) {
  scratch_ = dynamic_cast<PsmSlamEstimator*>(estimator_.get());
  continuation_ = dynamic_cast<MapContinuationEstimator*>(estimator_.get());
  localization_ = dynamic_cast<MapLocalizationEstimator*>(estimator_.get());
}

const PsmSlamEstimator* PsmSlamSession::mapping() const {
  if (scratch_) return scratch_;
  if (continuation_ && continuation_->mapping()) return &continuation_->mappingEstimator();
  return nullptr;
}

const PsmSlam* PsmSlamSession::slam() const {
  const PsmSlamEstimator* m = mapping();
  return m ? &m->slam() : nullptr;
}

void PsmSlamSession::onOdometry(const OdometryReading& reading) {
  started_ = true;
  estimator_->onOdometry(reading);
}

PsmSlamScanOutput PsmSlamSession::onLaser(const LaserScan& scan) {
  started_ = true;
  const bool mapping_before = mapping() != nullptr;
  estimator_->onLaser(scan);
  PsmSlamScanOutput out;
  out.pose = estimator_->onlineTrajectory().back();
  const PsmSlamEstimator* m = mapping();
  if (m && mapping_before) {
    const PsmSlamScanResult& r = m->lastResult();
    out.anchor = r.anchor;
    out.usable = r.usable;
    out.graph_changed = r.new_keyframe || r.loop_closed || r.optimized;
    out.optimized = r.optimized;
  } else {
    // Localising, or the scan that placed a continued map's robot (the graph appears with it).
    out.usable = localization_ ? localization_->lastResult().usable : true;
    out.graph_changed = m != nullptr;
  }
  return out;
}

void PsmSlamSession::saveMapNow() const {
  const PsmSlamEstimator* m = mapping();
  if (!m) throw MapFormatError(save_map_, "nothing to save yet: the robot has not been placed in the map");
  m->saveMapNow();
}

nlohmann::json PsmSlamSession::finish() {
  nlohmann::json report;
  estimator_->finish("", report);
  return report;
}

}  // namespace polarslam
