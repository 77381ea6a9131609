// The final refinement of PSM SLAM (issue 19, docs/algorithms.md §18): the filter ties each
// reference scan to the graph by the one match it was made with (and the loop closures it took),
// so each carries that match's noise. At the end of a run every reference scan is matched
// against the other reference scans that overlap it, from where the optimised graph puts the
// two, and each good match that agrees with the graph becomes a refinement edge (robust loss,
// χ² rejection, like a loop closure), for the final optimisation to weigh.
#include <algorithm>
#include <chrono>
#include <set>
#include <utility>

#include "slam/psm_match.hpp"
#include "slam/psm_slam.hpp"

namespace polarslam {
namespace {

using NodePair = std::pair<int64_t, int64_t>;

std::set<NodePair> joinedPairs(const PoseGraph& graph) {
  std::set<NodePair> joined;
  for (const PoseGraphEdge& e : graph.edges()) joined.insert({std::min(e.from, e.to), std::max(e.from, e.to)});
  return joined;
}

struct RefinementEdge {
  int64_t from = 0, to = 0;
  Pose2 z;
  Mat3 R;
};

}  // namespace

std::vector<int64_t> PsmSlam::refinementPartners(const Keyframe& current,
                                                 const std::set<std::pair<int64_t, int64_t>>& joined) const {
  const GraphRefinementParams& p = params_.refinement;
  const Pose2 pose = graph_.node(current.id).pose;
  std::vector<std::pair<double, int64_t>> near;
  for (const Keyframe& other : keyframes_) {
    if (other.id >= current.id) break;
    if (other.scan.empty() || joined.count({other.id, current.id})) continue;
    const Pose2 relative = between(graph_.node(other.id).pose, pose);
    const double distance = relative.translation().norm();
    if (distance <= p.max_distance && std::abs(relative.theta) <= p.max_heading) near.emplace_back(distance, other.id);
  }
  std::sort(near.begin(), near.end());
  std::vector<int64_t> partners;
  for (const auto& [distance, id] : near) {
    if (partners.size() >= static_cast<size_t>(std::max(0, p.max_pairs_per_scan))) break;
    partners.push_back(id);
  }
  return partners;
}

std::optional<RobotFrameMatch> PsmSlam::refinementMatch(const Keyframe& reference, const Keyframe& current,
                                                        GraphRefinementSummary& summary) {
  const GraphRefinementParams& p = params_.refinement;
  const Pose2 guess = between(graph_.node(reference.id).pose, graph_.node(current.id).pose);
  ++summary.pairs;
  std::optional<RobotFrameMatch> m = matchInRobotFrame(matcher_, reference.scan, reference.laser_mount, current.scan,
                                                       current.laser_mount, guess, params_, false);
  if (!m || !(m->error_index <= p.max_error_index) || m->overlap < p.min_overlap || !m->R.allFinite()) {
    ++summary.poor;
    return std::nullopt;
  }
  const Pose2 miss = between(guess, m->z);
  if (miss.translation().norm() > p.agree_translation || std::abs(miss.theta) > p.agree_rotation) {
    ++summary.disagreed;
    return std::nullopt;
  }
  return m;
}

GraphRefinementSummary PsmSlam::refine() {
  GraphRefinementSummary summary;
  if (!params_.refinement.enabled || keyframes_.size() < 3) return summary;
  const auto start = std::chrono::steady_clock::now();
  optimize();
  const std::set<NodePair> joined = joinedPairs(graph_);
  const int64_t first_own = map_frozen_ ? map_keyframes_ : 0;  // a frozen map's scans stay as they are
  std::vector<RefinementEdge> found;
  for (const Keyframe& current : keyframes_) {
    if (current.scan.empty() || current.id < first_own) continue;
    const size_t first = found.size();
    for (const int64_t id : refinementPartners(current, joined))
      if (const auto m = refinementMatch(keyframe(id), current, summary)) found.push_back({id, current.id, m->z, m->R});
    // The matches share the scan's noise: together they carry about one match's information,
    // not one per edge (otherwise the chains outweigh the loop closures, which then get disowned).
    const double share = static_cast<double>(found.size() - first);
    for (size_t k = first; k < found.size(); ++k) found[k].R *= share;
  }
  for (const RefinementEdge& e : found) {
    const size_t before = graph_.edges().size();
    addGraphEdge(e.from, e.to, e.z, e.R, PoseGraphEdgeKind::Refinement);
    summary.edges += graph_.edges().size() - before;
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace polarslam
