#include "common/foxglove_schemas.hpp"

#include <functional>
#include <map>
#include <stdexcept>

namespace polarslam::foxglove {
// Named, so that these builders cannot meet foxglove_messages.cpp's message builders of the same names.
namespace json_schema {
namespace {

using Json = nlohmann::json;

Json number() { return {{"type", "number"}}; }
Json integer() { return {{"type", "integer"}}; }
Json text() { return {{"type", "string"}}; }
Json boolean() { return {{"type", "boolean"}}; }
Json arrayOf(Json items) { return {{"type", "array"}, {"items", std::move(items)}}; }
/// An integer enum: values 0 … names.size() - 1.
Json enumeration(const std::vector<std::string>& names) {
  Json one_of = Json::array();
  for (size_t i = 0; i < names.size(); ++i) one_of.push_back({{"title", names[i]}, {"const", i}});
  return {{"oneOf", one_of}};
}
Json object(const std::string& title, Json properties) {
  return {{"type", "object"}, {"title", title}, {"properties", std::move(properties)}};
}

Json time() {
  return object("time", {{"sec", {{"type", "integer"}, {"minimum", 0}}},
                         {"nsec", {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}}}});
}
Json vector2() { return object("foxglove.Vector2", {{"x", number()}, {"y", number()}}); }
Json vector3() { return object("foxglove.Vector3", {{"x", number()}, {"y", number()}, {"z", number()}}); }
Json point3() { return object("foxglove.Point3", {{"x", number()}, {"y", number()}, {"z", number()}}); }
Json quaternion() {
  return object("foxglove.Quaternion", {{"x", number()}, {"y", number()}, {"z", number()}, {"w", number()}});
}
Json pose() { return object("foxglove.Pose", {{"position", vector3()}, {"orientation", quaternion()}}); }
Json color() { return object("foxglove.Color", {{"r", number()}, {"g", number()}, {"b", number()}, {"a", number()}}); }

Json grid() {
  const Json field = object("foxglove.PackedElementField",
                            {{"name", text()},
                             {"offset", {{"type", "integer"}, {"minimum", 0}}},
                             {"type", enumeration({"UNKNOWN", "UINT8", "INT8", "UINT16", "INT16", "UINT32", "INT32",
                                                   "FLOAT32", "FLOAT64"})}});
  return object("foxglove.Grid", {{"timestamp", time()},
                                  {"frame_id", text()},
                                  {"pose", pose()},
                                  {"column_count", {{"type", "integer"}, {"minimum", 0}}},
                                  {"cell_size", vector2()},
                                  {"row_stride", {{"type", "integer"}, {"minimum", 0}}},
                                  {"cell_stride", {{"type", "integer"}, {"minimum", 0}}},
                                  {"fields", arrayOf(field)},
                                  {"data", {{"type", "string"}, {"contentEncoding", "base64"}}}});
}

Json laserScan() {
  return object("foxglove.LaserScan", {{"timestamp", time()},
                                       {"frame_id", text()},
                                       {"pose", pose()},
                                       {"start_angle", number()},
                                       {"end_angle", number()},
                                       {"ranges", arrayOf(number())},
                                       {"intensities", arrayOf(number())}});
}

Json poseInFrame() {
  return object("foxglove.PoseInFrame", {{"timestamp", time()}, {"frame_id", text()}, {"pose", pose()}});
}

Json posesInFrame() {
  return object("foxglove.PosesInFrame", {{"timestamp", time()}, {"frame_id", text()}, {"poses", arrayOf(pose())}});
}

Json frameTransform() {
  return object("foxglove.FrameTransform", {{"timestamp", time()},
                                            {"parent_frame_id", text()},
                                            {"child_frame_id", text()},
                                            {"translation", vector3()},
                                            {"rotation", quaternion()}});
}

Json log() {
  return object("foxglove.Log", {{"timestamp", time()},
                                 {"level", enumeration({"UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL"})},
                                 {"message", text()},
                                 {"name", text()},
                                 {"file", text()},
                                 {"line", {{"type", "integer"}, {"minimum", 0}}}});
}

Json sizedPrimitive(const std::string& title) {
  return object(title, {{"pose", pose()}, {"size", vector3()}, {"color", color()}});
}

Json sceneEntity() {
  const Json key_value = object("foxglove.KeyValuePair", {{"key", text()}, {"value", text()}});
  const Json arrow = object("foxglove.ArrowPrimitive", {{"pose", pose()},
                                                        {"shaft_length", number()},
                                                        {"shaft_diameter", number()},
                                                        {"head_length", number()},
                                                        {"head_diameter", number()},
                                                        {"color", color()}});
  Json cylinder = sizedPrimitive("foxglove.CylinderPrimitive");
  cylinder["properties"]["bottom_scale"] = number();
  cylinder["properties"]["top_scale"] = number();
  const Json line = object("foxglove.LinePrimitive",
                           {{"type", enumeration({"LINE_STRIP", "LINE_LOOP", "LINE_LIST"})},
                            {"pose", pose()},
                            {"thickness", {{"type", "number"}, {"minimum", 0}}},
                            {"scale_invariant", boolean()},
                            {"points", arrayOf(point3())},
                            {"color", color()},
                            {"colors", arrayOf(color())},
                            {"indices", arrayOf({{"type", "integer"}, {"minimum", 0}})}});
  const Json triangles = object("foxglove.TriangleListPrimitive", {{"pose", pose()},
                                                                   {"points", arrayOf(point3())},
                                                                   {"color", color()},
                                                                   {"colors", arrayOf(color())},
                                                                   {"indices", arrayOf({{"type", "integer"}, {"minimum", 0}})}});
  const Json text_primitive = object("foxglove.TextPrimitive", {{"pose", pose()},
                                                               {"billboard", boolean()},
                                                               {"font_size", number()},
                                                               {"scale_invariant", boolean()},
                                                               {"color", color()},
                                                               {"text", text()}});
  const Json model = object("foxglove.ModelPrimitive", {{"pose", pose()},
                                                       {"scale", vector3()},
                                                       {"color", color()},
                                                       {"override_color", boolean()},
                                                       {"url", text()},
                                                       {"media_type", text()},
                                                       {"data", {{"type", "string"}, {"contentEncoding", "base64"}}}});
  Json duration = time();
  duration["title"] = "duration";
  return object("foxglove.SceneEntity", {{"timestamp", time()},
                                         {"frame_id", text()},
                                         {"id", text()},
                                         {"lifetime", duration},
                                         {"frame_locked", boolean()},
                                         {"metadata", arrayOf(key_value)},
                                         {"arrows", arrayOf(arrow)},
                                         {"cubes", arrayOf(sizedPrimitive("foxglove.CubePrimitive"))},
                                         {"spheres", arrayOf(sizedPrimitive("foxglove.SpherePrimitive"))},
                                         {"cylinders", arrayOf(cylinder)},
                                         {"lines", arrayOf(line)},
                                         {"triangles", arrayOf(triangles)},
                                         {"texts", arrayOf(text_primitive)},
                                         {"models", arrayOf(model)}});
}

Json sceneUpdate() {
  const Json deletion = object("foxglove.SceneEntityDeletion",
                               {{"timestamp", time()}, {"type", enumeration({"MATCHING_ID", "ALL"})}, {"id", text()}});
  return object("foxglove.SceneUpdate", {{"deletions", arrayOf(deletion)}, {"entities", arrayOf(sceneEntity())}});
}

Json processStatus() {
  return object("polarslam.ProcessStatus", {{"timestamp", time()},
                                            {"name", text()},
                                            {"host", text()},
                                            {"pid", integer()},
                                            {"state", text()},
                                            {"restarts", integer()},
                                            {"messages_handled", integer()},
                                            {"messages_rejected", integer()},
                                            {"messages_dropped", integer()},
                                            {"cpu_percent", number()},
                                            {"rss_mb", number()}});
}

const std::map<std::string, std::function<Json()>>& builders() {
  static const std::map<std::string, std::function<Json()>> table = {
      {"foxglove.Grid", grid},
      {"foxglove.LaserScan", laserScan},
      {"foxglove.PoseInFrame", poseInFrame},
      {"foxglove.PosesInFrame", posesInFrame},
      {"foxglove.FrameTransform", frameTransform},
      {"foxglove.SceneUpdate", sceneUpdate},
      {"foxglove.Log", log},
      {"polarslam.ProcessStatus", processStatus},
  };
  return table;
}

}  // namespace
}  // namespace json_schema

nlohmann::json schema(const std::string& schema_name) {
  const auto it = json_schema::builders().find(schema_name);
  if (it == json_schema::builders().end()) throw std::invalid_argument("no JSON schema for " + schema_name);
  return it->second();
}

std::vector<std::string> schemaNames() {
  std::vector<std::string> names;
  for (const auto& entry : json_schema::builders()) names.push_back(entry.first);
  return names;
}

}  // namespace polarslam::foxglove
