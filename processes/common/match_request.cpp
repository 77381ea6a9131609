#include "common/match_request.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <utility>

namespace polarslam {
namespace {

using nlohmann::json;

std::string scanFromJson(const json& j, LaserScan& scan) {
  if (!j.is_object()) return "is not an object";
  for (const char* key : {"angle_min", "angle_increment", "range_max"})
    if (!j.contains(key) || !j[key].is_number()) return std::string("has no numeric '") + key + "'";
  scan.angle_min = j["angle_min"].get<double>();
  scan.angle_increment = j["angle_increment"].get<double>();
  scan.range_max = j["range_max"].get<double>();
  if (!j.contains("ranges") || !j["ranges"].is_array()) return "has no 'ranges' array";
  const json& ranges = j["ranges"];
  if (ranges.size() > kMaxLaserBeams) return "has too many ranges";
  scan.ranges.resize(ranges.size());
  for (size_t i = 0; i < ranges.size(); ++i) {
    if (ranges[i].is_null()) scan.ranges[i] = std::numeric_limits<float>::quiet_NaN();
    else if (ranges[i].is_number()) scan.ranges[i] = ranges[i].get<float>();
    else return "ranges[" + std::to_string(i) + "] is not a number";
  }
  const std::string why = validateScan(scan);
  return why.empty() ? why : "is invalid: " + why;
}

std::string guessFromJson(const json& line, Pose2& guess) {
  if (!line.contains("guess")) return {};
  const json& g = line["guess"];
  if (!g.is_array() || g.size() != 3) return "'guess' is not [x, y, theta]";
  for (const json& v : g)
    if (!v.is_number() || !std::isfinite(v.get<double>())) return "'guess' holds a non-finite value";
  guess = {g[0].get<double>(), g[1].get<double>(), wrapAngle(g[2].get<double>())};
  return {};
}

}  // namespace

std::string parseMatchRequest(const std::string& text, MatchRequest& request) {
  const json line = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (line.is_discarded()) return "bad input: not valid JSON";
  if (!line.is_object()) return "bad input: not a JSON object";
  for (auto [key, scan] : {std::pair<const char*, LaserScan*>{"ref", &request.ref}, {"cur", &request.cur}}) {
    if (!line.contains(key)) return std::string("bad input: no '") + key + "' scan";
    const std::string why = scanFromJson(line[key], *scan);
    if (!why.empty()) return std::string("bad input: '") + key + "' " + why;
  }
  request.guess = Pose2{};
  if (const std::string why = guessFromJson(line, request.guess); !why.empty()) return "bad input: " + why;
  return {};
}

}  // namespace polarslam
