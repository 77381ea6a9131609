#pragma once
// PoseGraph ↔ pose_graph_t (lcmtypes/pose_graph_t.lcm).
#include <string>

#include "polarslam/pose_graph_t.hpp"
#include "slam/pose_graph.hpp"

namespace polarslam {

polarslam::pose_graph_t toLcm(const PoseGraph& graph, int64_t utime, int64_t seq, int32_t optimizations,
                              double optimization_seconds);

/// Checks counts against array sizes and that edges join listed nodes; returns an error string
/// (empty = ok) and leaves `out` holding the graph otherwise.
std::string fromLcm(const polarslam::pose_graph_t& msg, PoseGraph& out);

}  // namespace polarslam
