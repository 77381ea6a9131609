#include "eval/relation_metric.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "eval/trajectory_lookup.hpp"

namespace polarslam {
namespace {

RelationError relationError(const PoseStamped& p1, const PoseStamped& p2, const Relation& r) {
  RelationError e;
  e.estimate_t1 = p1.utime;
  e.estimate_t2 = p2.utime;
  e.estimated_motion = between(p1.pose, p2.pose);
  // The estimate is planar: its z, roll and pitch are zero.
  const double dx = e.estimated_motion.x - r.x, dy = e.estimated_motion.y - r.y, dz = -r.z;
  const double droll = wrapAngle(-r.roll), dpitch = wrapAngle(-r.pitch);
  const double dyaw = wrapAngle(e.estimated_motion.theta - r.yaw);
  e.translation = std::sqrt(dx * dx + dy * dy + dz * dz);
  e.rotation_deg = rad2deg(std::sqrt(droll * droll + dpitch * dpitch + dyaw * dyaw));
  return e;
}

}  // namespace

RelationMetric evaluateRelations(const std::vector<PoseStamped>& trajectory, const std::vector<Relation>& relations,
                                 const RelationMetricOptions& options) {
  const TrajectoryLookup lookup(trajectory);
  RelationMetric metric;
  metric.relations = relations.size();
  std::vector<double> translation, rotation, translation_sq, rotation_sq;
  for (size_t i = 0; i < relations.size(); ++i) {
    const PoseStamped* p1 = lookup.nearest(relations[i].t1, options.max_time_difference_us);
    const PoseStamped* p2 = lookup.nearest(relations[i].t2, options.max_time_difference_us);
    if (!p1 || !p2) continue;
    RelationError e = relationError(*p1, *p2, relations[i]);
    e.relation_index = i;
    translation.push_back(e.translation);
    rotation.push_back(e.rotation_deg);
    translation_sq.push_back(e.translation * e.translation);
    rotation_sq.push_back(e.rotation_deg * e.rotation_deg);
    metric.errors.push_back(e);
  }
  metric.evaluated = metric.errors.size();
  metric.skipped_no_pose = metric.relations - metric.evaluated;
  metric.translation = summarizeErrors(std::move(translation));
  metric.rotation_deg = summarizeErrors(std::move(rotation));
  metric.translation_squared = summarizeErrors(std::move(translation_sq));
  metric.rotation_squared = summarizeErrors(std::move(rotation_sq));
  return metric;
}

RelationConsistency relationConsistency(const std::vector<Relation>& relations) {
  // Each pose's relations, both ways: (other pose's time, motion from this pose to it, relation index).
  struct Leg {
    int64_t to = 0;
    Pose2 motion;
    size_t index = 0;
  };
  std::map<int64_t, std::vector<Leg>> legs;
  for (size_t i = 0; i < relations.size(); ++i) {
    const Relation& r = relations[i];
    if (r.t1 == r.t2) continue;
    legs[r.t1].push_back({r.t2, r.motion(), i});
    legs[r.t2].push_back({r.t1, r.motion().inverse(), i});
  }
  RelationConsistency out;
  std::set<size_t> members;
  std::vector<double> translation, rotation;
  for (size_t i = 0; i < relations.size(); ++i) {  // each triangle once: by its relation of lowest index
    const Relation& direct = relations[i];
    if (direct.t1 == direct.t2) continue;
    for (const Leg& first : legs[direct.t1]) {
      if (first.index <= i || first.to == direct.t2) continue;
      for (const Leg& second : legs[first.to]) {
        if (second.to != direct.t2 || second.index <= i || second.index == first.index) continue;
        const Pose2 miss = between(direct.motion(), first.motion * second.motion);
        translation.push_back(miss.translation().norm());
        rotation.push_back(rad2deg(std::abs(wrapAngle(miss.theta))));
        members.insert({i, first.index, second.index});
      }
    }
  }
  out.triangles = translation.size();
  out.relations.assign(members.begin(), members.end());
  out.translation = summarizeErrors(std::move(translation));
  out.rotation_deg = summarizeErrors(std::move(rotation));
  out.per_relation_translation = out.translation.mean / std::sqrt(3.0);
  return out;
}

std::vector<Relation> relationsFromGroundTruth(const std::vector<PoseStamped>& ground_truth, int64_t spacing_us) {
  const TrajectoryLookup sorted(ground_truth);
  const std::vector<PoseStamped>& poses = sorted.poses();
  std::vector<Relation> relations;
  size_t from = 0;
  for (size_t to = 1; to < poses.size(); ++to) {
    if (poses[to].utime - poses[from].utime < std::max<int64_t>(spacing_us, 1)) continue;
    const Pose2 motion = between(poses[from].pose, poses[to].pose);
    Relation r;
    r.t1 = poses[from].utime;
    r.t2 = poses[to].utime;
    r.x = motion.x;
    r.y = motion.y;
    r.yaw = motion.theta;
    relations.push_back(r);
    from = to;
  }
  return relations;
}

}  // namespace polarslam
