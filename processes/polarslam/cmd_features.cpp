// polarslam features: laser features of every scan in an LCM log, one JSON object per line.
//   polarslam features --log run.lcmlog --out features.jsonl [--channel LASER] [--config FILE]
// The extraction is the live process's (polarslam-features): same core code, same options.
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "command_registry.hpp"
#include "common/laser_feature_options.hpp"
#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "common/progress.hpp"

namespace polarslam {
namespace {

struct FeaturesCommand {
  std::string log, out, channel = "LASER", odometry_channel = "ODOMETRY";
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
  return {{"utime", f.utime}, {"seq", f.seq}, {"lines", lines}, {"corners", corners}};
}

void runFeatures(const FeaturesCommand& cmd) {
  const LaserFeatureExtractor extractor(cmd.options.resolve());
  LcmLogReader reader(cmd.log);
  const std::string tmp = cmd.out + ".tmp";
  std::ofstream out(tmp);
  if (!out) throw std::runtime_error("cannot write " + tmp);
  ProgressBar progress("features");
  std::optional<OdometryReading> odometry;
  long scans = 0, bad = 0, lines = 0, corners = 0;
  LogEvent event;
  while (reader.next(event)) {
    progress.update(reader.progress());
    if (!cmd.odometry_channel.empty() && event.channel == cmd.odometry_channel) {
      polarslam::odometry_t msg;
      OdometryReading reading;
      if (event.decode(msg) && fromLcm(msg, reading).empty()) odometry = reading;
      continue;
    }
    if (event.channel != cmd.channel) continue;
    polarslam::laser_scan_t msg;
    LaserScan scan;
    if (!event.decode(msg) || !fromLcm(msg, scan).empty()) {
      ++bad;
      continue;
    }
    SensorMotion motion;
    if (odometry && std::llabs(odometry->utime - scan.utime) < 500000)
      motion = sensorMotionFromBaseTwist(scan.laser_pose, odometry->v, odometry->omega);
    const FeatureSet features = extractor.extract(scan, {}, motion);
    out << scanJson(features).dump() << '\n';
    ++scans;
    lines += static_cast<long>(features.lines.size());
    corners += static_cast<long>(features.corners.size());
  }
  progress.finish();
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
  sub.add_option("--out", cmd->out, "output JSON lines, one object per scan")->required();
  sub.add_option("--channel", cmd->channel, "laser channel")->capture_default_str();
  sub.add_option("--odometry-channel", cmd->odometry_channel, "speed for the motion error term; \"\" = none")
      ->capture_default_str();
  cmd->options.add(sub);
  sub.callback([cmd] { runFeatures(*cmd); });
}

const RegisterCommand kRegister("features", "Laser line and corner features of every scan of a log (JSON lines)",
                                setupFeatures);

}  // namespace
}  // namespace polarslam
