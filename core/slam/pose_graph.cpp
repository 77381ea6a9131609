#include "slam/pose_graph.hpp"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>

namespace polarslam {
namespace {


/// Wraps into [−π, π) with operations that also work on Ceres jets.
template <typename T>
T wrapForSolver(const T& a) {
  using std::floor;
  const double two_pi = 2.0 * std::numbers::pi;
  return a - two_pi * floor((a + std::numbers::pi) / two_pi);
}

/// L such that LᵀL = Σ⁻¹: whitens a residual with covariance Σ.
Mat3 squareRootInformation(const Mat3& covariance) {
  const Mat3 information = covariance.inverse();
  const Mat3 lower = Eigen::LLT<Mat3>(0.5 * (information + information.transpose())).matrixL();
  return lower.transpose();
}

/// r = L·(v(⊖a ⊕ b) − v(z)), angle wrapped.
struct RelativePoseCost {
  RelativePoseCost(const Pose2& z, const Mat3& sqrt_information) : z_(z), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]), s = sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    const T e[3] = {c * dx + s * dy - T(z_.x), -s * dx + c * dy - T(z_.y), wrapForSolver(b[2] - a[2] - T(z_.theta))};
    for (int r = 0; r < 3; ++r)
      residual[r] = T(sqrt_information_(r, 0)) * e[0] + T(sqrt_information_(r, 1)) * e[1] +
                    T(sqrt_information_(r, 2)) * e[2];
    return true;
  }

  static ceres::CostFunction* create(const PoseGraphEdge& edge) {
    return new ceres::AutoDiffCostFunction<RelativePoseCost, 3, 3, 3>(
        new RelativePoseCost(edge.measurement, squareRootInformation(edge.covariance)));
  }

 private:
  Pose2 z_;
  Mat3 sqrt_information_;
};

/// Union-find over node indices joined by active edges: one representative per component.
std::vector<size_t> componentRoots(const PoseGraph& graph) {
  std::vector<size_t> parent(graph.nodes().size());
  std::iota(parent.begin(), parent.end(), size_t{0});
  auto find = [&](size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const auto& e : graph.edges()) {
    if (!e.active) continue;
    const size_t a = find(static_cast<size_t>(graph.indexOf(e.from))), b = find(static_cast<size_t>(graph.indexOf(e.to)));
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the earliest node stays the root
  }
  for (size_t i = 0; i < parent.size(); ++i) parent[i] = find(i);
  return parent;
}

struct SolveResult {
  bool usable = false;
  int iterations = 0;
  double initial_cost = 0.0, final_cost = 0.0;
  std::string message;
};

SolveResult solveOnce(PoseGraph& graph, const PoseGraphOptimizerOptions& options) {
  const auto& nodes = graph.nodes();
  std::vector<double> parameters(3 * nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    parameters[3 * i] = nodes[i].pose.x;
    parameters[3 * i + 1] = nodes[i].pose.y;
    parameters[3 * i + 2] = nodes[i].pose.theta;
  }
  const std::vector<size_t> roots = componentRoots(graph);
  std::vector<bool> fixed(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) fixed[i] = roots[i] == i || nodes[i].id < options.fixed_below;
  ceres::Problem problem;
  for (const auto& e : graph.edges()) {
    const size_t from = static_cast<size_t>(graph.indexOf(e.from)), to = static_cast<size_t>(graph.indexOf(e.to));
    // An edge between two fixed nodes moves nothing (a map held fixed while localising in it has
    // hundreds): Ceres would set it aside too, after building it.
    if (!e.active || (fixed[from] && fixed[to])) continue;
    ceres::LossFunction* loss =
        disownable(e.kind) && options.loop_loss_scale > 0 ? new ceres::CauchyLoss(options.loop_loss_scale) : nullptr;
    problem.AddResidualBlock(RelativePoseCost::create(e), loss, &parameters[3 * from], &parameters[3 * to]);
  }
  for (size_t i = 0; i < nodes.size(); ++i)
    if (fixed[i] && problem.HasParameterBlock(&parameters[3 * i])) problem.SetParameterBlockConstant(&parameters[3 * i]);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);

  SolveResult result;
  result.usable = summary.IsSolutionUsable();
  result.iterations = static_cast<int>(summary.iterations.size());
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.message = summary.BriefReport();
  if (!result.usable) return result;
  for (size_t i = 0; i < nodes.size(); ++i)
    graph.setPose(nodes[i].id, Pose2(parameters[3 * i], parameters[3 * i + 1], wrapAngle(parameters[3 * i + 2])));
  return result;
}

/// Deactivates active loop edges whose χ² exceeds the threshold; returns how many.
size_t rejectOutlierLoops(PoseGraph& graph, double chi2_threshold) {
  size_t rejected = 0;
  for (auto& e : graph.edges()) {
    if (!e.active || !disownable(e.kind)) continue;
    if (edgeChiSquared(graph.node(e.from).pose, graph.node(e.to).pose, e) > chi2_threshold) {
      e.active = false;
      ++rejected;
    }
  }
  return rejected;
}

}  // namespace

