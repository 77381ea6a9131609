#include "pipeline/g2o_export.hpp"

#include <Eigen/LU>

#include <sstream>

#include "io/atomic_file.hpp"

namespace polarslam {

std::string g2oText(const PoseGraph& graph) {
  std::ostringstream out;
  out.precision(12);
  for (const PoseGraphNode& n : graph.nodes())
    out << "VERTEX_SE2 " << n.id << ' ' << n.pose.x << ' ' << n.pose.y << ' ' << n.pose.theta << '\n';
  for (const PoseGraphEdge& e : graph.edges()) {
    if (!e.active) continue;
    const Mat3 information = e.covariance.inverse();
    out << "EDGE_SE2 " << e.from << ' ' << e.to << ' ' << e.measurement.x << ' ' << e.measurement.y << ' '
        << e.measurement.theta;
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) out << ' ' << information(r, c);
    out << '\n';
  }
  if (!graph.nodes().empty()) out << "FIX " << graph.nodes().front().id << '\n';
  return out.str();
}

void writeG2o(const std::string& path, const PoseGraph& graph) { writeFileAtomically(path, g2oText(graph)); }

}  // namespace polarslam
