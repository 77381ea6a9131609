// polarslam-features: LASER → LASER_FEATURES. Polar lines and right-angle corners with their
// error model (thesis chapter 2), in the laser frame: the laser feature stage of the EKF pipeline
// (core/pipeline/feature_pipeline.hpp), configured by the same --config file as polarslam-fusion,
// polarslam-ekf-slam and `polarslam run --pipeline ekf`. With fused sensors it reads SONAR for
// the break hints at sonar corners and edges; ODOMETRY supplies the robot's speed for the
// motion-during-scan term and moves the sonar cycles to the scan's time.
#include <CLI/CLI.hpp>

#include <iostream>

#include "common/program_info.hpp"
#include "pipeline/pipelines.hpp"
#include "common/laser_feature_options.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"
#include "pipeline/feature_pipeline.hpp"

using namespace polarslam;

int main(int argc, char** argv) {
  CLI::App app{"polarslam-features: laser scans to polar line and right-angle corner features"};
  addVersionFlag(app);
  std::string sensors = "fused", laser_channel = "LASER", features_channel = "LASER_FEATURES",
                   odometry_channel = "ODOMETRY", sonar_channel = "SONAR";
  LaserFeatureOptions options;
  options.add(app);
  app.add_option("--sensors", sensors, "laser | sonar | fused (fused: sonar break hints)")
      ->check(CLI::IsMember({"laser", "sonar", "fused"}))->capture_default_str();
  ProcessOptions process_options;
  addProcessOptions(app, process_options);
  app.add_option("--laser-channel", laser_channel, "channel of the laser scans (laser_scan_t)")->capture_default_str();
  app.add_option("--features-channel", features_channel, "channel of the feature sets (features_t)")->capture_default_str();
  app.add_option("--odometry-channel", odometry_channel, "speed for the motion error term; \"\" = none")
      ->capture_default_str();
  app.add_option("--sonar-channel", sonar_channel, "sonar cycles for break hints (fused sensors)")->capture_default_str();
  addPrintConfigFlag(app, [&] { return effectiveConfigYaml("ekf", {sensors, options.configPath()}); });
  CLI11_PARSE(app, argc, argv);

  try {
    LaserFeatureStage stage(options.resolvePipeline(parseSlamSensors(sensors)));
    ProcessContext context("polarslam-features", process_options);
    int64_t out_seq = 0;
    context.subscribeConverted<polarslam::laser_scan_t, LaserScan>(laser_channel, [&](LaserScan& scan) {
      FeatureSet features = stage.extract(scan);
      features.seq = out_seq++;
      context.publish(features_channel, toLcm(features));
      context.handled();
    });
    if (!odometry_channel.empty())
      context.subscribeConverted<polarslam::odometry_t, OdometryReading>(odometry_channel, [&](OdometryReading& reading) {
        if (!stage.addOdometry(reading)) return context.reject("odometry: non-finite or out of order");
        context.handled();
      });
    if (stage.usesSonar() && !sonar_channel.empty())
      context.subscribeConverted<polarslam::sonar_targets_t, SonarScan>(sonar_channel, [&](SonarScan& scan) {
        stage.addSonar(scan);
        context.handled();
      });
    context.run();
  } catch (const std::exception& e) {
    std::cerr << "polarslam-features: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
