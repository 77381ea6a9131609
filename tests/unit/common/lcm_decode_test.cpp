// decodeLcm (processes/common/lcm_decode.hpp): malformed bytes that make lcm-gen's decode()
// throw are a rejected message, not a crash (regression for the fuzz_lcm_messages findings).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "common/lcm_decode.hpp"
#include "common/lcm_log.hpp"

namespace polarslam {
namespace {

template <typename MsgT>
std::vector<uint8_t> encode(const MsgT& msg) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_GE(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  return buf;
}

/// Offset of the frame string's int32 length field: 8-byte hash, int64 utime, int64 seq.
constexpr size_t kFrameLengthOffset = 8 + 8 + 8;

TEST(LcmDecode, ValidPoseDecodes) {
  pose_t msg{};
  msg.utime = 42;
  msg.frame = "map";
  const std::vector<uint8_t> buf = encode(msg);
  pose_t out{};
  ASSERT_TRUE(decodeLcm(out, buf.data(), buf.size()));
  EXPECT_EQ(out.utime, 42);
  EXPECT_EQ(out.frame, "map");
}

TEST(LcmDecode, ZeroStringLengthIsRejectedNotThrown) {
  pose_t msg{};
  msg.frame = "map";
  std::vector<uint8_t> buf = encode(msg);
  // The encoded length of "map" is 4 (with the terminating NUL), big-endian.
  ASSERT_EQ(buf[kFrameLengthOffset + 3], 4);
  std::memset(&buf[kFrameLengthOffset], 0, 4);
  pose_t out{};
  EXPECT_THROW((void)out.decode(buf.data(), 0, static_cast<int>(buf.size())), std::length_error)
      << "lcm-gen's decode no longer throws here: this test documents why decodeLcm exists";
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
  LogEvent event;
  event.data = buf;
  EXPECT_FALSE(event.decode(out));
}

/// Big-endian int32 at `pos`.
void putCount(std::vector<uint8_t>& buf, size_t pos, uint32_t count) {
  for (int i = 0; i < 4; ++i) buf[pos + static_cast<size_t>(i)] = static_cast<uint8_t>(count >> (24 - 8 * i));
}

uint32_t getCount(const std::vector<uint8_t>& buf, size_t pos) {
  return (uint32_t{buf[pos]} << 24) | (uint32_t{buf[pos + 1]} << 16) | (uint32_t{buf[pos + 2]} << 8) | buf[pos + 3];
}

/// Messages the tests below take apart, each with its arrays and strings filled.
laser_scan_t threeBeamScan() {
  laser_scan_t scan{};
  scan.num_ranges = 3;
  scan.ranges = {1.0f, 2.0f, 3.0f};
  return scan;
}

sonar_targets_t twoTargetSonar() {
  sonar_targets_t sonar{};
  sonar.num_targets = 2;
  sonar.targets.resize(2);
  sonar.targets[1].range = 1.5;
  return sonar;
}

/// A line, a corner and two points; no break hints.
features_t featuresOfEachKind() {
  features_t features{};
  features.frame = "laser";
  features.num_lines = 1;
  features.lines.resize(1);
  features.lines[0].d = 2.0;
  features.num_corners = 1;
  features.corners.resize(1);
  features.num_points = 2;
  features.points.resize(2);
  features.points[1].x = -0.5;
  features.num_rejected = 3;
  return features;
}

path_t twoPosePath() {
  path_t path{};
  path.frame = "map";
  path.num_poses = 2;
  path.pose_utime = {1, 2};
  path.x = {0.0, 1.0};
  path.y = {0.0, 2.0};
  path.theta = {0.0, 0.0};
  path.source = {3, 3};
  return path;
}

/// One node, no edges.
pose_graph_t oneNodeGraph() {
  pose_graph_t graph{};
  graph.frame = "map";
  graph.num_nodes = 1;
  graph.node_id = {7};
  graph.node_utime = {8};
  graph.node_pose = {{1.0, 2.0, 3.0}};
  return graph;
}

process_status_t statusWithOneRejectKind() {
  process_status_t status{};
  status.name = "a";
  status.host = "b";
  status.state = "running";
  status.num_reject_kinds = 1;
  status.reject_kinds = {"laser: NaN range"};
  status.reject_counts = {5};
  return status;
}

scan_anchors_t oneAnchorMessage() {
  scan_anchors_t anchors{};
  anchors.pose.frame = "map";
  anchors.num_anchors = 1;
  anchors.anchors.resize(1);
  return anchors;
}

TEST(LcmDecode, HugeOrNegativeLaserCountIsRejectedBeforeAllocating) {
  std::vector<uint8_t> buf = encode(threeBeamScan());
  laser_scan_t out{};
  ASSERT_TRUE(decodeLcm(out, buf.data(), buf.size()));
  ASSERT_EQ(out.ranges.size(), 3u);
  const size_t count_at = 8 + 2 * 8 + 4 * 8 + 3 * 8;
  ASSERT_EQ(getCount(buf, count_at), 3u);
  putCount(buf, count_at, 0x7fffffffu);  // 2^31 - 1 beams in a 92-byte message: 8 GB if trusted
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
  putCount(buf, count_at, 4);  // one more beam than the bytes hold
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
  putCount(buf, count_at, 0xffffffffu);  // -1
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
}

TEST(LcmDecode, SonarAndFeatureCountsAreChecked) {
  std::vector<uint8_t> sbuf = encode(twoTargetSonar());
  sonar_targets_t sout{};
  ASSERT_TRUE(decodeLcm(sout, sbuf.data(), sbuf.size()));
  EXPECT_EQ(sout.targets.at(1).range, 1.5);
  const size_t targets_at = 8 + 2 * 8 + 4 + 3 * 8 + 2 * 8;
  ASSERT_EQ(getCount(sbuf, targets_at), 2u);
  putCount(sbuf, targets_at, 0x40000000u);
  EXPECT_FALSE(decodeLcm(sout, sbuf.data(), sbuf.size()));

  std::vector<uint8_t> fbuf = encode(featuresOfEachKind());
  features_t fout{};
  ASSERT_TRUE(decodeLcm(fout, fbuf.data(), fbuf.size()));
  EXPECT_EQ(fout.frame, "laser");
  EXPECT_EQ(fout.lines.at(0).d, 2.0);
  EXPECT_EQ(fout.points.at(1).x, -0.5);
  EXPECT_EQ(fout.num_rejected, 3);
  // The point count sits before 2 points, num_rejected and num_break_hints (no hints) at the end.
  const size_t points_at = fbuf.size() - 4 - 4 - 2 * static_cast<size_t>(point_feature_t{}.getEncodedSize() - 8) - 4;
  ASSERT_EQ(getCount(fbuf, points_at), 2u);
  putCount(fbuf, points_at, 0x7ffffff0u);
  EXPECT_FALSE(decodeLcm(fout, fbuf.data(), fbuf.size()));
}

// The types polarslam-bridge reads besides the sensor ones: a count that claims more than the
// bytes hold is refused before lcm-gen's decode() allocates for it.
TEST(LcmDecode, PathGraphAndStatusCountsAreCheckedAgainstTheirBytes) {
  std::vector<uint8_t> pbuf = encode(twoPosePath());
  path_t pout{};
  ASSERT_TRUE(decodeLcm(pout, pbuf.data(), pbuf.size()));
  EXPECT_EQ(pout.y.at(1), 2.0);
  const size_t poses_at = 8 + 16 + 4 + 4 + 8 + 1;  // hash utime seq "map" goal_utime goal_exact
  ASSERT_EQ(getCount(pbuf, poses_at), 2u);
  putCount(pbuf, poses_at, 0x7ffffff0u);
  EXPECT_FALSE(decodeLcm(pout, pbuf.data(), pbuf.size()));

  std::vector<uint8_t> gbuf = encode(oneNodeGraph());
  pose_graph_t gout{};
  ASSERT_TRUE(decodeLcm(gout, gbuf.data(), gbuf.size()));
  EXPECT_EQ(gout.node_pose.at(0)[2], 3.0);
  const size_t edges_at = 8 + 16 + 4 + 4 + 4 + 40;  // … "map", num_nodes, one node
  ASSERT_EQ(getCount(gbuf, edges_at), 0u);
  putCount(gbuf, edges_at, 1000u);
  EXPECT_FALSE(decodeLcm(gout, gbuf.data(), gbuf.size()));

  std::vector<uint8_t> sbuf = encode(statusWithOneRejectKind());
  process_status_t sout{};
  ASSERT_TRUE(decodeLcm(sout, sbuf.data(), sbuf.size()));
  EXPECT_EQ(sout.reject_kinds.at(0), "laser: NaN range");
  EXPECT_EQ(sout.reject_counts.at(0), 5);
  const size_t kinds_at = 8 + 8 + 6 + 6 + 4 + 12 + 4 + 24;  // hash utime name host pid state restarts counters
  ASSERT_EQ(getCount(sbuf, kinds_at), 1u);
  for (const uint32_t count : {2u, 0x7fffffffu, 0x80000000u}) {
    putCount(sbuf, kinds_at, count);
    EXPECT_FALSE(decodeLcm(sout, sbuf.data(), sbuf.size())) << count;
  }
}

// The break hints sit after num_rejected, last in features_t: the count the fuzzer found claiming
// gigabytes (CI run of stop 31) is refused.
TEST(LcmDecode, FeatureBreakHintCountIsChecked) {
  features_t features{};
  features.frame = "laser";
  features.num_break_hints = 2;
  features.break_hints = {0.25, 0.5};
  std::vector<uint8_t> buf = encode(features);
  features_t out{};
  ASSERT_TRUE(decodeLcm(out, buf.data(), buf.size()));
  EXPECT_EQ(out.break_hints.at(1), 0.5);
  const size_t hints_at = buf.size() - 2 * 8 - 4;
  ASSERT_EQ(getCount(buf, hints_at), 2u);
  for (const uint32_t count : {3u, 0x7fffffffu, 0x80000000u}) {
    putCount(buf, hints_at, count);
    EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size())) << count;
  }
}

