#pragma once
// The pose graph behind PSM SLAM: one node per reference scan (keyframe), one edge per
// relative-pose measurement between two of them, each with its covariance. Optimised with Ceres
// (SE(2) relative-pose factors weighted by the measurement information, a robust loss on loop
// closures) to make the map globally consistent after a loop closes; the delayed-state filter
// (psm_slam_filter.hpp) stays the fast front end.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "geometry/pose2.hpp"

namespace polarslam {

enum class PoseGraphEdgeKind : int8_t {
  Odometry = 0,  ///< dead-reckoned (and filtered) motion: no usable match at this keyframe
  Match = 1,     ///< PSM match with the previous reference scan
  Loop = 2,      ///< PSM match with an older reference scan (a loop closure)
  /// PSM match between two overlapping reference scans, added by the final refinement; robust
  /// and checked like a loop closure.
  Refinement = 3,
};
const char* edgeKindName(PoseGraphEdgeKind kind);
/// Whether `value` (from a file or a message) is one of the kinds above.
inline bool isEdgeKind(int value) { return value >= 0 && value <= static_cast<int>(PoseGraphEdgeKind::Refinement); }
/// Loop closures and refinement edges: the edges the optimiser may disown (robust loss, χ² rejection).
inline bool disownable(PoseGraphEdgeKind kind) {
  return kind == PoseGraphEdgeKind::Loop || kind == PoseGraphEdgeKind::Refinement;
}

struct PoseGraphNode {
  int64_t id = 0;     ///< keyframe id, unique and increasing
  int64_t utime = 0;  ///< time of the keyframe's scan
  Pose2 pose;         ///< robot base pose in the map frame
};

struct PoseGraphEdge {
  int64_t from = 0, to = 0;  ///< node ids
  Pose2 measurement;         ///< pose of `to` in the frame of `from`
  Mat3 covariance = Mat3::Identity();  ///< of measurement (x m, y m, θ rad)
  PoseGraphEdgeKind kind = PoseGraphEdgeKind::Match;
  bool active = true;        ///< false once rejected as an outlier by the optimiser
};

class PoseGraph {
 public:
  /// Adds a node; ids must be new. Returns its index.
  size_t addNode(const PoseGraphNode& node);
  /// Adds an edge between existing nodes; throws std::invalid_argument otherwise or when the
  /// measurement or covariance is not finite or the covariance not positive definite.
  void addEdge(const PoseGraphEdge& edge);

  const std::vector<PoseGraphNode>& nodes() const { return nodes_; }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  std::vector<PoseGraphEdge>& edges() { return edges_; }
  /// Index of a node id, or -1.
  long indexOf(int64_t id) const;
  const PoseGraphNode& node(int64_t id) const;
  void setPose(int64_t id, const Pose2& pose);
  size_t countEdges(PoseGraphEdgeKind kind, bool active_only = true) const;
  bool empty() const { return nodes_.empty(); }

 private:
  std::vector<PoseGraphNode> nodes_;
  std::vector<PoseGraphEdge> edges_;
};

/// A robot pose stored relative to a pose-graph node (the reference scan it was matched to), so
/// that it follows the node when the graph is optimised.
struct AnchoredPose {
  int64_t utime = 0;
  int64_t node = -1;   ///< node id; -1: `relative` is already in the map frame
  Pose2 relative;      ///< robot base pose in the node's frame
  bool new_node = false;  ///< this scan became node `node` (a new reference scan)
};

/// node pose ⊕ relative for each pose (covariance zero). A pose whose node the graph does not
/// hold is taken as `relative` unchanged and counted in `missing`.
std::vector<PoseStamped> reanchor(const std::vector<AnchoredPose>& poses, const PoseGraph& graph,
                                  size_t* missing = nullptr);

/// Residual of one edge at the given node poses: v(⊖from ⊕ to) − v(measurement), angle wrapped,
/// the vector whose covariance the edge carries and whose Mahalanobis norm the optimiser minimises.
Vec3 edgeResidual(const Pose2& from, const Pose2& to, const Pose2& measurement);
/// Its Mahalanobis norm rᵀ Σ⁻¹ r (χ² with 3 degrees of freedom for a correct edge).
double edgeChiSquared(const Pose2& from, const Pose2& to, const PoseGraphEdge& edge);

struct PoseGraphOptimizerOptions {
  /// Cauchy loss scale on loop-closure edges, in units of the whitened residual (σ): a wrong
  /// closure that slipped through the gates pulls with a force that fades instead of growing.
  double loop_loss_scale = 3.0;
  int max_iterations = 50;
  /// After solving, active loop edges with χ² above this are deactivated and the graph solved
  /// again (at most `max_outlier_rounds` times). χ²₃(0.999) ≈ 16.3.
  double outlier_chi2 = 16.27;
  int max_outlier_rounds = 3;
  /// Relative cost change at which Ceres stops.
  double function_tolerance = 1e-8;
  /// Nodes with ids below this are held where they are too (a stored map localised in).
  int64_t fixed_below = 0;
};

struct PoseGraphOptimizationSummary {
  bool solved = false;        ///< Ceres reported a usable solution
  int iterations = 0;
  int rounds = 0;             ///< solves (1 + outlier-rejection rounds)
  double initial_cost = 0.0;  ///< ½Σ whitened residuals² (with the robust loss) before, of the edges it can move
  double final_cost = 0.0;    ///< ... and after
  double seconds = 0.0;       ///< wall time spent in this call
  size_t nodes = 0, edges = 0;
  size_t rejected_loops = 0;  ///< loop edges deactivated by this call
  std::string message;        ///< Ceres' own summary line
};

/// Optimises the node poses in place; the first node is held fixed (it defines the map frame).
/// Nodes not connected to the first node through active edges are left where they are.
PoseGraphOptimizationSummary optimizePoseGraph(PoseGraph& graph, const PoseGraphOptimizerOptions& options = {});

}  // namespace polarslam
