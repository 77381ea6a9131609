// foxglove.* JSON messages built from polarslam data: checked against RFC 4648 base64 vectors,
// the quaternion of a yaw, the χ² 95 % ellipse in closed form, and the published schemas'
// property lists (foxglove_schemas.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "common/foxglove_messages.hpp"
#include "common/foxglove_schemas.hpp"
#include "common/pose_trail.hpp"

namespace polarslam::foxglove {
namespace {

using Json = nlohmann::json;

/// Every property of `schema` is in `message` and nothing else, recursively through objects.
void expectShape(const Json& message, const Json& schema, const std::string& where) {
  if (!schema.contains("properties")) return;
  ASSERT_TRUE(message.is_object()) << where;
  for (const auto& [key, sub] : schema["properties"].items()) {
    ASSERT_TRUE(message.contains(key)) << where << "." << key;
    if (sub.value("type", "") == "object") expectShape(message[key], sub, where + "." + key);
    if (sub.value("type", "") == "array" && sub["items"].value("type", "") == "object")
      for (const Json& item : message[key]) expectShape(item, sub["items"], where + "." + key + "[]");
  }
  for (const auto& [key, value] : message.items()) EXPECT_TRUE(schema["properties"].contains(key)) << where << "." << key;
}

std::string decodeBase64(const std::string& text) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    if (c == '=') break;
    bits = (bits << 6) | static_cast<uint32_t>(alphabet.find(c));
    if ((count += 6) >= 8) out += static_cast<char>((bits >> (count -= 8)) & 0xff);
  }
  return out;
}

TEST(FoxgloveMessages, Base64MatchesTheRfc4648Vectors) {
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foob"), "Zm9vYg==");
  EXPECT_EQ(base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64(std::string("\xff\x00\x80", 3)), "/wCA");
}

