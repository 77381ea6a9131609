// polarslam eval: scores a TUM trajectory against Kümmerle relations (relation metric) or
// against the ground-truth poses of an LCM log (ATE, and the relation metric on relations taken
// from the ground truth). Prints JSON; fields are documented in core/eval/README.md.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

#include "command_registry.hpp"
#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "common/progress.hpp"
#include "eval/ate.hpp"
#include "eval/eval_json.hpp"
#include "eval/relation_metric.hpp"
#include "io/atomic_file.hpp"
#include "io/relations.hpp"
#include "io/text_fields.hpp"
#include "io/tum.hpp"

namespace polarslam {
namespace {

struct EvalOptions {
  std::string trajectory, relations, ground_truth, channel = "GROUND_TRUTH", ground_truth_frame = "start", out;
  double max_time_difference = 0.1;  ///< s
  double relation_spacing = 1.0;     ///< s, relations taken from ground truth
};

struct GroundTruthLog {
  std::vector<PoseStamped> poses;
  long undecodable = 0, invalid = 0;
};

int64_t secondsToUtime(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e6)); }

GroundTruthLog readGroundTruth(const std::string& path, const std::string& channel) {
  GroundTruthLog truth;
  LcmLogReader reader(path);
  ProgressBar progress("eval: reading " + channel);
  LogEvent event;
  while (reader.next(event)) {
    progress.update(reader.progress());
    if (event.channel != channel) continue;
    polarslam::pose_t msg;
    PoseStamped pose;
    if (!event.decode(msg)) {
      ++truth.undecodable;
    } else if (!fromLcm(msg, pose).empty()) {
      ++truth.invalid;
    } else {
      truth.poses.push_back(pose);
    }
  }
  progress.finish();
  reader.printWarnings();
  if (truth.poses.empty())
    throw std::runtime_error("no valid pose_t messages on channel " + channel + " in '" + path + "'");
  return truth;
}

void warnIfNothingEvaluated(const RelationMetric& metric, const std::vector<PoseStamped>& trajectory,
                            const std::vector<Relation>& relations) {
  if (metric.evaluated > 0 || relations.empty() || trajectory.empty()) return;
  const auto [first, last] = std::minmax_element(
      trajectory.begin(), trajectory.end(), [](const PoseStamped& a, const PoseStamped& b) { return a.utime < b.utime; });
  std::cerr << "polarslam eval: warning: no relation has estimated poses within the time tolerance; "
               "trajectory spans " << formatUtimeAsSeconds(first->utime) << " .. "
            << formatUtimeAsSeconds(last->utime) << " s, relations start at "
            << formatUtimeAsSeconds(relations.front().t1) << " s (different time base?)\n";
}

nlohmann::json relationSection(const std::vector<PoseStamped>& trajectory, const std::vector<Relation>& relations,
                                const EvalOptions& o) {
  RelationMetricOptions options;
  options.max_time_difference_us = secondsToUtime(o.max_time_difference);
  const RelationMetric metric = evaluateRelations(trajectory, relations, options);
  warnIfNothingEvaluated(metric, trajectory, relations);
  nlohmann::json section = relationMetricJson(metric);
  section["max_time_difference_s"] = o.max_time_difference;
  return section;
}

nlohmann::json evaluate(const EvalOptions& o) {
  const std::vector<PoseStamped> trajectory = readTumTrajectory(o.trajectory);
  if (trajectory.empty()) throw std::runtime_error("no poses in '" + o.trajectory + "'");
  nlohmann::json result;
  result["trajectory"] = {{"file", o.trajectory}, {"poses", trajectory.size()}};
  if (!o.relations.empty()) {
    nlohmann::json section = relationSection(trajectory, readRelations(o.relations), o);
    section["source"] = o.relations;
    result["relation_metric"] = section;
    return result;
  }
  GroundTruthLog truth = readGroundTruth(o.ground_truth, o.channel);
  if (o.ground_truth_frame == "start") truth.poses = inStartFrame(std::move(truth.poses));
  result["ground_truth"] = {{"file", o.ground_truth},   {"channel", o.channel},
                            {"poses", truth.poses.size()}, {"undecodable", truth.undecodable},
                            {"invalid", truth.invalid},  {"frame", o.ground_truth_frame}};
  AteOptions ate_options;
  ate_options.max_time_difference_us = secondsToUtime(o.max_time_difference);
  result["ate"] = ateJson(evaluateAte(trajectory, truth.poses, ate_options));
  result["ate"]["max_time_difference_s"] = o.max_time_difference;
  nlohmann::json section =
      relationSection(trajectory, relationsFromGroundTruth(truth.poses, secondsToUtime(o.relation_spacing)), o);
  section["source"] = "ground_truth";
  section["spacing_s"] = o.relation_spacing;
  result["relation_metric"] = section;
  return result;
}

void runEval(const EvalOptions& o) {
  const std::string text = evaluate(o).dump(2) + "\n";
  if (!o.out.empty()) writeFileAtomically(o.out, text);
  std::cout << text;
}

void setupEval(CLI::App& sub) {
  auto o = std::make_shared<EvalOptions>();
  sub.add_option("--trajectory,-t", o->trajectory, "estimated trajectory, TUM format")
      ->required()->check(CLI::ExistingFile);
  auto* relations = sub.add_option("--relations,-r", o->relations, "Kümmerle relations file (t1 t2 x y z roll pitch yaw)")
                        ->check(CLI::ExistingFile);
  auto* truth = sub.add_option("--ground-truth,-g", o->ground_truth, "LCM log with pose_t ground truth")
                    ->check(CLI::ExistingFile);
  relations->excludes(truth);
  truth->excludes(relations);
  sub.add_option("--ground-truth-channel", o->channel, "pose_t channel of the ground truth in the --ground-truth log")->capture_default_str();
  sub.add_option("--ground-truth-frame", o->ground_truth_frame,
                 "start: ground truth re-expressed in the frame of its first pose, as `polarslam run` "
                 "estimates are; world: as logged")
      ->check(CLI::IsMember({"start", "world"}))->capture_default_str();
  sub.add_option("--max-time-difference", o->max_time_difference,
                 "s: an estimated pose farther than this from a relation's or ground truth's time is not used")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub.add_option("--relation-spacing", o->relation_spacing, "s: spacing of relations taken from ground truth")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub.add_option("--out,-o", o->out, "also write the JSON to this file");
  sub.callback([o, relations, truth] {
    if (relations->count() == 0 && truth->count() == 0)
      throw std::runtime_error("needs --relations R or --ground-truth X.lcmlog");
    runEval(*o);
  });
}

RegisterCommand reg_eval("eval", "Score a TUM trajectory: relation metric (Kümmerle 2009) and ATE against ground truth",
                    setupEval);

}  // namespace
}  // namespace polarslam
