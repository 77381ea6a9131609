// The EKF pipeline's one definition: the configuration file the processes and `polarslam run`
// read, the laser feature stage (break hints from the sonar), and the estimator's two
// trajectories (online at scan time, final regenerated in the final map) on a simulated run.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>

#include "source_path.hpp"
#include "eval/ate.hpp"
#include "pipeline/feature_slam_estimator.hpp"
#include "sim/simulator.hpp"

namespace polarslam {
namespace {

using testing::sourcePath;

TEST(FeaturePipelineConfig, TheShippedFileHoldsTheDefaultsOfTheDefaultRobot) {
  const FeaturePipelineConfig file = loadFeaturePipelineConfig(sourcePath("config/ekf.yaml"), SlamSensors::Fused);
  const FeaturePipelineConfig robot = loadFeaturePipelineConfig(sourcePath("config/robots/default.yaml"), SlamSensors::Fused);
  const FeaturePipelineConfig defaults;
  EXPECT_EQ(file.slam.association.gate_probability, defaults.slam.association.gate_probability);
  EXPECT_EQ(file.slam.new_feature_probability, defaults.slam.new_feature_probability);
  EXPECT_EQ(file.slam.tentative_gate_probability, defaults.slam.tentative_gate_probability);
  EXPECT_EQ(file.slam.confirm_observations, defaults.slam.confirm_observations);
  EXPECT_EQ(file.slam.tentative_timeout_s, defaults.slam.tentative_timeout_s);
  EXPECT_EQ(file.slam.max_line_extent_gap, defaults.slam.max_line_extent_gap);
  EXPECT_EQ(file.slam.anchor_radius, defaults.slam.anchor_radius);
  EXPECT_EQ(file.slam.max_anchors, defaults.slam.max_anchors);
  EXPECT_EQ(file.slam.latency_s, defaults.slam.latency_s);
  EXPECT_EQ(file.slam.association.ambiguity_nis_margin, defaults.slam.association.ambiguity_nis_margin);
  EXPECT_EQ(file.slam.association.max_nodes, defaults.slam.association.max_nodes);
  EXPECT_EQ(file.fusion.fusion.gate_probability, defaults.fusion.fusion.gate_probability);
  EXPECT_EQ(file.fusion.max_sonar_offset_s, defaults.fusion.max_sonar_offset_s);
  EXPECT_EQ(file.fusion.sonar_wait_s, defaults.fusion.sonar_wait_s);
  EXPECT_EQ(file.fusion.laser_wait_s, defaults.fusion.laser_wait_s);
  // The robot it names is the default robot: the same error models as the robot file itself.
  EXPECT_EQ(file.laser.errors.range.noise_sigma, robot.laser.errors.range.noise_sigma);
  EXPECT_EQ(file.laser.errors.range.fixed_bias, robot.laser.errors.range.fixed_bias);
  EXPECT_EQ(file.slam.odometry.wheels.wheelbase, robot.slam.odometry.wheels.wheelbase);
  EXPECT_EQ(file.fusion.sonar.range_sigma_floor, robot.fusion.sonar.range_sigma_floor);
  EXPECT_TRUE(file.sonar_break_hints);
}

TEST(FeaturePipelineConfig, UnknownKeysAndOutOfRangeValuesNameTheFileAndLine) {
  const auto dir = std::filesystem::temp_directory_path();
  const auto path = (dir / ("polarslam-ekf-config-" + std::to_string(::getpid()) + ".yaml")).string();
  std::ofstream(path) << "ekf:\n  latency_s: 0.3\n  gate_probabilty: 0.9\n";
  try {
    loadFeaturePipelineConfig(path, SlamSensors::Fused);
    FAIL() << "a misspelt key was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("gate_probabilty"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "fusion:\n  sonar_wait_s: -1\n";
  EXPECT_THROW(loadFeaturePipelineConfig(path, SlamSensors::Fused), std::runtime_error);
  std::filesystem::remove(path);
}

/// A simulated run of the office world, every message kept in time order.
struct SimulatedRun : SimSink {
  std::vector<LaserScan> scans;
  std::vector<SonarScan> sonar;
  std::vector<OdometryReading> odometry;
  std::vector<PoseStamped> truth;
  std::vector<std::function<void(Estimator&)>> events;
  enum class Kind { Laser, Sonar, Odometry };
  std::vector<std::pair<Kind, size_t>> order;  ///< every message: its kind and index in its vector
  void onLaser(const LaserScan& s) override {
    order.emplace_back(Kind::Laser, scans.size());
    scans.push_back(s);
    events.push_back([s](Estimator& e) { e.onLaser(s); });
  }
  void onSonar(const SonarScan& s) override {
    order.emplace_back(Kind::Sonar, sonar.size());
    sonar.push_back(s);
    events.push_back([s](Estimator& e) { e.onSonar(s); });
  }
  void onOdometry(const OdometryReading& o) override {
    order.emplace_back(Kind::Odometry, odometry.size());
    odometry.push_back(o);
    events.push_back([o](Estimator& e) { e.onOdometry(o); });
  }
  void onGroundTruth(const PoseStamped& p) override { truth.push_back(p); }
};

const SimulatedRun& officeRun() {
  static const SimulatedRun run = [] {
    SimulatedRun r;
    Simulator sim(loadWorld(sourcePath("config/worlds/office.yaml")), loadRobotDescription(sourcePath("config/robots/default.yaml")), 5);
    while (sim.time() < 60.0 && !sim.finished()) sim.step(r);
    return r;
  }();
  return run;
}

TEST(LaserFeatureStage, FusedSensorsBreakLaserSegmentsWhereTheSonarSawCornersAndEdges) {
  const SimulatedRun& run = officeRun();
  const FeaturePipelineConfig fused = loadFeaturePipelineConfig(sourcePath("config/ekf.yaml"), SlamSensors::Fused);
  const FeaturePipelineConfig laser_only = loadFeaturePipelineConfig(sourcePath("config/ekf.yaml"), SlamSensors::Laser);
  LaserFeatureStage with_hints(fused), without(laser_only);
  EXPECT_TRUE(with_hints.usesSonar());
  EXPECT_FALSE(without.usesSonar());
  size_t o = 0, s = 0, scans_with_hints = 0;
  for (const LaserScan& scan : run.scans) {
    for (; o < run.odometry.size() && run.odometry[o].utime <= scan.utime; ++o) {
      with_hints.addOdometry(run.odometry[o]);
      without.addOdometry(run.odometry[o]);
    }
    for (; s < run.sonar.size() && run.sonar[s].utime <= scan.utime; ++s) {
      with_hints.addSonar(run.sonar[s]);
      without.addSonar(run.sonar[s]);
    }
    const FeatureSet hinted = with_hints.extract(scan);
    EXPECT_TRUE(without.extract(scan).break_hints.empty());
    if (hinted.break_hints.empty()) continue;
    ++scans_with_hints;
    for (double bearing : hinted.break_hints) EXPECT_TRUE(std::isfinite(bearing));
  }
  // The office has door frames and corners in sonar view most of the time.
  EXPECT_GT(scans_with_hints, run.scans.size() / 10);
}

TEST(FeatureSlamEstimator, FinalTrajectoryIsRegeneratedInTheFinalMapOnePosePerScan) {
  const SimulatedRun& run = officeRun();
  FeatureSlamEstimator ekf(loadFeaturePipelineConfig(sourcePath("config/ekf.yaml"), SlamSensors::Fused));
  for (const auto& event : run.events) event(ekf);
  nlohmann::json report;
  ekf.finish("", report);
  const auto& online = ekf.onlineTrajectory();
  const auto& final_poses = ekf.trajectory();
  ASSERT_EQ(online.size(), run.scans.size());
  ASSERT_EQ(final_poses.size(), run.scans.size());
  for (size_t i = 0; i < run.scans.size(); ++i) {
    EXPECT_EQ(online[i].utime, run.scans[i].utime);
    EXPECT_EQ(final_poses[i].utime, run.scans[i].utime);
  }
  const std::vector<PoseStamped> truth = inStartFrame(run.truth);
  const double online_ate = evaluateAte(online, truth).raw_translation.rmse;
  const double final_ate = evaluateAte(final_poses, truth).raw_translation.rmse;
  EXPECT_LT(final_ate, 0.05);
  EXPECT_LT(final_ate, online_ate * 1.25) << "online " << online_ate << " m, final " << final_ate << " m";
  // Regenerated, not copied: later map information moves the early poses.
  double moved = 0.0;
  for (size_t i = 0; i < online.size(); ++i)
    moved = std::max(moved, (online[i].pose.translation() - final_poses[i].pose.translation()).norm());
  EXPECT_GT(moved, 1e-4);
}

/// Messages that reach a stage `lag_us` of stream time after their own stamp, as from a process
/// that falls behind.
class LaggingLink {
 public:
  /// Each message is due `lag_us` after its stamp, plus up to `jitter_us` more (never before the
  /// one sent ahead of it).
  LaggingLink(int64_t lag_us, int64_t jitter_us = 0, uint64_t seed = 1) : lag_us_(lag_us), jitter_us_(jitter_us), rng_(seed) {}
  void send(const FeatureSet& set) {
    int64_t due = set.utime + lag_us_;
    if (jitter_us_ > 0) due += std::uniform_int_distribution<int64_t>(0, jitter_us_)(rng_);
    last_due_ = std::max(last_due_, due);
    queue_.push_back({last_due_, set});
  }
  /// Hands over everything due by stream time `now` (all of it when `now` is the end).
  template <typename Deliver>
  void release(int64_t now, Deliver deliver) {
    while (!queue_.empty() && queue_.front().first <= now) {
      const FeatureSet set = std::move(queue_.front().second);
      queue_.pop_front();
      deliver(set);
    }
  }

 private:
  int64_t lag_us_, jitter_us_;
  std::mt19937_64 rng_;
  int64_t last_due_ = std::numeric_limits<int64_t>::min();
  std::deque<std::pair<int64_t, FeatureSet>> queue_;
};

/// The three EKF stages run apart, as the live processes: LASER, SONAR and ODOMETRY reach each
/// stage at once, LASER_FEATURES reach the fusion and FEATURES the EKF `lag_s` late. Returns the
/// scan anchors' poses (the online trajectory).
std::vector<PoseStamped> runStagesApart(const SimulatedRun& run, const FeaturePipelineConfig& config, double lag_s,
                                        FeatureSlamStats* slam_stats = nullptr, FeatureFusionStats* fusion_stats = nullptr,
                                        double jitter_s = 0.0, uint64_t seed = 1) {
  LaserFeatureStage features(config);
  FeatureFusion fusion(config.fusion);
  FeatureSlam slam(config.slam);
  const auto lag_us = static_cast<int64_t>(lag_s * 1e6), jitter_us = static_cast<int64_t>(jitter_s * 1e6);
  LaggingLink laser_features(lag_us, jitter_us, seed), fused(lag_us / 2, jitter_us, seed + 1);
  std::vector<PoseStamped> poses;
  auto pass = [&](int64_t now) {
    laser_features.release(now, [&](const FeatureSet& set) { fusion.addLaserFeatures(set); });
    for (const FeatureSet& set : fusion.takeReady()) fused.send(set);
    fused.release(now, [&](const FeatureSet& set) { slam.addFeatures(set); });
    for (const ScanAnchors& a : slam.takeAnchors()) poses.push_back(a.pose);
  };
  for (const auto& [kind, i] : run.order) {
    int64_t now = 0;
    switch (kind) {
      case SimulatedRun::Kind::Odometry:
        features.addOdometry(run.odometry[i]);
        fusion.addOdometry(run.odometry[i]);
        slam.addOdometry(run.odometry[i]);
        now = run.odometry[i].utime;
        break;
      case SimulatedRun::Kind::Laser:
        slam.requestAnchors(run.scans[i].utime);
        fusion.addLaserScan(run.scans[i]);
        if (config.fusion.use_laser) laser_features.send(features.extract(run.scans[i]));
        now = run.scans[i].utime;
        break;
      case SimulatedRun::Kind::Sonar:
        features.addSonar(run.sonar[i]);
        if (config.fusion.use_sonar) fusion.addSonar(run.sonar[i]);
        now = run.sonar[i].utime;
        break;
    }
    pass(now);
  }
  pass(std::numeric_limits<int64_t>::max());
  fusion.flush();
  pass(std::numeric_limits<int64_t>::max());
  slam.flush();
  pass(std::numeric_limits<int64_t>::max());
  if (slam_stats) *slam_stats = slam.stats();
  if (fusion_stats) *fusion_stats = fusion.stats();
  return poses;
}

double largestDifference(const std::vector<PoseStamped>& a, const std::vector<PoseStamped>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i)
    worst = std::max({worst, (a[i].pose.translation() - b[i].pose.translation()).norm(),
                      std::abs(wrapAngle(a[i].pose.theta - b[i].pose.theta))});
  return worst;
}

// Live, LASER_FEATURES and FEATURES come from other processes, which fall behind on a loaded or
// slow machine (the sanitizer build, a busy robot computer): a scan's sets wait for them however
// late, so a lag of seconds gives the one-process result; only a stalled peer (no set within
// max_*_lag_s) makes the stages go on without it, counted.
TEST(FeatureSlamEstimator, StagesApartGiveTheOneProcessResultWhateverTheLagOfTheFeatureStreams) {
  const SimulatedRun& run = officeRun();
  const FeaturePipelineConfig config = loadFeaturePipelineConfig(sourcePath("config/ekf.yaml"), SlamSensors::Fused);
  FeatureSlamEstimator ekf(config);
  for (const auto& event : run.events) event(ekf);
  nlohmann::json report;
  ekf.finish("", report);
  const std::vector<PoseStamped>& one_process = ekf.onlineTrajectory();
  ASSERT_EQ(one_process.size(), run.scans.size());
  for (const double lag_s : {0.0, 0.1, 0.5, 2.0}) {
    FeatureSlamStats slam_stats;
    FeatureFusionStats fusion_stats;
    EXPECT_EQ(largestDifference(runStagesApart(run, config, lag_s, &slam_stats, &fusion_stats), one_process), 0.0)
        << "lag " << lag_s << " s";
    EXPECT_EQ(slam_stats.rejected_sets, 0) << "lag " << lag_s << " s";
    EXPECT_EQ(fusion_stats.late, 0) << "lag " << lag_s << " s";
    EXPECT_EQ(slam_stats.gave_up_waiting + fusion_stats.missing_laser_sets, 0) << "lag " << lag_s << " s";
  }
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    FeatureSlamStats slam_stats;
    FeatureFusionStats fusion_stats;
    EXPECT_EQ(largestDifference(runStagesApart(run, config, 0.2, &slam_stats, &fusion_stats, 1.0, seed), one_process), 0.0)
        << "lag 0.2 s + up to 1 s, seed " << seed;
    EXPECT_EQ(slam_stats.rejected_sets + fusion_stats.late, 0) << "seed " << seed;
  }
  // Beyond max_*_lag_s the peer counts as stalled: the stages go on without its sets and say so.
  FeaturePipelineConfig impatient = config;
  impatient.slam.max_feature_lag_s = impatient.fusion.max_laser_lag_s = 0.5;
  FeatureSlamStats slam_stats;
  FeatureFusionStats fusion_stats;
  EXPECT_GT(largestDifference(runStagesApart(run, impatient, 2.0, &slam_stats, &fusion_stats), one_process), 0.0);
  EXPECT_GT(slam_stats.gave_up_waiting, 0);
  EXPECT_GT(fusion_stats.missing_laser_sets, 0);
  EXPECT_GT(slam_stats.rejected_sets + fusion_stats.late, 0);
}

TEST(RecordedEstimator, AnchorsAndTheLastMapGiveTheOfflineFinalTrajectory) {
  const SimulatedRun& run = officeRun();
  FeatureSlamEstimator ekf(loadFeaturePipelineConfig("", SlamSensors::Fused));
  for (const auto& event : run.events) event(ekf);
  nlohmann::json report;
  ekf.finish("", report);
  RecordedEstimator recorded;
  for (const ScanAnchors& a : ekf.anchors()) recorded.onScanAnchors(a);
  recorded.onScanAnchors(ekf.anchors().front());  // a stale repeat: dropped and counted
  FeatureMap early = ekf.slam().map();
  early.features.resize(early.features.size() / 2);
  recorded.onFeatureMap(early);
  recorded.onFeatureMap(ekf.slam().map());  // the last map counts
  nlohmann::json recorded_report;
  recorded.finish("", recorded_report);
  ASSERT_EQ(recorded.trajectory().size(), ekf.trajectory().size());
  for (size_t i = 0; i < ekf.trajectory().size(); ++i) {
    EXPECT_NEAR(recorded.trajectory()[i].pose.x, ekf.trajectory()[i].pose.x, 1e-12);
    EXPECT_NEAR(recorded.trajectory()[i].pose.y, ekf.trajectory()[i].pose.y, 1e-12);
    EXPECT_NEAR(recorded.onlineTrajectory()[i].pose.x, ekf.onlineTrajectory()[i].pose.x, 1e-12);
  }
  EXPECT_EQ(recorded_report["recorded"]["out_of_order_dropped"], 1);
  EXPECT_EQ(recorded_report["recorded"]["maps"], 2);
}

}  // namespace
}  // namespace polarslam