TEST(FoxgloveMessages, TimestampsAndPoses) {
  const Json t = timestamp(1234567890123456);
  EXPECT_EQ(t["sec"], 1234567890);
  EXPECT_EQ(t["nsec"], 123456000);
  EXPECT_EQ(timestamp(-5)["sec"], 0);
  const Json p = pose(Pose2(1.0, -2.0, M_PI / 2));
  EXPECT_DOUBLE_EQ(p["position"]["x"], 1.0);
  EXPECT_DOUBLE_EQ(p["position"]["y"], -2.0);
  EXPECT_NEAR(p["orientation"]["z"].get<double>(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(p["orientation"]["w"].get<double>(), std::sqrt(0.5), 1e-12);
}

TEST(FoxgloveMessages, GridCellsAreInt8PercentWithUnknownMinusOne) {
  GridSlice slice;
  slice.resolution = 0.1;
  slice.origin = Vec2(-1.0, 2.0);
  slice.width = 3;
  slice.height = 2;
  slice.probability = {std::nanf(""), 0.0f, 1.0f, 0.5f, 0.254f, 0.2f};
  const Json g = grid(slice, 5000000, "map");
  expectShape(g, schema("foxglove.Grid"), "Grid");
  EXPECT_EQ(g["column_count"], 3);
  EXPECT_EQ(g["row_stride"], 3);
  EXPECT_EQ(g["cell_stride"], 1);
  EXPECT_EQ(g["fields"][0]["type"], 2);  // INT8
  EXPECT_DOUBLE_EQ(g["pose"]["position"]["x"], -1.0);
  EXPECT_DOUBLE_EQ(g["cell_size"]["y"], 0.1);
  const std::string cells = decodeBase64(g["data"]);
  ASSERT_EQ(cells.size(), 6u);
  const std::vector<int> expected = {-1, 0, 100, 50, 25, 20};
  for (size_t i = 0; i < cells.size(); ++i) EXPECT_EQ(static_cast<int8_t>(cells[i]), expected[i]) << i;
}

TEST(FoxgloveMessages, LaserScanAnglesAndNoReturns) {
  LaserScan scan;
  scan.utime = 7;
  scan.angle_min = -M_PI / 2;
  scan.angle_increment = M_PI / 180;
  scan.range_max = 8.0;
  scan.ranges.assign(181, 2.5f);
  scan.ranges[3] = std::nanf("");
  scan.ranges[4] = 8.0f;
  const Json s = laserScan(scan);
  expectShape(s, schema("foxglove.LaserScan"), "LaserScan");
  EXPECT_EQ(s["frame_id"], "laser");
  EXPECT_NEAR(s["end_angle"].get<double>(), M_PI / 2, 1e-12);
  ASSERT_EQ(s["ranges"].size(), 181u);
  EXPECT_EQ(s["ranges"][3], 0.0);
  EXPECT_EQ(s["ranges"][4], 0.0);
  EXPECT_FLOAT_EQ(s["ranges"][5].get<float>(), 2.5f);
}

TEST(FoxgloveMessages, PointCovarianceEllipseIsTheChiSquared95Contour) {
  FeatureMap map;
  MapFeature point;
  point.kind = MapFeatureKind::Point;
  point.params = Vec3(3.0, 1.0, 0.0);
  point.cov.topLeftCorner<2, 2>() << 0.04, 0.0, 0.0, 0.01;
  map.features.push_back(point);
  const Json scene = featureMapScene(map);
  expectShape(scene, schema("foxglove.SceneUpdate"), "SceneUpdate");
  const Json& entity = scene["entities"][0];
  ASSERT_EQ(entity["spheres"].size(), 1u);
  const Json* ellipse = nullptr;
  for (const Json& line : entity["lines"])
    if (line["points"].size() > 10) ellipse = &line;
  ASSERT_NE(ellipse, nullptr);
  const double chi2_95 = -2.0 * std::log(0.05);  // 2 degrees of freedom: closed form
  for (const Json& p : (*ellipse)["points"]) {
    const double dx = p["x"].get<double>() - 3.0, dy = p["y"].get<double>() - 1.0;
    EXPECT_NEAR(dx * dx / 0.04 + dy * dy / 0.01, chi2_95, 1e-6);
  }
}

TEST(FoxgloveMessages, ConcaveCornerArmsOpenTowardsFreeSpaceAndLinesBecomeSegments) {
  FeatureMap map;
  MapFeature corner;
  corner.kind = MapFeatureKind::Corner;
  corner.params = Vec3(1.0, 1.0, 0.0);  // bisector along +x
  corner.cov = Mat3::Identity() * 0.01;
  MapFeature line;
  line.kind = MapFeatureKind::Line;
  line.params = Vec3(0.0, 2.0, 0.0);
  line.cov = Mat3::Identity() * 0.0001;
  line.endpoint_a = Vec2(2.0, -1.0);
  line.endpoint_b = Vec2(2.0, 1.0);
  map.features = {corner, line};
  const Json lines = featureMapScene(map)["entities"][0]["lines"];
  const Json& segments = lines[0]["points"];
  ASSERT_EQ(segments.size(), 2u);
  EXPECT_DOUBLE_EQ(segments[1]["y"], 1.0);
  const Json& arms = lines[1]["points"];
  ASSERT_EQ(arms.size(), 4u);
  for (const int end : {1, 3}) {
    EXPECT_NEAR(arms[end]["x"].get<double>() - 1.0, 0.3 * std::sqrt(0.5), 1e-9);  // both arms ahead of the apex
    EXPECT_NEAR(std::abs(arms[end]["y"].get<double>() - 1.0), 0.3 * std::sqrt(0.5), 1e-9);
  }
  const Json& band = lines[3]["points"];  // ±2σ_d = ±0.02 m either side of x = 2
  ASSERT_EQ(band.size(), 4u);
  EXPECT_NEAR(band[0]["x"].get<double>(), 1.98, 1e-9);
  EXPECT_NEAR(band[2]["x"].get<double>(), 2.02, 1e-9);
}

TEST(FoxgloveMessages, PoseGraphLoopsAreSeparateFromTheChain) {
  PoseGraph graph;
  for (int i = 0; i < 3; ++i) graph.addNode({i, i * 1000, Pose2(i, 0.0, 0.0)});
  PoseGraphEdge e;
  e.from = 0; e.to = 1; e.measurement = Pose2(1, 0, 0);
  graph.addEdge(e);
  e.from = 1; e.to = 2;
  graph.addEdge(e);
  e.from = 0; e.to = 2; e.measurement = Pose2(2, 0, 0); e.kind = PoseGraphEdgeKind::Loop;
  graph.addEdge(e);
  const Json scene = poseGraphScene(graph, 3000);
  expectShape(scene, schema("foxglove.SceneUpdate"), "SceneUpdate");
  const Json& entity = scene["entities"][0];
  EXPECT_EQ(entity["spheres"].size(), 3u);
  EXPECT_EQ(entity["lines"][0]["points"].size(), 4u);  // two chain edges
  ASSERT_EQ(entity["lines"][1]["points"].size(), 2u);  // one loop closure
  EXPECT_DOUBLE_EQ(entity["lines"][1]["points"][1]["x"], 2.0);
}

TEST(FoxgloveMessages, EveryMessageHasItsSchemasFields) {
  PoseStamped p;
  p.utime = 1;
  expectShape(poseInFrame(p, "map"), schema("foxglove.PoseInFrame"), "PoseInFrame");
  expectShape(posesInFrame({Pose2(), Pose2(1, 1, 1)}, 1, "map"), schema("foxglove.PosesInFrame"), "PosesInFrame");
  expectShape(frameTransform(Pose2(0.2, 0, 0), 1, "base_link", "laser"), schema("foxglove.FrameTransform"), "Transform");
  ProcessState s{1, "polarslam-grid", "base", "crashed", 42, 1, 10, 2, 0, std::nan(""), 12.5};
  expectShape(processLog(s, "running"), schema("foxglove.Log"), "Log");
  expectShape(processStatus(s), schema("polarslam.ProcessStatus"), "ProcessStatus");
  EXPECT_EQ(processLog(s, "running")["level"], 4);  // ERROR
  EXPECT_EQ(processStatus(s)["cpu_percent"], 0.0);  // NaN is not JSON
  EXPECT_THROW(schema("foxglove.Nonsense"), std::invalid_argument);
  for (const std::string& name : schemaNames()) EXPECT_EQ(schema(name)["title"], name);
}

TEST(FoxgloveMessages, GoalsFromTheShapesClientsSend) {
  Vec2 at;
  double theta = 0.0;
  EXPECT_EQ(goalFromJson({{"x", 1.5}, {"y", -2.0}}, at, theta), "");
  EXPECT_EQ(at, Vec2(1.5, -2.0));
  EXPECT_TRUE(std::isnan(theta));
  EXPECT_EQ(goalFromJson({{"x", 1.0}, {"y", 2.0}, {"theta", 0.5}}, at, theta), "");
  EXPECT_DOUBLE_EQ(theta, 0.5);
  EXPECT_EQ(goalFromJson(Json::parse(R"({"pose":{"position":{"x":3,"y":4,"z":0}}})"), at, theta), "");
  EXPECT_EQ(at, Vec2(3.0, 4.0));
  EXPECT_EQ(goalFromJson(Json::parse(R"({"point":{"x":5,"y":6}})"), at, theta), "");
  EXPECT_EQ(at, Vec2(5.0, 6.0));
  EXPECT_NE(goalFromJson(Json::parse(R"({"x":"1","y":2})"), at, theta), "");
  EXPECT_NE(goalFromJson(Json::parse(R"({"x":1})"), at, theta), "");
  EXPECT_NE(goalFromJson({{"x", INFINITY}, {"y", 0.0}}, at, theta), "");
  EXPECT_NE(goalFromJson({{"x", 1.0}, {"y", nullptr}}, at, theta), "");
}

TEST(PoseTrail, KeepsPosesThatMovedAndStaysBounded) {
  PoseTrail trail(8);
  for (int i = 0; i < 100; ++i) trail.add({i, Pose2(0.001 * i, 0.0, 0.0), Mat3::Zero()}, "map");
  EXPECT_EQ(trail.poses().size(), 2u);  // 0 and 0.05 m
  EXPECT_TRUE(trail.takeChanged());
  EXPECT_FALSE(trail.takeChanged());
  for (int i = 0; i < 100; ++i) trail.add({i, Pose2(1.0 + i, 0.0, 0.0), Mat3::Zero()}, "map");
  EXPECT_LE(trail.poses().size(), 8u);
  EXPECT_DOUBLE_EQ(trail.poses().back().x, 100.0);  // the newest pose is always kept
  trail.add({1, Pose2(0, 0, 0), Mat3::Zero()}, "world");
  EXPECT_EQ(trail.poses().size(), 1u);
  EXPECT_EQ(trail.frame(), "world");
}

TEST(PoseTrail, HeadingsPointAlongThePath) {
  const std::vector<Pose2> poses = headingsAlong({Vec2(0, 0), Vec2(1, 0), Vec2(1, 1)});
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_DOUBLE_EQ(poses[0].theta, 0.0);
  EXPECT_DOUBLE_EQ(poses[1].theta, M_PI / 2);
  EXPECT_DOUBLE_EQ(poses[2].theta, M_PI / 2);
}

}  // namespace
}  // namespace polarslam::foxglove