const char* edgeKindName(PoseGraphEdgeKind kind) {
  switch (kind) {
    case PoseGraphEdgeKind::Odometry: return "odometry";
    case PoseGraphEdgeKind::Match: return "match";
    case PoseGraphEdgeKind::Loop: return "loop";
    case PoseGraphEdgeKind::Refinement: return "refinement";
  }
  return "unknown";
}

size_t PoseGraph::addNode(const PoseGraphNode& node) {
  if (!finitePose(node.pose)) throw std::invalid_argument("pose graph node pose is not finite");
  if (!nodes_.empty() && node.id <= nodes_.back().id)
    throw std::invalid_argument("pose graph node ids must increase");
  nodes_.push_back(node);
  return nodes_.size() - 1;
}

void PoseGraph::addEdge(const PoseGraphEdge& edge) {
  if (indexOf(edge.from) < 0 || indexOf(edge.to) < 0 || edge.from == edge.to)
    throw std::invalid_argument("pose graph edge must join two different existing nodes");
  if (!finitePose(edge.measurement) || !edge.covariance.allFinite())
    throw std::invalid_argument("pose graph edge measurement or covariance is not finite");
  if (Eigen::LLT<Mat3>(edge.covariance).info() != Eigen::Success)
    throw std::invalid_argument("pose graph edge covariance is not positive definite");
  edges_.push_back(edge);
}

long PoseGraph::indexOf(int64_t id) const {
  // Ids increase with the index, so a binary search finds them.
  auto it = std::lower_bound(nodes_.begin(), nodes_.end(), id,
                             [](const PoseGraphNode& n, int64_t value) { return n.id < value; });
  return it != nodes_.end() && it->id == id ? static_cast<long>(it - nodes_.begin()) : -1;
}

const PoseGraphNode& PoseGraph::node(int64_t id) const {
  const long i = indexOf(id);
  if (i < 0) throw std::out_of_range("no pose graph node " + std::to_string(id));
  return nodes_[static_cast<size_t>(i)];
}

void PoseGraph::setPose(int64_t id, const Pose2& pose) {
  const long i = indexOf(id);
  if (i < 0) throw std::out_of_range("no pose graph node " + std::to_string(id));
  nodes_[static_cast<size_t>(i)].pose = pose;
}

size_t PoseGraph::countEdges(PoseGraphEdgeKind kind, bool active_only) const {
  return static_cast<size_t>(std::count_if(edges_.begin(), edges_.end(), [&](const PoseGraphEdge& e) {
    return e.kind == kind && (e.active || !active_only);
  }));
}

Vec3 edgeResidual(const Pose2& from, const Pose2& to, const Pose2& measurement) {
  const Pose2 predicted = between(from, to);
  return {predicted.x - measurement.x, predicted.y - measurement.y, wrapAngle(predicted.theta - measurement.theta)};
}

double edgeChiSquared(const Pose2& from, const Pose2& to, const PoseGraphEdge& edge) {
  const Vec3 r = edgeResidual(from, to, edge.measurement);
  return r.dot(edge.covariance.ldlt().solve(r));
}

PoseGraphOptimizationSummary optimizePoseGraph(PoseGraph& graph, const PoseGraphOptimizerOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PoseGraphOptimizationSummary summary;
  summary.nodes = graph.nodes().size();
  summary.edges = graph.edges().size();
  if (graph.nodes().size() < 2 || graph.edges().empty()) {
    summary.solved = true;
    summary.message = "nothing to optimise";
    return summary;
  }
  const std::vector<PoseGraphNode> before = graph.nodes();
  for (int round = 0; round <= options.max_outlier_rounds; ++round) {
    const SolveResult solve = solveOnce(graph, options);
    ++summary.rounds;
    summary.iterations += solve.iterations;
    if (round == 0) summary.initial_cost = solve.initial_cost;
    summary.final_cost = solve.final_cost;
    summary.message = solve.message;
    summary.solved = solve.usable;
    if (!solve.usable) {
      for (const auto& n : before) graph.setPose(n.id, n.pose);
      break;
    }
    if (round == options.max_outlier_rounds) break;
    const size_t rejected = rejectOutlierLoops(graph, options.outlier_chi2);
    summary.rejected_loops += rejected;
    if (rejected == 0) break;
    // Solve again from the start: the rejected closures may have dragged the poses far off.
    for (const auto& n : before) graph.setPose(n.id, n.pose);
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

std::vector<PoseStamped> reanchor(const std::vector<AnchoredPose>& poses, const PoseGraph& graph, size_t* missing) {
  std::vector<PoseStamped> out;
  out.reserve(poses.size());
  size_t unknown = 0;
  for (const AnchoredPose& p : poses) {
    Pose2 pose = p.relative;
    if (p.node >= 0) {
      if (graph.indexOf(p.node) >= 0) pose = graph.node(p.node).pose * p.relative;
      else ++unknown;
    }
    out.push_back({p.utime, pose, Mat3::Zero()});
  }
  if (missing) *missing = unknown;
  return out;
}

}  // namespace polarslam
