// g2o export: vertices, edges with information = covariance⁻¹ (upper triangle), rejected loop
// closures left out, the first node fixed.
#include <gtest/gtest.h>

#include <sstream>

#include "pipeline/g2o_export.hpp"

namespace polarslam {
namespace {

TEST(G2oExport, VerticesEdgesInformationAndTheFixedFirstNode) {
  PoseGraph graph;
  graph.addNode({3, 100, Pose2(0.0, 0.0, 0.0)});
  graph.addNode({4, 200, Pose2(1.0, 0.5, 0.25)});
  graph.addNode({9, 300, Pose2(2.0, 0.0, -0.5)});
  Mat3 cov;
  cov << 0.04, 0.01, 0.0, 0.01, 0.09, 0.0, 0.0, 0.0, 0.0025;
  graph.addEdge({3, 4, Pose2(1.0, 0.5, 0.25), cov, PoseGraphEdgeKind::Match, true});
  graph.addEdge({4, 9, Pose2(0.9, -0.7, -0.75), cov, PoseGraphEdgeKind::Odometry, true});
  graph.addEdge({3, 9, Pose2(2.0, 0.0, -0.5), cov, PoseGraphEdgeKind::Loop, false});  // rejected
  std::istringstream text(g2oText(graph));
  std::string tag;
  int vertices = 0, edges = 0;
  int64_t fixed = -1;
  while (text >> tag) {
    if (tag == "VERTEX_SE2") {
      int64_t id;
      double x, y, theta;
      text >> id >> x >> y >> theta;
      ++vertices;
      if (id == 4) {
        EXPECT_DOUBLE_EQ(theta, 0.25);
      }
    } else if (tag == "EDGE_SE2") {
      int64_t from, to;
      double dx, dy, dt, i11, i12, i13, i22, i23, i33;
      text >> from >> to >> dx >> dy >> dt >> i11 >> i12 >> i13 >> i22 >> i23 >> i33;
      ++edges;
      EXPECT_FALSE(from == 3 && to == 9) << "a rejected loop closure is not exported";
      Mat3 information;
      information << i11, i12, i13, i12, i22, i23, i13, i23, i33;
      EXPECT_TRUE((information * cov).isApprox(Mat3::Identity(), 1e-9));
    } else if (tag == "FIX") {
      text >> fixed;
    } else {
      FAIL() << "unexpected tag " << tag;
    }
  }
  EXPECT_EQ(vertices, 3);
  EXPECT_EQ(edges, 2);
  EXPECT_EQ(fixed, 3);
}

}  // namespace
}  // namespace polarslam