/// A valid message decodes; the same bytes one short or one long do not (the layout walk of its type
/// must end exactly at its last byte, which checks the walk itself against lcm-gen's encoding).
template <typename MsgT>
void expectLayoutMatchesEncoding(const MsgT& msg) {
  std::vector<uint8_t> buf = encode(msg);
  MsgT out{};
  EXPECT_TRUE(decodeLcm(out, buf.data(), buf.size())) << MsgT::getTypeName();
  EXPECT_EQ(out.getEncodedSize(), msg.getEncodedSize()) << MsgT::getTypeName();
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size() - 1)) << MsgT::getTypeName() << " one byte short";
  buf.push_back(0);
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size())) << MsgT::getTypeName() << " one byte long";
  EXPECT_FALSE(decodeLcm(out, buf.data(), 0)) << MsgT::getTypeName() << " empty";
}

TEST(LcmDecode, EveryDecodedTypesLayoutMatchesItsEncoding) {
  expectLayoutMatchesEncoding(threeBeamScan());
  expectLayoutMatchesEncoding(odometry_t{});
  expectLayoutMatchesEncoding(twoTargetSonar());
  pose_t pose{};
  pose.frame = "map";
  expectLayoutMatchesEncoding(pose);
  features_t features = featuresOfEachKind();
  features.num_break_hints = 1;
  features.break_hints = {0.1};
  expectLayoutMatchesEncoding(features);
  grid_map_t grid{};
  grid.frame = "map";
  grid.source = "ekf-anchors";
  grid.num_bytes = 3;
  grid.data = {1, 2, 3};
  expectLayoutMatchesEncoding(grid);
  slam_map_t map{};
  map.robot.frame = "map";
  map.num_features = 2;
  map.features.resize(2);
  expectLayoutMatchesEncoding(map);
  expectLayoutMatchesEncoding(oneAnchorMessage());
  expectLayoutMatchesEncoding(twoPosePath());
  pose_graph_t graph = oneNodeGraph();
  graph.num_edges = 1;
  graph.edge_from = graph.edge_to = {7};
  graph.edge_kind = {1};
  graph.edge_active = {true};
  graph.edge_measurement = {{0.0, 0.0, 0.0}};
  graph.edge_cov = {std::vector<double>(9, 0.0)};
  expectLayoutMatchesEncoding(graph);
  process_status_t status = statusWithOneRejectKind();  // two kinds: the layout walks a list of strings
  status.num_reject_kinds = 2;
  status.reject_kinds.push_back("bc");
  status.reject_counts.push_back(2);
  expectLayoutMatchesEncoding(status);
  scan_match_t match{};
  match.method = "psm";
  match.status = "converged";
  expectLayoutMatchesEncoding(match);
  grid_request_t request{};
  request.out_dir = "/tmp/maps";
  expectLayoutMatchesEncoding(request);
  grid_status_t grid_status{};
  grid_status.state = "idle";
  grid_status.out_dir = "/tmp";
  grid_status.plan_state = "none";
  expectLayoutMatchesEncoding(grid_status);
  expectLayoutMatchesEncoding(anchored_pose_t{});
  expectLayoutMatchesEncoding(goal_t{});
  expectLayoutMatchesEncoding(map_request_t{});
}

TEST(LcmDecode, NestedPoseFrameAndAnchorCountsAreChecked) {
  std::vector<uint8_t> buf = encode(oneAnchorMessage());
  scan_anchors_t out{};
  ASSERT_TRUE(decodeLcm(out, buf.data(), buf.size()));
  const size_t frame_at = 8 + 2 * 8 + 2 * 8;  // hash, utime seq, the pose's utime seq
  ASSERT_EQ(getCount(buf, frame_at), 4u);
  putCount(buf, frame_at, 0x80000000u);  // INT_MIN: lcm-gen computes INT_MIN - 1
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
  putCount(buf, frame_at, 4u);
  const size_t anchors_at = frame_at + 4 + 4 + 12 * 8;
  ASSERT_EQ(getCount(buf, anchors_at), 1u);
  putCount(buf, anchors_at, 0x10000000u);
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
}

}  // namespace
}  // namespace polarslam
