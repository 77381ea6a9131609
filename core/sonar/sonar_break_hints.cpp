#include "sonar/sonar_break_hints.hpp"

#include <cstdlib>

#include "sonar/feature_frames.hpp"

namespace polarslam {

SonarBreakHintSource::SonarBreakHintSource(SonarBreakHintParams params)
    : params_(std::move(params)), odometry_(5.0, params_.odometry) {}

bool SonarBreakHintSource::addOdometry(const OdometryReading& reading) { return odometry_.add(reading); }

void SonarBreakHintSource::addSonar(const SonarScan& scan) {
  const auto it = latest_sonar_.find(scan.sensor_id);
  if (it == latest_sonar_.end() || scan.utime >= it->second.utime) latest_sonar_[scan.sensor_id] = scan;
}

std::vector<BreakHint> SonarBreakHintSource::hints(const LaserScan& scan) const {
  const int64_t max_age_us = static_cast<int64_t>(params_.max_age_s * 1e6);
  FeatureSet sonar_base;
  for (const auto& [id, latest] : latest_sonar_) {
    if (std::llabs(latest.utime - scan.utime) > max_age_us) continue;
    FeatureSet f = sonarFeatures(latest, params_.sonar);
    if (latest.utime != scan.utime) {
      const auto motion = odometry_.motion(scan.utime, latest.utime);
      if (!motion) continue;
      f = transformFeatures(f, motion->delta, motion->cov);
    }
    sonar_base.corners.insert(sonar_base.corners.end(), f.corners.begin(), f.corners.end());
    sonar_base.points.insert(sonar_base.points.end(), f.points.begin(), f.points.end());
  }
  return sonarBreakHints(sonar_base, scan.laser_pose);
}

}  // namespace polarslam
