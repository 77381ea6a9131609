// The refinement of PSM SLAM (psm_slam_refinement.cpp, docs/algorithms.md §18): at the end of a
// run (and with `online` after loop closures), overlapping reference scans are matched pairwise
// into the pose graph. In the
// simulated office, where one match per reference scan leaves its noise in the map, the
// trajectories end closer to the truth; no refinement edge that stays active is off the truth.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <set>
#include <tuple>

#include "eval/ate.hpp"
#include "psm_slam_sim.hpp"
#include "slam/psm_slam.hpp"

namespace polarslam {
namespace {

struct OfficeRun {
  double ate = 0.0;                ///< m, RMS of the final trajectory against the truth
  GraphRefinementSummary refinement;
  size_t edges_off_truth = 0;      ///< active refinement edges that disagree with the truth
};

OfficeRun runOffice(uint64_t seed, bool refine) {
  PsmSlamParams params;
  params.refinement.enabled = refine;
  PsmSlam slam(params);
  testing::PsmSlamSimSink sink(slam);
  testing::simulatePsmSlam("office.yaml", seed, sink);
  OfficeRun run;
  run.refinement = slam.refine();
  slam.optimize();
  run.ate = evaluateAte(slam.trajectory(), inStartFrame(sink.truth)).raw_translation.rmse;
  run.edges_off_truth = testing::edgesOffTheTruth(slam.graph(), sink.truth, PoseGraphEdgeKind::Refinement);
  return run;
}

TEST(PsmSlamRefinement, OverlappingReferenceScansBringTheOfficeRunsCloserToTheTruth) {
  double sum_without = 0.0, sum_with = 0.0;
  for (uint64_t seed = 8000; seed < 8008; ++seed) {
    const OfficeRun without = runOffice(seed, false), with = runOffice(seed, true);
    std::printf("seed %llu: ATE %.4f m without, %.4f m with the refinement (%zu pairs matched, %zu edges, %zu poor, "
                "%zu disagreed)\n",
                static_cast<unsigned long long>(seed), without.ate, with.ate, with.refinement.pairs,
                with.refinement.edges, with.refinement.poor, with.refinement.disagreed);
    EXPECT_EQ(without.refinement.pairs, 0u) << "disabled: nothing is matched";
    EXPECT_GT(with.refinement.edges, 50u) << "seed " << seed;
    EXPECT_EQ(with.edges_off_truth, 0u) << "seed " << seed;
    sum_without += without.ate;
    sum_with += with.ate;
  }
  std::printf("mean ATE over 8 seeds: %.4f m without, %.4f m with the refinement\n", sum_without / 8, sum_with / 8);
  EXPECT_LT(sum_with, 0.9 * sum_without) << "the refinement should bring the office runs closer to the truth";
}

// refinement.online: after each loop-closure optimisation the settled pairs are matched on another
// thread and join the graph at the next one. Where the thread happens to be when the filter goes on
// changes nothing: two runs end with the same graph. No pair is matched twice (the end of the run
// tries only what the rounds did not), and every refinement edge stays on the truth.
TEST(PsmSlamRefinement, RoundsAfterLoopClosuresEndTheSameEachTimeAndMatchNoPairTwice) {
  auto run = [](PsmSlamParams params) {
    auto slam = std::make_unique<PsmSlam>(std::move(params));
    testing::PsmSlamSimSink sink(*slam);
    testing::simulatePsmSlam("office.yaml", 8001, sink);
    const GraphRefinementSummary summary = slam->refine();
    slam->optimize();
    return std::make_tuple(std::move(slam), summary, sink.truth);
  };
  PsmSlamParams params;
  params.refinement.enabled = params.refinement.online = true;
  const auto [first, summary, truth] = run(params);
  const auto [second, summary_again, truth_again] = run(params);
  std::printf("%zu rounds after loop closures; %zu edges of %zu pairs matched\n", summary.background_rounds, summary.edges,
              summary.pairs);
  EXPECT_GT(summary.background_rounds, 0u) << "the office run closes loops: rounds ran during it";
  EXPECT_GT(summary.edges, 50u);
  EXPECT_EQ(summary_again.edges, summary.edges);
  EXPECT_EQ(summary_again.pairs, summary.pairs);
  const std::vector<PoseGraphEdge>& edges = first->graph().edges();
  ASSERT_EQ(second->graph().edges().size(), edges.size());
  std::set<NodePair> refined;
  for (size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge& e = edges[k];
    const PoseGraphEdge& again = second->graph().edges()[k];
    EXPECT_TRUE(e.from == again.from && e.to == again.to && e.kind == again.kind && e.active == again.active) << k;
    EXPECT_EQ((e.covariance - again.covariance).norm(), 0.0) << "edge " << k;
    if (e.kind == PoseGraphEdgeKind::Refinement) {
      EXPECT_TRUE(refined.insert({e.from, e.to}).second) << e.from << "-" << e.to;
    }
  }
  for (const PoseGraphNode& node : first->graph().nodes()) {
    const Pose2 other = second->graph().node(node.id).pose;
    EXPECT_EQ(node.pose.x, other.x) << node.id;
    EXPECT_EQ(node.pose.theta, other.theta) << node.id;
  }
  EXPECT_EQ(testing::edgesOffTheTruth(first->graph(), truth, PoseGraphEdgeKind::Refinement), 0u);
}

}  // namespace
}  // namespace polarslam
