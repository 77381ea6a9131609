#pragma once
// Where the laser segmenter should break lines because an advanced sonar saw a corner or an edge
// there (thesis §3.3): the latest cycle of every sonar array, moved to the laser scan's time with
// the odometry and into the laser frame. The laser feature stage (polarslam-features) owns one,
// so hints depend only on the SONAR and ODOMETRY messages received before the LASER scan, live
// and offline alike.
#include <map>
#include <vector>

#include "laser/laser_scan.hpp"
#include "odometry/odometry_history.hpp"
#include "sonar/sonar_features.hpp"
#include "sonar/sonar_selection.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

struct SonarBreakHintParams {
  SonarFeatureParams sonar;
  double max_age_s = 0.3;  ///< sonar cycles further than this from the scan give no hints
  OdometryModelParams odometry;
};

class SonarBreakHintSource {
 public:
  explicit SonarBreakHintSource(SonarBreakHintParams params = {});

  /// False for a reading the odometry history refuses (non-finite, out of order).
  bool addOdometry(const OdometryReading& reading);
  void addSonar(const SonarScan& scan);
  /// Hints for one laser scan, from the cycles received so far.
  std::vector<BreakHint> hints(const LaserScan& scan) const;

 private:
  SonarBreakHintParams params_;
  OdometryHistory odometry_;
  std::map<int, SonarScan> latest_sonar_;  ///< by array id
};

}  // namespace polarslam
