#include "eval/ate.hpp"

#include <cmath>
#include <stdexcept>

#include "eval/trajectory_lookup.hpp"

namespace polarslam {
namespace {

Vec2 centroid(const std::vector<Vec2>& points) {
  Vec2 sum = Vec2::Zero();
  for (const Vec2& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

struct PoseErrors {
  std::vector<double> translation, rotation_deg;
};

PoseErrors poseErrors(const std::vector<Pose2>& estimate, const std::vector<Pose2>& truth, const Pose2& transform) {
  PoseErrors errors;
  for (size_t i = 0; i < estimate.size(); ++i) {
    const Pose2 moved = transform * estimate[i];
    errors.translation.push_back((moved.translation() - truth[i].translation()).norm());
    errors.rotation_deg.push_back(std::abs(rad2deg(wrapAngle(moved.theta - truth[i].theta))));
  }
  return errors;
}

}  // namespace

Pose2 alignRigid2d(const std::vector<Vec2>& source, const std::vector<Vec2>& target) {
  if (source.size() != target.size() || source.empty())
    throw std::invalid_argument("alignRigid2d: needs equally many source and target points, at least one");
  const Vec2 source_mean = centroid(source), target_mean = centroid(target);
  // Rotation angle maximising Σ bᵢ·R aᵢ over the centred points: atan2(Σ aᵢ×bᵢ, Σ aᵢ·bᵢ).
  double cross = 0.0, dot = 0.0;
  for (size_t i = 0; i < source.size(); ++i) {
    const Vec2 a = source[i] - source_mean, b = target[i] - target_mean;
    cross += a.x() * b.y() - a.y() * b.x();
    dot += a.dot(b);
  }
  const double angle = (cross == 0.0 && dot == 0.0) ? 0.0 : std::atan2(cross, dot);
  const Pose2 rotation(0.0, 0.0, angle);
  const Vec2 t = target_mean - rotation.transform(source_mean);
  return {t.x(), t.y(), angle};
}

AteResult evaluateAte(const std::vector<PoseStamped>& estimate, const std::vector<PoseStamped>& ground_truth,
                      const AteOptions& options) {
  const TrajectoryLookup truth_lookup(ground_truth);
  AteResult result;
  result.estimated = estimate.size();
  std::vector<Pose2> estimated_poses, true_poses;
  for (const PoseStamped& p : estimate) {
    const std::optional<Pose2> truth = truth_lookup.interpolate(p.utime, options.max_time_difference_us);
    if (!truth) continue;
    estimated_poses.push_back(p.pose);
    true_poses.push_back(*truth);
  }
  result.matched = estimated_poses.size();
  result.unmatched = result.estimated - result.matched;
  if (estimated_poses.empty()) {
    result.raw_translation = result.raw_rotation_deg = summarizeErrors({});
    result.aligned_translation = result.aligned_rotation_deg = summarizeErrors({});
    return result;
  }
  std::vector<Vec2> source, target;
  for (size_t i = 0; i < estimated_poses.size(); ++i) {
    source.push_back(estimated_poses[i].translation());
    target.push_back(true_poses[i].translation());
  }
  result.alignment = alignRigid2d(source, target);
  PoseErrors raw = poseErrors(estimated_poses, true_poses, Pose2());
  PoseErrors aligned = poseErrors(estimated_poses, true_poses, result.alignment);
  result.raw_translation = summarizeErrors(std::move(raw.translation));
  result.raw_rotation_deg = summarizeErrors(std::move(raw.rotation_deg));
  result.aligned_translation = summarizeErrors(std::move(aligned.translation));
  result.aligned_rotation_deg = summarizeErrors(std::move(aligned.rotation_deg));
  return result;
}

std::vector<PoseStamped> inStartFrame(std::vector<PoseStamped> poses) {
  if (poses.empty()) return poses;
  const Pose2 origin_inverse = poses.front().pose.inverse();
  for (PoseStamped& p : poses) p.pose = origin_inverse * p.pose;
  return poses;
}

}  // namespace polarslam
