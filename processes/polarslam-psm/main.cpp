// polarslam-psm: laser odometry by polar scan matching. LASER (+ ODOMETRY as the prior) →
// PSM_ODOMETRY (pose_t, frame "odom", with covariance) and PSM_MATCHES (scan_match_t, one per
// match against the current keyframe). A thin shell over core/scanmatch/laser_odometry.
#include <CLI/CLI.hpp>

#include <iostream>

#include "common/program_info.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"
#include "polarslam/scan_match_t.hpp"
#include "scanmatch/laser_odometry.hpp"

using namespace polarslam;

namespace {

struct Channels {
  std::string laser = "LASER", odometry = "ODOMETRY", pose = "PSM_ODOMETRY", matches = "PSM_MATCHES";
};

polarslam::scan_match_t matchMessage(const LaserOdometryUpdate& u, MatchMethod method, int64_t seq) {
  polarslam::scan_match_t msg;
  msg.utime = u.utime;
  msg.ref_utime = u.ref_utime;
  msg.seq = seq;
  msg.method = methodName(method);
  msg.status = statusText(u.match.status);
  msg.pose[0] = u.match.pose.x;
  msg.pose[1] = u.match.pose.y;
  msg.pose[2] = u.match.pose.theta;
  copyMatrix<3>(u.match.cov, msg.cov);
  msg.iterations = u.match.iterations;
  msg.valid_points = u.match.valid_points;
  msg.error_index = u.match.error_index;
  msg.time_us = static_cast<int64_t>(u.match_time_us + 0.5);
  return msg;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"polarslam-psm: laser odometry by polar scan matching (PSM)"};
  addVersionFlag(app);
  std::string method = "psm", covariance = "wls";
  bool ignore_odometry = false;
  Channels channels;
  LaserOdometryParams params;
  PsmParams psm;
  ProcessOptions process_options;
  addProcessOptions(app, process_options);
  app.add_option("--method", method)->check(CLI::IsMember({"psm", "psm-c", "icp"}))->capture_default_str();
  app.add_option("--covariance", covariance)->check(CLI::IsMember({"wls", "heuristic"}))->capture_default_str();
  app.add_option("--decimation", psm.decimation, "use every n-th beam")->check(CLI::Range(1, 16))->capture_default_str();
  app.add_option("--max-range", psm.max_range, "readings farther than this (m) are not matched")->capture_default_str();
  app.add_option("--keyframe-distance", params.keyframe_distance, "m of motion before a new keyframe")->capture_default_str();
  app.add_option("--keyframe-angle", params.keyframe_angle, "rad of rotation before a new keyframe")->capture_default_str();
  app.add_flag("--ignore-odometry", ignore_odometry, "do not use ODOMETRY as the prior (constant velocity instead)");
  app.add_option("--laser-channel", channels.laser, "channel of the laser scans (laser_scan_t)")->capture_default_str();
  app.add_option("--odometry-channel", channels.odometry, "channel of the odometry (odometry_t)")->capture_default_str();
  app.add_option("--pose-channel", channels.pose, "channel of the robot poses (pose_t)")->capture_default_str();
  app.add_option("--matches-channel", channels.matches, "channel of the scan matches (scan_match_t)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  parseMatchMethod(method, params.method);
  parseCovarianceModel(covariance, psm.covariance);

  try {
    ProcessContext context("polarslam-psm", process_options);
    LaserOdometry odometry(params, psm);
    int64_t pose_seq = 0, match_seq = 0;
    context.subscribeConverted<polarslam::laser_scan_t, LaserScan>(channels.laser, [&](LaserScan& scan) {
      const LaserOdometryUpdate u = odometry.addScan(scan);
      context.publish(channels.pose, toLcm(PoseStamped{u.utime, u.pose, u.cov}, "odom", pose_seq++));
      if (u.matched) context.publish(channels.matches, matchMessage(u, params.method, match_seq++));
      context.handled();
    });
    if (!ignore_odometry) {
      context.subscribeConverted<polarslam::odometry_t, OdometryReading>(channels.odometry, [&](OdometryReading& reading) {
        odometry.addOdometry(reading);
        context.handled();
      });
    }
    context.run();
    std::cerr << "polarslam-psm: " << odometry.scans() << " scans, " << odometry.keyframes() << " keyframes, "
              << odometry.failedMatches() << " failed matches, " << odometry.heldScans() << " held still\n";
  } catch (const std::exception& e) {
    std::cerr << "polarslam-psm: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
