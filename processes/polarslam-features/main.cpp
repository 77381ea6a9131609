// polarslam-features: LASER → LASER_FEATURES. Polar lines and right-angle corners with their
// error model (thesis chapter 2), in the laser frame. All the work is core/laser; this only
// moves messages. ODOMETRY (optional) supplies the robot's speed for the motion-during-scan term.
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <optional>

#include "common/laser_feature_options.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"

using namespace polarslam;

int main(int argc, char** argv) {
  CLI::App app{"polarslam-features: laser scans to polar line and right-angle corner features"};
  std::string url, laser_channel = "LASER", features_channel = "LASER_FEATURES", odometry_channel = "ODOMETRY";
  LaserFeatureOptions options;
  options.add(app);
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL or multicast TTL 0)");
  app.add_option("--laser-channel", laser_channel)->capture_default_str();
  app.add_option("--features-channel", features_channel)->capture_default_str();
  app.add_option("--odometry-channel", odometry_channel, "speed for the motion error term; \"\" = none")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  try {
    const LaserFeatureExtractor extractor(options.resolve());
    ProcessContext context("polarslam-features", url);
    std::optional<OdometryReading> odometry;  // latest reading: the robot's speed
    int64_t out_seq = 0;
    context.subscribeConverted<polarslam::laser_scan_t, LaserScan>(laser_channel, [&](LaserScan& scan) {
      SensorMotion motion;
      if (odometry && std::llabs(odometry->utime - scan.utime) < 500000)
        motion = sensorMotionFromBaseTwist(scan.laser_pose, odometry->v, odometry->omega);
      FeatureSet features = extractor.extract(scan, {}, motion);
      features.seq = out_seq++;
      context.publish(features_channel, toLcm(features));
      context.handled();
    });
    if (!odometry_channel.empty())
      context.subscribeConverted<polarslam::odometry_t, OdometryReading>(odometry_channel, [&](OdometryReading& reading) {
        odometry = reading;
        context.handled();
      });
    context.run();
  } catch (const std::exception& e) {
    std::cerr << "polarslam-features: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
