#include "config/parameter_table.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace polarslam {
namespace {

std::string formatNumber(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string joined(const std::vector<std::string>& words, const char* separator) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : separator) + w;
  return out;
}

}  // namespace

ParameterTable::Entry& ParameterTable::add(std::string key, std::string doc) {
  if (std::any_of(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.key == key; }))
    throw std::logic_error("parameter '" + key + "' declared twice");
  entries_.push_back({std::move(key), std::move(doc), {}, {}, {}});
  return entries_.back();
}

void ParameterTable::number(std::string key, double& field, double lo, double hi, std::string doc) {
  Entry& e = add(std::move(key), std::move(doc));
  e.read = [&field, lo, hi](const YamlFields& y, const YAML::Node& node, const std::string& name) {
    field = y.number(node, name, lo, hi);
  };
  e.value = [&field] { return formatNumber(field); };
}

void ParameterTable::angle(std::string key, double& field, double lo_deg, double hi_deg, std::string doc) {
  if (key.size() < 4 || key.compare(key.size() - 4, 4, "_deg") != 0)
    throw std::logic_error("angle parameter '" + key + "' must end in _deg");
  Entry& e = add(std::move(key), std::move(doc));
  e.read = [&field, lo_deg, hi_deg](const YamlFields& y, const YAML::Node& node, const std::string& name) {
    field = deg2rad(y.number(node, name, lo_deg, hi_deg));
  };
  e.value = [&field] { return formatNumber(rad2deg(field)); };
}

void ParameterTable::integer(std::string key, int& field, int lo, int hi, std::string doc) {
  Entry& e = add(std::move(key), std::move(doc));
  e.read = [&field, lo, hi](const YamlFields& y, const YAML::Node& node, const std::string& name) {
    const double v = y.number(node, name, lo, hi);
    if (v != std::floor(v)) y.fail(node, name + ": expected a whole number, got " + node.Scalar());
    field = static_cast<int>(v);
  };
  e.value = [&field] { return std::to_string(field); };
}

void ParameterTable::count(std::string key, size_t& field, size_t lo, size_t hi, std::string doc) {
  Entry& e = add(std::move(key), std::move(doc));
  e.read = [&field, lo, hi](const YamlFields& y, const YAML::Node& node, const std::string& name) {
    const double v = y.number(node, name, static_cast<double>(lo), static_cast<double>(hi));
    if (v != std::floor(v)) y.fail(node, name + ": expected a whole number, got " + node.Scalar());
    field = static_cast<size_t>(v);
  };
  e.value = [&field] { return std::to_string(field); };
}

void ParameterTable::boolean(std::string key, bool& field, std::string doc) {
  Entry& e = add(std::move(key), std::move(doc));
  e.read = [&field](const YamlFields& y, const YAML::Node& node, const std::string& name) {
    bool value = false;
    bool ok = node.IsScalar();
    if (ok) {
      try {
        value = node.as<bool>();
      } catch (const YAML::Exception&) {
        ok = false;
      }
    }
    if (!ok) y.fail(node, name + ": expected true or false");
    field = value;
  };
  e.value = [&field] { return field ? "true" : "false"; };
}

void ParameterTable::choice(std::string key, std::vector<std::string> options,
                            std::function<bool(const std::string&)> set, std::function<std::string()> get,
                            std::string doc) {
  Entry& e = add(std::move(key), doc + " (" + joined(options, " | ") + ")");
  e.read = [options, set](const YamlFields& y, const YAML::Node& node, const std::string& name) {
    const std::string word = node.IsScalar() ? node.Scalar() : "";
    if (std::find(options.begin(), options.end(), word) == options.end() || !set(word))
      y.fail(node, name + ": expected one of " + joined(options, ", ") + ", got '" + word + "'");
  };
  e.value = std::move(get);
}

ParameterTable& ParameterTable::section(std::string key, std::string doc) {
  Entry& e = add(std::move(key), std::move(doc));
  e.section = std::make_unique<ParameterTable>();
  ParameterTable* table = e.section.get();
  e.read = [table](const YamlFields& y, const YAML::Node& node, const std::string& name) { table->read(y, node, name); };
  return *table;
}

void ParameterTable::read(const YamlFields& yaml, const YAML::Node& map, const std::string& context) const {
  if (!map || map.IsNull()) return;
  std::vector<std::string> allowed;
  for (const Entry& e : entries_) allowed.push_back(e.key);
  yaml.requireMap(map, context, allowed);
  for (const Entry& e : entries_)
    if (const YAML::Node node = map[e.key]) e.read(yaml, node, context + "." + e.key);
}

std::vector<std::string> ParameterTable::keys() const {
  std::vector<std::string> out;
  for (const Entry& e : entries_) {
    if (!e.section) {
      out.push_back(e.key);
      continue;
    }
    for (const std::string& k : e.section->keys()) out.push_back(e.key + "." + k);
  }
  return out;
}

std::vector<std::string> ParameterTable::missingFrom(const YAML::Node& map) const {
  std::vector<std::string> out;
  for (const Entry& e : entries_) {
    const YAML::Node node = map && map.IsMap() ? map[e.key] : YAML::Node();
    if (!e.section) {
      if (!node) out.push_back(e.key);
      continue;
    }
    for (const std::string& k : e.section->missingFrom(node)) out.push_back(e.key + "." + k);
  }
  return out;
}

std::string ParameterTable::yaml(int indent) const {
  const std::string pad(static_cast<size_t>(indent), ' ');
  std::string out;
  for (const Entry& e : entries_) {
    if (e.section) {
      out += pad + e.key + ":" + (e.doc.empty() ? "" : "  # " + e.doc) + "\n" + e.section->yaml(indent + 2);
      continue;
    }
    std::string line = pad + e.key + ": " + e.value();
    if (!e.doc.empty()) line += std::string(line.size() < 44 ? 44 - line.size() : 1, ' ') + "# " + e.doc;
    out += line + "\n";
  }
  return out;
}

}  // namespace polarslam
