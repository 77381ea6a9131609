#pragma once
// Reading hand-written YAML (worlds, robot configs) with errors a user can act on: every
// failure is a std::runtime_error "FILE:LINE: what is wrong (key ...)".
#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

class YamlFields {
 public:
  /// Parses `path`; syntax errors and unreadable files are reported with the file name.
  explicit YamlFields(std::string path);

  const YAML::Node& root() const { return root_; }
  const std::string& path() const { return path_; }

  /// "FILE:LINE" of a node (LINE counted from 1).
  std::string where(const YAML::Node& node) const;
  [[noreturn]] void fail(const YAML::Node& at, const std::string& what) const;

  /// Fails unless `node` is a map whose keys are all in `allowed` (catches typos).
  void requireMap(const YAML::Node& node, const std::string& what,
                  std::initializer_list<const char*> allowed) const;
  void requireMap(const YAML::Node& node, const std::string& what, const std::vector<std::string>& allowed) const;
  /// Fails unless `node` is a sequence.
  void requireSequence(const YAML::Node& node, const std::string& what) const;

  bool has(const YAML::Node& map, const char* key) const { return map.IsMap() && map[key]; }

  /// A finite number in [lo, hi]. `name` is the key path shown in errors.
  double number(const YAML::Node& node, const std::string& name, double lo, double hi) const;
  /// map[key] as a number in [lo, hi], or `fallback` when the key is absent.
  double number(const YAML::Node& map, const char* key, const std::string& context, double fallback,
                double lo, double hi) const;
  /// map[key] as a number in [lo, hi]; the key must be present.
  double requiredNumber(const YAML::Node& map, const char* key, const std::string& context,
                        double lo, double hi) const;
  int integer(const YAML::Node& map, const char* key, const std::string& context, int fallback,
              int lo, int hi) const;
  bool boolean(const YAML::Node& map, const char* key, const std::string& context,
               bool fallback) const;
  std::string text(const YAML::Node& map, const char* key, const std::string& context,
                   const std::string& fallback) const;
  /// A two-number sequence [x, y], each within ±limit.
  Vec2 point(const YAML::Node& node, const std::string& name, double limit) const;
  /// {x, y, theta_deg} with theta in degrees in the file, radians in the result.
  Pose2 pose(const YAML::Node& node, const std::string& name, double limit) const;

 private:
  std::string path_;
  YAML::Node root_;
};

}  // namespace polarslam
