#include "pose_graph_message.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/lcm_convert.hpp"

namespace polarslam {
namespace {

bool allFinite(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

}  // namespace

polarslam::pose_graph_t toLcm(const PoseGraph& graph, int64_t utime, int64_t seq, int32_t optimizations,
                              double optimization_seconds) {
  polarslam::pose_graph_t msg;
  msg.utime = utime;
  msg.seq = seq;
  msg.frame = "map";
  msg.num_nodes = static_cast<int32_t>(graph.nodes().size());
  for (const PoseGraphNode& n : graph.nodes()) {
    msg.node_id.push_back(n.id);
    msg.node_utime.push_back(n.utime);
    msg.node_pose.push_back({n.pose.x, n.pose.y, n.pose.theta});
  }
  msg.num_edges = static_cast<int32_t>(graph.edges().size());
  for (const PoseGraphEdge& e : graph.edges()) {
    msg.edge_from.push_back(e.from);
    msg.edge_to.push_back(e.to);
    msg.edge_kind.push_back(static_cast<int8_t>(e.kind));
    msg.edge_active.push_back(e.active);
    msg.edge_measurement.push_back({e.measurement.x, e.measurement.y, e.measurement.theta});
    std::vector<double> cov(9);
    copyMatrix<3>(e.covariance, cov.data());
    msg.edge_cov.push_back(cov);
  }
  msg.num_optimizations = optimizations;
  msg.optimization_seconds = optimization_seconds;
  return msg;
}

std::string fromLcm(const polarslam::pose_graph_t& msg, PoseGraph& out) {
  const auto nodes = static_cast<size_t>(std::max(0, msg.num_nodes));
  const auto edges = static_cast<size_t>(std::max(0, msg.num_edges));
  if (msg.num_nodes < 0 || msg.node_id.size() != nodes || msg.node_utime.size() != nodes || msg.node_pose.size() != nodes)
    return "pose graph node arrays do not match num_nodes";
  if (msg.num_edges < 0 || msg.edge_from.size() != edges || msg.edge_to.size() != edges ||
      msg.edge_kind.size() != edges || msg.edge_active.size() != edges || msg.edge_measurement.size() != edges ||
      msg.edge_cov.size() != edges)
    return "pose graph edge arrays do not match num_edges";
  PoseGraph graph;
  try {
    for (size_t i = 0; i < nodes; ++i) {
      if (msg.node_pose[i].size() != 3) return "pose graph node pose is not 3 numbers";
      if (!allFinite(msg.node_pose[i])) return "pose graph: non-finite node pose";
      graph.addNode({msg.node_id[i], msg.node_utime[i], Pose2(msg.node_pose[i][0], msg.node_pose[i][1], msg.node_pose[i][2])});
    }
    for (size_t i = 0; i < edges; ++i) {
      if (msg.edge_measurement[i].size() != 3 || msg.edge_cov[i].size() != 9) return "pose graph edge arrays have wrong sizes";
      if (!isEdgeKind(msg.edge_kind[i])) return "pose graph edge kind out of range";
      if (!allFinite(msg.edge_measurement[i]) || !allFinite(msg.edge_cov[i])) return "pose graph: non-finite edge";
      PoseGraphEdge e;
      e.from = msg.edge_from[i];
      e.to = msg.edge_to[i];
      e.kind = static_cast<PoseGraphEdgeKind>(msg.edge_kind[i]);
      e.active = msg.edge_active[i];
      e.measurement = Pose2(msg.edge_measurement[i][0], msg.edge_measurement[i][1], msg.edge_measurement[i][2]);
      e.covariance = readMatrix<3>(msg.edge_cov[i].data());
      graph.addEdge(e);
    }
  } catch (const std::exception& e) {
    return std::string("pose graph: ") + e.what();
  }
  out = std::move(graph);
  return {};
}

polarslam::anchored_pose_t toLcm(const AnchoredPose& pose, int64_t seq) {
  polarslam::anchored_pose_t msg;
  msg.utime = pose.utime;
  msg.seq = seq;
  msg.node_id = pose.node;
  msg.relative[0] = pose.relative.x;
  msg.relative[1] = pose.relative.y;
  msg.relative[2] = pose.relative.theta;
  msg.new_node = pose.new_node;
  return msg;
}

std::string fromLcm(const polarslam::anchored_pose_t& msg, AnchoredPose& out) {
  if (!std::isfinite(msg.relative[0]) || !std::isfinite(msg.relative[1]) || !std::isfinite(msg.relative[2]))
    return "anchored pose: non-finite value";
  if (msg.node_id < -1) return "anchored pose: node id below -1";
  out = {msg.utime, msg.node_id, Pose2(msg.relative[0], msg.relative[1], wrapAngle(msg.relative[2])), msg.new_node != 0};
  return {};
}

}  // namespace polarslam
