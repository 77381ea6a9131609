#pragma once
// A pose graph in g2o's text format, which g2o, Ceres' pose-graph examples, GTSAM's readG2o and
// most SLAM back ends read:
//   VERTEX_SE2 id x y theta
//   EDGE_SE2 from to dx dy dtheta i11 i12 i13 i22 i23 i33   (information = covariance⁻¹, upper triangle)
//   FIX id                                                   (the first node: it defines the map frame)
// Edges the optimiser deactivated (rejected loop closures) are left out.
#include <string>

#include "slam/pose_graph.hpp"

namespace polarslam {

std::string g2oText(const PoseGraph& graph);
/// Writes g2oText(graph) to `path` atomically; throws std::runtime_error naming the file.
void writeG2o(const std::string& path, const PoseGraph& graph);

}  // namespace polarslam
