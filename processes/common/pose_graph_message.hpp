#pragma once
// PoseGraph ↔ pose_graph_t and AnchoredPose ↔ anchored_pose_t: PSM SLAM's graph and the poses
// anchored to it (lcmtypes/pose_graph_t.lcm, anchored_pose_t.lcm).
#include <string>

#include "polarslam/anchored_pose_t.hpp"
#include "polarslam/pose_graph_t.hpp"
#include "slam/pose_graph.hpp"

namespace polarslam {

polarslam::pose_graph_t toLcm(const PoseGraph& graph, int64_t utime, int64_t seq, int32_t optimizations,
                              double optimization_seconds);

/// Checks counts against array sizes and that edges join listed nodes; returns an error string
/// (empty = ok) and leaves `out` holding the graph otherwise.
std::string fromLcm(const polarslam::pose_graph_t& msg, PoseGraph& out);

polarslam::anchored_pose_t toLcm(const AnchoredPose& pose, int64_t seq);
std::string fromLcm(const polarslam::anchored_pose_t& msg, AnchoredPose& out);

}  // namespace polarslam
