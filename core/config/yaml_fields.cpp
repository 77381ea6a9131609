#include "config/yaml_fields.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace polarslam {
namespace {

std::string formatRange(double lo, double hi) {
  std::ostringstream s;
  s << "[" << lo << ", " << hi << "]";
  return s.str();
}

}  // namespace

YamlFields::YamlFields(std::string path) : path_(std::move(path)) {
  if (!std::filesystem::is_regular_file(path_))
    throw std::runtime_error(path_ + ": cannot open (no such file)");
  try {
    root_ = YAML::LoadFile(path_);
  } catch (const YAML::ParserException& e) {
    throw std::runtime_error(path_ + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path_ + ": cannot read: " + e.what());
  }
  if (!root_.IsMap()) throw std::runtime_error(path_ + ":1: expected a map of keys at the top level");
}

std::string YamlFields::where(const YAML::Node& node) const {
  const YAML::Mark mark = node.IsDefined() ? node.Mark() : YAML::Mark::null_mark();
  if (mark.line < 0) return path_;
  return path_ + ":" + std::to_string(mark.line + 1);
}

void YamlFields::fail(const YAML::Node& at, const std::string& what) const {
  throw std::runtime_error(where(at) + ": " + what);
}

void YamlFields::requireMap(const YAML::Node& node, const std::string& what,
                            std::initializer_list<const char*> allowed) const {
  if (!node.IsMap()) fail(node, what + ": expected a map of keys");
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    const bool known = std::any_of(allowed.begin(), allowed.end(),
                                   [&](const char* a) { return key == a; });
    if (!known) {
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
      fail(kv.first, "unknown key '" + key + "' in " + what + " (allowed: " + list + ")");
    }
  }
}

void YamlFields::requireMap(const YAML::Node& node, const std::string& what,
                            const std::vector<std::string>& allowed) const {
  if (!node.IsMap()) fail(node, what + ": expected a map of keys");
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string list;
    for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(kv.first, "unknown key '" + key + "' in " + what + " (allowed: " + list + ")");
  }
}

void YamlFields::requireSequence(const YAML::Node& node, const std::string& what) const {
  if (!node.IsSequence()) fail(node, what + ": expected a list");
}

double YamlFields::number(const YAML::Node& node, const std::string& name, double lo, double hi) const {
  if (!node.IsScalar()) fail(node, name + ": expected a number");
  double v = 0.0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    fail(node, name + ": '" + node.Scalar() + "' is not a number");
  }
  if (!std::isfinite(v)) fail(node, name + ": must be finite, got '" + node.Scalar() + "'");
  if (v < lo || v > hi)
    fail(node, name + ": " + node.Scalar() + " is outside the allowed range " + formatRange(lo, hi));
  return v;
}

double YamlFields::number(const YAML::Node& map, const char* key, const std::string& context,
                          double fallback, double lo, double hi) const {
  const YAML::Node node = map[key];
  if (!node) return fallback;
  return number(node, context + "." + key, lo, hi);
}

double YamlFields::requiredNumber(const YAML::Node& map, const char* key, const std::string& context,
                                  double lo, double hi) const {
  const YAML::Node node = map[key];
  if (!node) fail(map, "missing key '" + std::string(key) + "' in " + context);
  return number(node, context + "." + key, lo, hi);
}

int YamlFields::integer(const YAML::Node& map, const char* key, const std::string& context,
                        int fallback, int lo, int hi) const {
  const YAML::Node node = map[key];
  if (!node) return fallback;
  const double v = number(node, context + "." + key, lo, hi);
  if (v != std::floor(v)) fail(node, context + "." + key + ": expected a whole number, got " + node.Scalar());
  return static_cast<int>(v);
}

bool YamlFields::boolean(const YAML::Node& map, const char* key, const std::string& context,
                         bool fallback) const {
  const YAML::Node node = map[key];
  if (!node) return fallback;
  try {
    if (node.IsScalar()) return node.as<bool>();
  } catch (const YAML::Exception&) {
  }
  fail(node, context + "." + key + ": expected true or false");
}

std::string YamlFields::text(const YAML::Node& map, const char* key, const std::string& context,
                             const std::string& fallback) const {
  const YAML::Node node = map[key];
  if (!node) return fallback;
  if (!node.IsScalar()) fail(node, context + "." + key + ": expected a word");
  return node.Scalar();
}

Vec2 YamlFields::point(const YAML::Node& node, const std::string& name, double limit) const {
  if (!node.IsSequence() || node.size() != 2) fail(node, name + ": expected a point [x, y]");
  return {number(node[0], name + "[0]", -limit, limit), number(node[1], name + "[1]", -limit, limit)};
}

Pose2 YamlFields::pose(const YAML::Node& node, const std::string& name, double limit) const {
  requireMap(node, name, {"x", "y", "theta_deg"});
  return {requiredNumber(node, "x", name, -limit, limit), requiredNumber(node, "y", name, -limit, limit),
          deg2rad(number(node, "theta_deg", name, 0.0, -360.0, 360.0))};
}

}  // namespace polarslam
