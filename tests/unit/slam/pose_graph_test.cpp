// Pose-graph optimiser on small synthetic loops whose true poses are known.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <random>

#include "slam/pose_graph.hpp"

namespace polarslam {
namespace {

/// A square loop of `per_side` steps of 1 m per side, turning 90° at each corner.
std::vector<Pose2> squareLoop(int per_side) {
  std::vector<Pose2> poses{Pose2()};
  for (int side = 0; side < 4; ++side)
    for (int k = 0; k < per_side; ++k) {
      const bool corner = k == per_side - 1;
      poses.push_back(poses.back() * Pose2(1.0, 0.0, corner ? M_PI / 2 : 0.0));
    }
  poses.pop_back();  // the last step returns to the start: closed by the loop edge below
  return poses;
}

Mat3 diag3(double a, double b, double c) { return Vec3(a, b, c).asDiagonal(); }

struct NoisyGraph {
  PoseGraph graph;
  std::vector<Pose2> truth;
};

/// Odometry edges with sampled noise, initial poses by chaining them (dead reckoning), and
/// a loop edge from the last pose to the first.
NoisyGraph noisyLoop(int per_side, const Mat3& odometry_cov, const Mat3& loop_cov, uint64_t seed) {
  NoisyGraph g;
  g.truth = squareLoop(per_side);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const Eigen::Matrix3d L = odometry_cov.llt().matrixL();
  Pose2 dead_reckoning;
  g.graph.addNode({0, 0, dead_reckoning});
  for (size_t i = 1; i < g.truth.size(); ++i) {
    const Pose2 truth = between(g.truth[i - 1], g.truth[i]);
    const Vec3 noise = L * Vec3(unit(rng), unit(rng), unit(rng));
    const Pose2 measured(truth.x + noise.x(), truth.y + noise.y(), wrapAngle(truth.theta + noise.z()));
    dead_reckoning = dead_reckoning * measured;
    g.graph.addNode({static_cast<int64_t>(i), static_cast<int64_t>(i), dead_reckoning});
    g.graph.addEdge({static_cast<int64_t>(i - 1), static_cast<int64_t>(i), measured, odometry_cov, PoseGraphEdgeKind::Odometry});
  }
  const int64_t last = static_cast<int64_t>(g.truth.size() - 1);
  g.graph.addEdge({last, 0, between(g.truth.back(), g.truth.front()), loop_cov, PoseGraphEdgeKind::Loop});
  return g;
}

double maxPositionError(const PoseGraph& graph, const std::vector<Pose2>& truth) {
  double worst = 0.0;
  for (size_t i = 0; i < truth.size(); ++i)
    worst = std::max(worst, (graph.nodes()[i].pose.translation() - truth[i].translation()).norm());
  return worst;
}

TEST(PoseGraph, EdgeResidualIsTheRelativePoseDifference) {
  const Pose2 a(1.0, 2.0, M_PI / 2), b(1.0, 3.0, M_PI);
  // b seen from a: 1 m straight ahead, turned by 90°.
  const Vec3 r = edgeResidual(a, b, Pose2(0.9, 0.1, M_PI / 2 - 0.2));
  EXPECT_NEAR(r.x(), 0.1, 1e-12);
  EXPECT_NEAR(r.y(), -0.1, 1e-12);
  EXPECT_NEAR(r.z(), 0.2, 1e-12);
  PoseGraphEdge edge{0, 1, Pose2(0.9, 0.1, M_PI / 2 - 0.2), diag3(0.01, 0.04, 0.01), PoseGraphEdgeKind::Match};
  EXPECT_NEAR(edgeChiSquared(a, b, edge), 0.01 / 0.01 + 0.01 / 0.04 + 0.04 / 0.01, 1e-9);
}

TEST(PoseGraph, ExactMeasurementsRecoverTheTruthFromAPerturbedStart) {
  NoisyGraph g = noisyLoop(5, diag3(1e-12, 1e-12, 1e-12), diag3(1e-4, 1e-4, 1e-4), 1);
  // Exact edges, but start far from the truth.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (size_t i = 1; i < g.truth.size(); ++i) {
    const Pose2& t = g.truth[i];
    g.graph.setPose(static_cast<int64_t>(i), Pose2(t.x + jitter(rng), t.y + jitter(rng), t.theta + 0.5 * jitter(rng)));
  }
  for (auto& e : g.graph.edges()) e.covariance = diag3(1e-4, 1e-4, 1e-4);
  const PoseGraphOptimizationSummary s = optimizePoseGraph(g.graph);
  ASSERT_TRUE(s.solved) << s.message;
  // The edges carry σ = 1e-6 noise (drawn from their 1e-12 covariance).
  EXPECT_LT(maxPositionError(g.graph, g.truth), 1e-4);
  for (size_t i = 0; i < g.truth.size(); ++i)
    EXPECT_NEAR(wrapAngle(g.graph.nodes()[i].pose.theta - g.truth[i].theta), 0.0, 1e-5);
  EXPECT_LT(s.final_cost, 1e-6);
  EXPECT_EQ(s.rejected_loops, 0u);
}

TEST(PoseGraph, LoopClosureShrinksTheDriftOfNoisyOdometry) {
  // Averaged over seeds, so that one lucky draw cannot pass the test.
  double before = 0.0, after = 0.0;
  const int runs = 20;
  for (int seed = 0; seed < runs; ++seed) {
    NoisyGraph g = noisyLoop(10, diag3(4e-4, 4e-4, 4e-4), diag3(1e-4, 1e-4, 1e-5), static_cast<uint64_t>(seed));
    before += maxPositionError(g.graph, g.truth);
    const PoseGraphOptimizationSummary s = optimizePoseGraph(g.graph);
    ASSERT_TRUE(s.solved) << s.message;
    EXPECT_EQ(s.rejected_loops, 0u);
    after += maxPositionError(g.graph, g.truth);
  }
  before /= runs;
  after /= runs;
  // 40 steps of 2 cm / 1.1° noise drift about 0.5 m; a closed loop halves the worst error at least.
  EXPECT_GT(before, 0.2);
  EXPECT_LT(after, 0.5 * before);
}

TEST(PoseGraph, OptimisedErrorsMatchTheirPredictedSpread) {
  // Monte Carlo: with every edge drawn from its covariance, twice the optimal cost is χ² with
  // 3·(edges − free nodes) degrees of freedom (the problem is nearly linear at this noise).
  double total = 0.0;
  const int runs = 30;
  size_t redundancy = 0;
  for (int seed = 0; seed < runs; ++seed) {
    NoisyGraph g = noisyLoop(6, diag3(1e-4, 1e-4, 1e-4), diag3(1e-4, 1e-4, 1e-4), 100 + static_cast<uint64_t>(seed));
    // Make the loop edge a noisy measurement too, drawn with its covariance.
    std::mt19937_64 rng(1000 + static_cast<uint64_t>(seed));
    std::normal_distribution<double> unit(0.0, 1.0);
    auto& loop = g.graph.edges().back();
    loop.measurement = Pose2(loop.measurement.x + 0.01 * unit(rng), loop.measurement.y + 0.01 * unit(rng),
                             loop.measurement.theta + 0.01 * unit(rng));
    PoseGraphOptimizerOptions options;
    options.loop_loss_scale = 0.0;  // plain least squares for this check
    const PoseGraphOptimizationSummary s = optimizePoseGraph(g.graph, options);
    ASSERT_TRUE(s.solved);
    total += 2.0 * s.final_cost;
    redundancy = 3 * (g.graph.edges().size() - (g.graph.nodes().size() - 1));
  }
  const double mean = total / runs;
  EXPECT_NEAR(mean, static_cast<double>(redundancy), 0.6 * static_cast<double>(redundancy));
}

TEST(PoseGraph, AWrongLoopClosureIsRejectedAndTheRestStaysCorrect) {
  NoisyGraph g = noisyLoop(8, diag3(1e-6, 1e-6, 1e-6), diag3(1e-4, 1e-4, 1e-5), 5);
  // A second, wrong closure claiming node 12 sits 2 m to the side of node 4 (a corridor
  // that looks alike), with a confident covariance.
  const Pose2 wrong = between(g.truth[4], g.truth[12]) * Pose2(0.0, 2.0, 0.3);
  g.graph.addEdge({4, 12, wrong, diag3(1e-4, 1e-4, 1e-5), PoseGraphEdgeKind::Loop});
  const PoseGraphOptimizationSummary s = optimizePoseGraph(g.graph);
  ASSERT_TRUE(s.solved) << s.message;
  EXPECT_EQ(s.rejected_loops, 1u);
  EXPECT_FALSE(g.graph.edges().back().active);
  EXPECT_TRUE(g.graph.edges()[g.graph.edges().size() - 2].active);  // the true closure stays
  EXPECT_EQ(g.graph.countEdges(PoseGraphEdgeKind::Loop), 1u);
  EXPECT_LT(maxPositionError(g.graph, g.truth), 0.02);
}

TEST(PoseGraph, DisconnectedPiecesKeepTheirFrames) {
  PoseGraph graph;
  graph.addNode({0, 0, Pose2()});
  graph.addNode({1, 1, Pose2(1.1, 0.0, 0.0)});
  graph.addNode({5, 2, Pose2(10.0, 10.0, 1.0)});
  graph.addNode({6, 3, Pose2(10.5, 10.0, 1.0)});
  graph.addEdge({0, 1, Pose2(1.0, 0.0, 0.0), diag3(1e-4, 1e-4, 1e-4), PoseGraphEdgeKind::Match});
  graph.addEdge({5, 6, Pose2(1.0, 0.0, 0.0), diag3(1e-4, 1e-4, 1e-4), PoseGraphEdgeKind::Match});
  const PoseGraphOptimizationSummary s = optimizePoseGraph(graph);
  ASSERT_TRUE(s.solved) << s.message;
  EXPECT_NEAR(graph.node(1).pose.x, 1.0, 1e-6);
  EXPECT_NEAR(graph.node(5).pose.x, 10.0, 1e-12);  // the second piece's first node is its anchor
  const Pose2 rel = between(graph.node(5).pose, graph.node(6).pose);
  EXPECT_NEAR(rel.x, 1.0, 1e-6);
  EXPECT_NEAR(rel.y, 0.0, 1e-6);
}

TEST(PoseGraph, RejectsMalformedInput) {
  PoseGraph graph;
  graph.addNode({0, 0, Pose2()});
  graph.addNode({1, 0, Pose2(1, 0, 0)});
  EXPECT_THROW(graph.addNode({1, 0, Pose2()}), std::invalid_argument);
  EXPECT_THROW(graph.addNode({2, 0, Pose2(NAN, 0, 0)}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 7, Pose2(), Mat3::Identity(), PoseGraphEdgeKind::Match}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 0, Pose2(), Mat3::Identity(), PoseGraphEdgeKind::Match}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 1, Pose2(INFINITY, 0, 0), Mat3::Identity(), PoseGraphEdgeKind::Match}),
               std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 1, Pose2(), Mat3::Zero(), PoseGraphEdgeKind::Match}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 1, Pose2(), diag3(1, -1, 1), PoseGraphEdgeKind::Match}), std::invalid_argument);
  EXPECT_EQ(graph.edges().size(), 0u);
  const PoseGraphOptimizationSummary s = optimizePoseGraph(graph);  // nothing to do, no crash
  EXPECT_TRUE(s.solved);
  EXPECT_NEAR(graph.node(1).pose.x, 1.0, 0.0);
}

}  // namespace
}  // namespace polarslam
