// The refinement of PSM SLAM (issue 19, docs/algorithms.md §18): the filter ties each reference
// scan to the graph by the one match it was made with (and the loop closures it took), so each
// carries that match's noise. Every reference scan is matched against the other reference scans
// that overlap it, from where the optimised graph puts the two, and each good match that agrees
// with the graph becomes a refinement edge (robust loss, χ² rejection, like a loop closure).
// With `online`, after each loop-closure optimisation the pairs of reference scans the filter no
// longer holds are matched in the background, and their edges join the graph at the next one (a
// fixed point in the scan sequence: live and offline agree); at the end of a run the pairs not
// yet tried are matched before the final optimisation.
#include <algorithm>
#include <chrono>
#include <map>
#include <set>
#include <utility>

#include "slam/psm_match.hpp"
#include "slam/psm_slam.hpp"

namespace polarslam {
namespace {

std::set<NodePair> joinedPairs(const PoseGraph& graph) {
  std::set<NodePair> joined;
  for (const PoseGraphEdge& e : graph.edges()) joined.insert({std::min(e.from, e.to), std::max(e.from, e.to)});
  return joined;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// A good match that agrees with the graph's relative pose `guess`, or nothing (counted).
std::optional<RobotFrameMatch> refinementMatch(ScanMatcher& matcher, const RefinementScan& reference,
                                               const RefinementScan& current, const Pose2& guess,
                                               const PsmSlamParams& params, GraphRefinementSummary& counts) {
  const GraphRefinementParams& p = params.refinement;
  ++counts.pairs;
  std::optional<RobotFrameMatch> m =
      matchInRobotFrame(matcher, reference.scan, reference.mount, current.scan, current.mount, guess, params, false);
  if (!m || !(m->error_index <= p.max_error_index) || m->overlap < p.min_overlap || !m->R.allFinite()) {
    ++counts.poor;
    return std::nullopt;
  }
  const Pose2 miss = between(guess, m->z);
  if (miss.translation().norm() > p.agree_translation || std::abs(miss.theta) > p.agree_rotation) {
    ++counts.disagreed;
    return std::nullopt;
  }
  return m;
}

}  // namespace

GraphRefinementSummary& GraphRefinementSummary::operator+=(const GraphRefinementSummary& other) {
  pairs += other.pairs;
  edges += other.edges;
  poor += other.poor;
  disagreed += other.disagreed;
  seconds += other.seconds;
  background_rounds += other.background_rounds;
  return *this;
}

RefinementOutcome matchRefinementPairs(const RefinementJob& job, const PsmSlamParams& params) {
  const auto start = std::chrono::steady_clock::now();
  ScanMatcher matcher(params.psm);  // its own: the job may run beside the filter's matcher
  RefinementOutcome out;
  for (const RefinementPair& pair : job.pairs) {
    const RefinementScan& reference = job.scans.at(pair.reference);
    const RefinementScan& current = job.scans.at(pair.current);
    if (const auto m = refinementMatch(matcher, reference, current, pair.guess, params, out.counts))
      out.edges.push_back({pair.reference, pair.current, m->z, m->R});
  }
  out.counts.seconds = secondsSince(start);
  return out;
}

std::vector<int64_t> PsmSlam::refinementPartners(const Keyframe& current, const std::set<NodePair>& excluded,
                                                 bool settled_only) const {
  const GraphRefinementParams& p = params_.refinement;
  const Pose2 pose = graph_.node(current.id).pose;
  std::vector<std::pair<double, int64_t>> near;
  for (const Keyframe& other : keyframes_) {
    if (other.id >= current.id) break;
    if (other.scan.empty() || excluded.count({other.id, current.id})) continue;
    if (settled_only && filter_keyframes_.count(other.id)) continue;
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

RefinementJob PsmSlam::refinementJob(bool settled_only) {
  RefinementJob job;
  std::set<NodePair> excluded = joinedPairs(graph_);
  excluded.insert(refinement_tried_.begin(), refinement_tried_.end());
  const int64_t first_own = map_frozen_ ? map_keyframes_ : 0;  // a frozen map's scans stay as they are
  for (const Keyframe& current : keyframes_) {
    if (current.scan.empty() || current.id < first_own) continue;
    if (settled_only && filter_keyframes_.count(current.id)) continue;
    const Pose2 pose = graph_.node(current.id).pose;
    for (const int64_t id : refinementPartners(current, excluded, settled_only)) {
      job.pairs.push_back({id, current.id, between(graph_.node(id).pose, pose)});
      refinement_tried_.insert({id, current.id});
      for (const int64_t used : {id, current.id})
        if (!job.scans.count(used)) job.scans.emplace(used, RefinementScan{keyframe(used).scan, keyframe(used).laser_mount});
    }
  }
  return job;
}

void PsmSlam::addRefinementEdges(const RefinementOutcome& outcome) {
  // A scan's matches share its noise: together they carry about one match's information, not
  // one per edge (otherwise the chains outweigh the loop closures, which then get disowned). Edges
  // added to a scan earlier are widened to the new share.
  std::map<int64_t, size_t> added;
  for (const RefinementEdge& e : outcome.edges) ++added[e.to];
  std::map<int64_t, std::vector<size_t>> earlier;
  for (size_t k = 0; k < graph_.edges().size(); ++k) {
    const PoseGraphEdge& e = graph_.edges()[k];
    if (e.kind == PoseGraphEdgeKind::Refinement && added.count(e.to)) earlier[e.to].push_back(k);
  }
  for (const auto& [scan, indices] : earlier) {
    const double widen = static_cast<double>(indices.size() + added[scan]) / static_cast<double>(indices.size());
    for (const size_t k : indices) graph_.edges()[k].covariance *= widen;
  }
  for (const RefinementEdge& e : outcome.edges) {
    const size_t before = graph_.edges().size();
    const double share = static_cast<double>(earlier[e.to].size() + added[e.to]);
    addGraphEdge(e.from, e.to, e.z, e.R * share, PoseGraphEdgeKind::Refinement);
    refinement_.edges += graph_.edges().size() - before;
  }
  GraphRefinementSummary counts = outcome.counts;
  counts.edges = 0;  // counted above, as the graph took them
  refinement_ += counts;
}

void PsmSlam::startBackgroundRefinement() {
  if (!params_.refinement.enabled || !params_.refinement.online || background_refinement_.valid()) return;
  RefinementJob job = refinementJob(true);
  if (job.pairs.empty()) return;
  // On its own thread; where none can be started, when its edges are taken (the same edges).
  background_refinement_ =
      std::async(std::launch::async | std::launch::deferred, matchRefinementPairs, std::move(job), params_);
}

bool PsmSlam::joinBackgroundRefinement() {
  if (!background_refinement_.valid()) return false;
  const size_t before = refinement_.edges;
  addRefinementEdges(background_refinement_.get());
  ++refinement_.background_rounds;
  return refinement_.edges > before;
}

GraphRefinementSummary PsmSlam::refine() {
  if (!params_.refinement.enabled || keyframes_.size() < 3) return refinement_;
  const auto start = std::chrono::steady_clock::now();
  joinBackgroundRefinement();
  optimize();
  addRefinementEdges(matchRefinementPairs(refinementJob(false), params_));
  refinement_.final_seconds = secondsSince(start);
  return refinement_;
}

}  // namespace polarslam
