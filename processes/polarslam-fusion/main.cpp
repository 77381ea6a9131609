// polarslam-fusion: LASER_FEATURES + SONAR (+ LASER for laser-aided sonar selection, + ODOMETRY to
// move sonar cycles to the laser scan's time) → FEATURES in the robot base frame (thesis §3.3).
// All the work is core/sonar/feature_fusion.hpp, the fusion stage of the EKF pipeline
// (core/pipeline/feature_pipeline.hpp); this only moves messages. --config: the same file as the
// other stages.
#include <CLI/CLI.hpp>

#include <iostream>

#include "common/program_info.hpp"
#include "pipeline/pipelines.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"
#include "pipeline/feature_pipeline.hpp"
#include "sonar/feature_fusion.hpp"

using namespace polarslam;

int main(int argc, char** argv) {
  CLI::App app{"polarslam-fusion: laser and advanced-sonar features fused into FEATURES"};
  addVersionFlag(app);
  std::string config, sensors = "fused";
  std::string laser_features_channel = "LASER_FEATURES", sonar_channel = "SONAR", laser_channel = "LASER",
              odometry_channel = "ODOMETRY", out_channel = "FEATURES";
  app.add_option("--config", config, "robot file or estimator file (see core/pipeline/feature_slam_estimator.hpp)")
      ->check(CLI::ExistingFile);
  app.add_option("--sensors", sensors, "laser | sonar | fused")->check(CLI::IsMember({"laser", "sonar", "fused"}))
      ->capture_default_str();
  ProcessOptions process_options;
  addProcessOptions(app, process_options);
  app.add_option("--laser-features-channel", laser_features_channel, "channel of the laser feature sets, laser frame (features_t)")->capture_default_str();
  app.add_option("--sonar-channel", sonar_channel, "channel of the advanced-sonar cycles (sonar_targets_t)")->capture_default_str();
  app.add_option("--laser-channel", laser_channel, "raw scans for laser-aided sonar selection")->capture_default_str();
  app.add_option("--odometry-channel", odometry_channel, "channel of the odometry (odometry_t)")->capture_default_str();
  app.add_option("--out-channel", out_channel, "channel of the fused feature sets, base frame (features_t)")->capture_default_str();
  addPrintConfigFlag(app, [&] { return effectiveConfigYaml("ekf", {sensors, config}); });
  CLI11_PARSE(app, argc, argv);

  try {
    const SlamSensors which = parseSlamSensors(sensors);
    const FeaturePipelineConfig cfg = loadFeaturePipelineConfig(config, which);
    ProcessContext context("polarslam-fusion", process_options);
    FeatureFusion fusion(cfg.fusion);
    int64_t out_seq = 0;
    bool stall_told = false;  // said once; the count is in the stats
    auto publishReady = [&] {
      if (!stall_told && fusion.stats().missing_laser_sets > 0) {
        std::cerr << "polarslam-fusion: went on without a scan's laser set (max_laser_lag_s); "
                     "is polarslam-features running?\n";
        stall_told = true;
      }
      for (FeatureSet& set : fusion.takeReady()) {
        set.seq = out_seq++;
        context.publish(out_channel, toLcm(set));
      }
    };
    context.subscribeConverted<polarslam::features_t, FeatureSet>(laser_features_channel, [&](FeatureSet& set) {
      if (!fusion.addLaserFeatures(set)) return context.reject("laser features: late or not in use");
      context.handled();
      publishReady();
    });
    context.subscribeConverted<polarslam::sonar_targets_t, SonarScan>(sonar_channel, [&](SonarScan& scan) {
      if (!fusion.addSonar(scan)) return context.reject("sonar: late or not in use");
      context.handled();
      publishReady();
    });
    context.subscribeConverted<polarslam::laser_scan_t, LaserScan>(laser_channel, [&](LaserScan& scan) {
      fusion.addLaserScan(scan);
      context.handled();
      publishReady();
    });
    context.subscribeConverted<polarslam::odometry_t, OdometryReading>(odometry_channel, [&](OdometryReading& reading) {
      if (!fusion.addOdometry(reading)) return context.reject("odometry: out of order");
      context.handled();
      publishReady();
    });
    context.run();
    fusion.flush();
    publishReady();
  } catch (const std::exception& e) {
    std::cerr << "polarslam-fusion: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
