// The final refinement of PSM SLAM (psm_slam_refinement.cpp, docs/algorithms.md §18): at the end
// of a run, overlapping reference scans are matched pairwise into the pose graph. In the
// simulated office, where one match per reference scan leaves its noise in the map, the
// trajectories end closer to the truth; no refinement edge that stays active is off the truth.
#include <gtest/gtest.h>

#include <cstdio>

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

}  // namespace
}  // namespace polarslam
