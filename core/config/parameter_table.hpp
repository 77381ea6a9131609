#pragma once
// One table per component binds every configuration key to its field, its range and a line of
// documentation, so that one description serves reading a YAML file (ranges checked, unknown keys
// rejected, errors "FILE:LINE: key ..."), printing the effective parameters (--print-config) and
// proving that a shipped defaults file (config/*.yaml) lists every key with the built-in default.
// Angles are radians in the code and degrees in the files: their keys end in `_deg`.
//
//   ParameterTable table;
//   table.number("keyframe_distance", p.keyframe_distance, 0.01, 100, "m from the active reference scan");
//   table.angle("keyframe_angle_deg", p.keyframe_angle, 1, 180, "from the active reference scan");
//   ParameterTable& psm = table.section("psm", "the scan matcher");
//   table.read(yaml, yaml.root(), "psm-slam");
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "config/yaml_fields.hpp"

namespace polarslam {

class ParameterTable {
 public:
  void number(std::string key, double& field, double lo, double hi, std::string doc);
  /// `field` in radians; the file's key (ending in _deg) holds degrees in [lo_deg, hi_deg].
  void angle(std::string key, double& field, double lo_deg, double hi_deg, std::string doc);
  void integer(std::string key, int& field, int lo, int hi, std::string doc);
  void count(std::string key, size_t& field, size_t lo, size_t hi, std::string doc);
  void boolean(std::string key, bool& field, std::string doc);
  /// A word among `options`, stored through `set` (false = refused) and shown through `get`.
  void choice(std::string key, std::vector<std::string> options, std::function<bool(const std::string&)> set,
              std::function<std::string()> get, std::string doc);
  /// A nested map of parameters.
  ParameterTable& section(std::string key, std::string doc);

  /// Sets the fields from `map`; keys left out keep their values.
  void read(const YamlFields& yaml, const YAML::Node& map, const std::string& context) const;
  /// Keys of this table (dotted for sections), in declaration order.
  std::vector<std::string> keys() const;
  /// Declared keys that `map` does not hold (dotted).
  std::vector<std::string> missingFrom(const YAML::Node& map) const;
  /// The current values as YAML, one key a line with its documentation as a comment.
  std::string yaml(int indent = 0) const;

 private:
  struct Entry {
    std::string key, doc;
    std::function<void(const YamlFields&, const YAML::Node&, const std::string&)> read;
    std::function<std::string()> value;
    std::unique_ptr<ParameterTable> section;
  };
  Entry& add(std::string key, std::string doc);

  std::vector<Entry> entries_;
};

}  // namespace polarslam
