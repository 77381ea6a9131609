// polarslam-ekf-slam: ODOMETRY + FEATURES → SLAM_POSE (pose_t), SLAM_MAP (slam_map_t) and
// SCAN_ANCHORS (scan_anchors_t, one per LASER scan) — EKF feature SLAM of thesis §3.5–§3.7.
// All the work is core/slam/feature_slam.hpp, the last stage of the EKF pipeline
// (core/pipeline/feature_pipeline.hpp); this only moves messages. On exit it publishes its final
// SLAM_MAP: with the SCAN_ANCHORS it gives every scan's final pose (pose regeneration). LASER is read for its
// time stamps only: each scan gets the anchors the grid process regenerates its pose from.
#include <CLI/CLI.hpp>

#include <iostream>

#include "common/program_info.hpp"
#include "pipeline/pipelines.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"
#include "slam/feature_slam.hpp"
#include "pipeline/feature_pipeline.hpp"

using namespace polarslam;

int main(int argc, char** argv) {
  CLI::App app{"polarslam-ekf-slam: EKF SLAM with line, corner and point features"};
  addVersionFlag(app);
  std::string config;
  std::string odometry_channel = "ODOMETRY", features_channel = "FEATURES", laser_channel = "LASER",
              pose_channel = "SLAM_POSE", map_channel = "SLAM_MAP", anchors_channel = "SCAN_ANCHORS";
  double map_period = 1.0;
  app.add_option("--config", config, "robot file or estimator file (see core/pipeline/feature_slam_estimator.hpp)")
      ->check(CLI::ExistingFile);
  ProcessOptions process_options;
  addProcessOptions(app, process_options);
  app.add_option("--odometry-channel", odometry_channel, "channel of the odometry (odometry_t)")->capture_default_str();
  app.add_option("--features-channel", features_channel, "channel of the feature sets (features_t)")->capture_default_str();
  app.add_option("--laser-channel", laser_channel, "scan time stamps for SCAN_ANCHORS ('' = none)")->capture_default_str();
  app.add_option("--pose-channel", pose_channel, "channel of the robot poses (pose_t)")->capture_default_str();
  app.add_option("--map-channel", map_channel, "channel of the feature map (slam_map_t)")->capture_default_str();
  app.add_option("--anchors-channel", anchors_channel, "channel of the scan anchors (scan_anchors_t)")->capture_default_str();
  app.add_option("--map-period", map_period, "s between SLAM_MAP messages (stream time)")->check(CLI::PositiveNumber)
      ->capture_default_str();
  JournalOptions journal;
  addJournalOptions(app, journal);
  addPrintConfigFlag(app, [&] { return effectiveConfigYaml("ekf", {"fused", config}); });
  CLI11_PARSE(app, argc, argv);

  try {
    const FeaturePipelineConfig cfg = loadFeaturePipelineConfig(config, SlamSensors::Fused);
    ProcessContext context("polarslam-ekf-slam", process_options);
    context.enableJournal(journal);
    FeatureSlam slam(cfg.slam);
    int64_t pose_seq = 0, map_seq = 0, anchor_seq = 0, last_map_utime = 0;
    const int64_t map_period_us = static_cast<int64_t>(map_period * 1e6);
    bool stall_told = false;  // said once; the count is in the stats
    auto publishOutputs = [&] {
      if (!stall_told && slam.stats().gave_up_waiting > 0) {
        std::cerr << "polarslam-ekf-slam: went on without a scan's feature set (max_feature_lag_s); "
                     "is polarslam-fusion running?\n";
        stall_told = true;
      }
      for (const ScanAnchors& a : slam.takeAnchors()) context.publish(anchors_channel, toLcm(a, anchor_seq++));
      slam.takePoses();  // the live pose below already includes them
      slam.takeMatches();
      if (!slam.started()) return;  // nothing received yet that gives the pose a time
      const PoseStamped pose = slam.currentPose();
      context.publish(pose_channel, toLcm(pose, "map", pose_seq++));
      if (slam.filterTime() - last_map_utime >= map_period_us) {  // the map is made only when due
        context.publish(map_channel, toLcm(slam.map(), map_seq++));
        last_map_utime = slam.filterTime();
      }
    };
    auto rejectIf = [&](const std::string& why) {
      if (why.empty()) return false;
      context.reject(why);
      return true;
    };
    context.subscribeConverted<polarslam::odometry_t, OdometryReading>(odometry_channel, [&](OdometryReading& reading) {
      if (rejectIf(slam.addOdometry(reading))) return;
      context.handled();
      publishOutputs();
    });
    context.subscribeConverted<polarslam::features_t, FeatureSet>(features_channel, [&](FeatureSet& set) {
      if (rejectIf(slam.addFeatures(set))) return;
      context.handled();
      publishOutputs();
    });
    if (!laser_channel.empty())
      context.subscribe<polarslam::laser_scan_t>(laser_channel, [&](const polarslam::laser_scan_t& msg) {
        if (rejectIf(slam.requestAnchors(msg.utime))) return;
        context.handled();
        publishOutputs();
      }, Stamps::StreamTime);
    context.run();
    slam.flush();
    publishOutputs();
    context.publish(map_channel, toLcm(slam.map(), map_seq++));
  } catch (const std::exception& e) {
    std::cerr << "polarslam-ekf-slam: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
