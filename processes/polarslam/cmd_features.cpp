// polarslam features: laser features of every scan in an LCM log, one JSON object per line.
//   polarslam features --log run.lcmlog -o features.jsonl [--laser-channel LASER] [--config FILE]
// The extraction is the live process's (polarslam-features): the same LaserFeatureStage, fed
// LASER, SONAR (break hints, fused sensors) and ODOMETRY in log order, with the same options.
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "command_registry.hpp"
#include "common/laser_feature_options.hpp"
#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "common/progress.hpp"

namespace polarslam {
namespace {

struct FeaturesCommand {
  std::string log, out, channel = "LASER", odometry_channel = "ODOMETRY", sonar_channel = "SONAR", sensors = "fused";
  LaserFeatureOptions options;
};

template <int N>
nlohmann::ordered_json matrixJson(const Eigen::Matrix<double, N, N>& m) {
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (int r = 0; r < N; ++r) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (int c = 0; c < N; ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

nlohmann::ordered_json lineJson(const LineFeature& l) {
  return {{"alpha", l.alpha},
          {"d", l.d},
          {"cov", matrixJson<2>(l.cov)},
          {"random_cov", matrixJson<2>(l.random_cov)},
          {"systematic_bound", {l.systematic_bound.x(), l.systematic_bound.y()}},
          {"endpoints", {{l.endpoint_a.x(), l.endpoint_a.y()}, {l.endpoint_b.x(), l.endpoint_b.y()}}},
          {"n", l.num_points},
          {"first_index", l.first_index},
          {"last_index", l.last_index}};
}

nlohmann::ordered_json cornerJson(const CornerFeature& c) {
  return {{"x", c.x}, {"y", c.y}, {"gamma", c.gamma}, {"convex", c.convex}, {"cov", matrixJson<3>(c.cov)},
          {"n", c.num_points}};
}

nlohmann::ordered_json scanJson(const FeatureSet& f) {
  nlohmann::ordered_json lines = nlohmann::ordered_json::array(), corners = nlohmann::ordered_json::array();
  for (const LineFeature& l : f.lines) lines.push_back(lineJson(l));
  for (const CornerFeature& c : f.corners) corners.push_back(cornerJson(c));
  return {{"utime", f.utime}, {"seq", f.seq}, {"lines", lines}, {"corners", corners}, {"break_hints", f.break_hints}};
}

void runFeatures(const FeaturesCommand& cmd) {
  LaserFeatureStage stage(cmd.options.resolvePipeline(parseSlamSensors(cmd.sensors)));
  LcmLogReader reader(cmd.log);
  const std::string tmp = cmd.out + ".tmp";
  std::ofstream out(tmp);
  if (!out) throw std::runtime_error("cannot write " + tmp);
  ProgressBar progress("features");
  long scans = 0, bad = 0, lines = 0, corners = 0;
  LogEvent event;
  while (reader.next(event)) {
    progress.update(reader.progress());
    if (!cmd.odometry_channel.empty() && event.channel == cmd.odometry_channel) {
      polarslam::odometry_t msg;
      OdometryReading reading;
      if (event.decode(msg) && fromLcm(msg, reading).empty()) stage.addOdometry(reading);
      continue;
    }
    if (stage.usesSonar() && event.channel == cmd.sonar_channel) {
      polarslam::sonar_targets_t msg;
      SonarScan sonar;
      if (event.decode(msg) && fromLcm(msg, sonar).empty()) stage.addSonar(sonar);
      continue;
    }
    if (event.channel != cmd.channel) continue;
    polarslam::laser_scan_t msg;
    LaserScan scan;
    if (!event.decode(msg) || !fromLcm(msg, scan).empty()) {
      ++bad;
      continue;
    }
    const FeatureSet features = stage.extract(scan);
    out << scanJson(features).dump() << '\n';
    ++scans;
    lines += static_cast<long>(features.lines.size());
    corners += static_cast<long>(features.corners.size());
  }
  progress.finish();
  reader.printWarnings();
  out.close();
  if (!out) throw std::runtime_error("error writing " + tmp);
  std::filesystem::rename(tmp, cmd.out);
  std::cerr << "polarslam features: " << scans << " scans, " << lines << " lines, " << corners << " corners";
  if (bad > 0) std::cerr << ", " << bad << " unusable scans skipped";
  std::cerr << " -> " << cmd.out << "\n";
  if (scans == 0) throw std::runtime_error("no laser scans on channel " + cmd.channel + " in " + cmd.log);
}

void setupFeatures(CLI::App& sub) {
  auto cmd = std::make_shared<FeaturesCommand>();
  sub.add_option("--log", cmd->log, "input LCM log")->required()->check(CLI::ExistingFile);
  sub.add_option("-o,--out", cmd->out, "output JSON lines, one object per scan")->required();
  sub.add_option("--laser-channel", cmd->channel, "channel of the laser scans (laser_scan_t)")->capture_default_str();
  sub.add_option("--odometry-channel", cmd->odometry_channel, "speed for the motion error term; \"\" = none")
      ->capture_default_str();
  sub.add_option("--sonar-channel", cmd->sonar_channel, "sonar cycles for break hints (fused sensors)")
      ->capture_default_str();
  sub.add_option("--sensors", cmd->sensors, "laser | sonar | fused (fused: sonar break hints)")
      ->check(CLI::IsMember({"laser", "sonar", "fused"}))->capture_default_str();
  cmd->options.add(sub);
  sub.callback([cmd] { runFeatures(*cmd); });
}

RegisterCommand reg_features("features", "Laser line and corner features of every scan of a log (JSON lines)",
                                setupFeatures);

}  // namespace
}  // namespace polarslam
