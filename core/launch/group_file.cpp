#include "launch/group_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "config/yaml_fields.hpp"

namespace polarslam {
namespace {

struct NamedSignal {
  const char* name;
  int number;
};
constexpr NamedSignal kSignals[] = {{"HUP", SIGHUP},   {"INT", SIGINT},   {"QUIT", SIGQUIT},
                                    {"ABRT", SIGABRT}, {"KILL", SIGKILL}, {"USR1", SIGUSR1},
                                    {"USR2", SIGUSR2}, {"TERM", SIGTERM}};

/// What a group passes down to its commands and subgroups.
struct Defaults {
  std::string host;
  Environment environment;
  std::string working_dir;
  bool auto_respawn = true;
  int stop_signal = SIGTERM;
  double stop_grace_s = 3.0;
  RestartBackoff backoff;
};

bool isValidName(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '-' || c == '.';
  });
}

bool isValidVariableName(const std::string& name) {
  return !name.empty() && !std::isdigit(static_cast<unsigned char>(name[0])) &&
         std::all_of(name.begin(), name.end(), [](unsigned char c) { return std::isalnum(c) || c == '_'; });
}

class GroupFileParser {
 public:
  GroupFileParser(const std::string& path, const Environment& launcher_env)
      : f_(path), launcher_env_(launcher_env) {
    group_dir_ = std::filesystem::absolute(path).lexically_normal().parent_path().string();
  }

  GroupSpec parse() {
    const std::string stem = std::filesystem::path(f_.path()).stem().string();
    GroupSpec root = parseGroup(f_.root(), Defaults{}, "", stem);
    checkNames(root);
    return root;
  }

 private:
  GroupSpec parseGroup(const YAML::Node& node, Defaults defaults, const std::string& parent_path,
                       const std::string& fallback_name) {
    const std::string what = parent_path.empty() ? "top-level group" : "group in " + parent_path;
    f_.requireMap(node, what,
                  {"name", "host", "environment", "working_dir", "auto_respawn", "stop_signal", "stop_grace",
                   "respawn_backoff", "commands", "groups"});
    GroupSpec group;
    const bool named_by_file = !node["name"] && !fallback_name.empty();
    group.name = named_by_file ? fallback_name : name(node, what);
    group.path = parent_path.empty() ? group.name : parent_path + "/" + group.name;
    defaults = readDefaults(node, group.path, defaults);
    if (const YAML::Node list = node["commands"]) {
      f_.requireSequence(list, group.path + ".commands");
      for (const auto& item : list) group.commands.push_back(parseCommand(item, defaults, group.path));
    }
    if (const YAML::Node list = node["groups"]) {
      f_.requireSequence(list, group.path + ".groups");
      for (const auto& item : list) group.groups.push_back(parseGroup(item, defaults, group.path, ""));
    }
    if (group.commands.empty() && group.groups.empty())
      f_.fail(node, "group '" + group.path + "' has neither commands nor groups");
    return group;
  }

  std::string name(const YAML::Node& node, const std::string& what) const {
    const YAML::Node n = node["name"];
    if (!n) f_.fail(node, what + ": missing key 'name'");
    if (!n.IsScalar() || !isValidName(n.Scalar()))
      f_.fail(n, what + ": name must be letters, digits, '_', '-' or '.'");
    return n.Scalar();
  }

  Defaults readDefaults(const YAML::Node& node, const std::string& ctx, Defaults d) const {
    d.host = f_.text(node, "host", ctx, d.host);
    if (node["environment"]) d.environment = environment(node["environment"], ctx, d.environment);
    if (node["working_dir"]) d.working_dir = expandedText(node["working_dir"], ctx + ".working_dir", varsWith(d.environment));
    d.auto_respawn = f_.boolean(node, "auto_respawn", ctx, d.auto_respawn);
    if (node["stop_signal"]) d.stop_signal = signal(node["stop_signal"], ctx + ".stop_signal");
    d.stop_grace_s = f_.number(node, "stop_grace", ctx, d.stop_grace_s, 0.0, 600.0);
    if (node["respawn_backoff"]) d.backoff = backoff(node["respawn_backoff"], ctx + ".respawn_backoff", d.backoff);
    return d;
  }

  CommandSpec parseCommand(const YAML::Node& node, const Defaults& group_defaults, const std::string& group_path) {
    const std::string what = "command in " + group_path;
    f_.requireMap(node, what,
                  {"name", "exec", "command", "args", "environment", "working_dir", "host", "auto_respawn",
                   "stop_signal", "stop_grace", "respawn_backoff", "start_order", "start_delay", "wait_for", "wait_timeout", "required"});
    CommandSpec cmd;
    cmd.name = name(node, what);
    if (cmd.name == "launch" || cmd.name == "launcher")
      f_.fail(node["name"], what + ": the name '" + cmd.name + "' is kept for the launcher's own messages and log");
    cmd.group_path = group_path;
    cmd.where = f_.where(node);
    const std::string ctx = group_path + "/" + cmd.name;
    const Defaults d = readDefaults(node, ctx, group_defaults);
    cmd.host = d.host;
    cmd.environment = d.environment;
    cmd.environment["GROUP_DIR"] = group_dir_;
    cmd.working_dir = d.working_dir;
    cmd.auto_respawn = d.auto_respawn;
    cmd.stop_signal = d.stop_signal;
    cmd.stop_grace_s = d.stop_grace_s;
    cmd.backoff = d.backoff;
    cmd.start_order = f_.integer(node, "start_order", ctx, 0, -1000, 1000);
    cmd.start_delay_s = f_.number(node, "start_delay", ctx, 0.0, 0.0, 3600.0);
    cmd.wait_for = names(node["wait_for"], ctx + ".wait_for");
    cmd.wait_timeout_s = f_.number(node, "wait_timeout", ctx, cmd.wait_timeout_s, 0.0, 3600.0);
    cmd.required = f_.boolean(node, "required", ctx, false);
    cmd.argv = argv(node, ctx, varsWith(cmd.environment));
    return cmd;
  }

  std::vector<std::string> names(const YAML::Node& node, const std::string& ctx) const {
    if (!node) return {};
    f_.requireSequence(node, ctx);
    std::vector<std::string> out;
    for (const auto& item : node) {
      if (!item.IsScalar() || item.Scalar().empty()) f_.fail(item, ctx + ": expected command names");
      out.push_back(item.Scalar());
    }
    return out;
  }

  std::vector<std::string> argv(const YAML::Node& node, const std::string& ctx, const Environment& vars) const {
    const YAML::Node exec = node["exec"], shell = node["command"], args = node["args"];
    if (exec && shell) f_.fail(shell, ctx + ": give either 'exec' (a program) or 'command' (a shell line), not both");
    if (!exec && !shell) f_.fail(node, ctx + ": missing key 'exec' (a program) or 'command' (a shell line)");
    if (shell) {
      if (args) f_.fail(args, ctx + ": 'args' goes with 'exec'; put the arguments into the 'command' line");
      if (!shell.IsScalar() || shell.Scalar().empty()) f_.fail(shell, ctx + ".command: expected a shell command line");
      return {"/bin/sh", "-c", shell.Scalar()};  // the shell expands ${...} itself: every variable is exported
    }
    const std::string program = expandedText(exec, ctx + ".exec", vars);
    if (program.empty()) f_.fail(exec, ctx + ".exec: empty program name");
    std::vector<std::string> result{program};
    if (args) {
      f_.requireSequence(args, ctx + ".args");
      for (size_t i = 0; i < args.size(); ++i)
        result.push_back(expandedText(args[i], ctx + ".args[" + std::to_string(i) + "]", vars));
    }
    return result;
  }

  Environment environment(const YAML::Node& node, const std::string& ctx, Environment inherited) const {
    if (!node.IsMap()) f_.fail(node, ctx + ".environment: expected a map of NAME: value");
    const Environment vars = varsWith(inherited);
    for (const auto& kv : node) {
      const std::string key = kv.first.Scalar();
      if (!isValidVariableName(key)) f_.fail(kv.first, ctx + ".environment: '" + key + "' is not a variable name");
      inherited[key] = expandedText(kv.second, ctx + ".environment." + key, vars);
    }
    return inherited;
  }

  int signal(const YAML::Node& node, const std::string& ctx) const {
    const int sig = node.IsScalar() ? parseSignal(node.Scalar()) : -1;
    if (sig < 0) f_.fail(node, ctx + ": expected a signal such as SIGINT, SIGTERM or SIGKILL");
    return sig;
  }

  RestartBackoff backoff(const YAML::Node& node, const std::string& ctx, RestartBackoff b) const {
    f_.requireMap(node, ctx, {"initial", "factor", "max", "reset_after"});
    b.initial_s = f_.number(node, "initial", ctx, b.initial_s, 0.0, 3600.0);
    b.factor = f_.number(node, "factor", ctx, b.factor, 1.0, 100.0);
    b.max_s = f_.number(node, "max", ctx, b.max_s, b.initial_s, 86400.0);
    b.reset_after_s = f_.number(node, "reset_after", ctx, b.reset_after_s, 0.0, 86400.0);
    return b;
  }

  std::string expandedText(const YAML::Node& node, const std::string& ctx, const Environment& vars) const {
    if (!node.IsScalar()) f_.fail(node, ctx + ": expected a single value");
    return expandVariables(node.Scalar(), vars, f_.where(node) + ": " + ctx);
  }

  Environment varsWith(const Environment& extra) const {
    Environment vars = launcher_env_;
    vars["GROUP_DIR"] = group_dir_;
    for (const auto& [k, v] : extra) vars[k] = v;
    return vars;
  }

  void checkNames(const GroupSpec& root) const {
    std::map<std::string, std::string> commands;
    std::set<std::string> groups;
    checkUniqueNames(root, commands, groups);
    checkAwaitedNames(root, commands);
  }

  void checkUniqueNames(const GroupSpec& group, std::map<std::string, std::string>& commands,
                        std::set<std::string>& groups) const {
    if (!groups.insert(group.name).second)
      throw std::runtime_error(f_.path() + ": two groups are named '" + group.name + "'");
    for (const auto& cmd : group.commands) {
      auto [it, fresh] = commands.emplace(cmd.name, cmd.where);
      if (!fresh) throw std::runtime_error(cmd.where + ": command name '" + cmd.name + "' already used at " + it->second);
    }
    for (const auto& sub : group.groups) checkUniqueNames(sub, commands, groups);
  }

  void checkAwaitedNames(const GroupSpec& group, const std::map<std::string, std::string>& commands) const {
    for (const auto& cmd : group.commands)
      for (const auto& name : cmd.wait_for) {
        if (name == cmd.name) throw std::runtime_error(cmd.where + ": '" + cmd.name + "' waits for itself (wait_for)");
        if (!commands.count(name))
          throw std::runtime_error(cmd.where + ": wait_for names '" + name + "', which is not a command of this file");
      }
    for (const auto& sub : group.groups) checkAwaitedNames(sub, commands);
  }

  YamlFields f_;
  Environment launcher_env_;
  std::string group_dir_;
};

const GroupSpec* findGroup(const GroupSpec& group, const std::string& name) {
  if (group.name == name || group.path == name) return &group;
  for (const auto& sub : group.groups)
    if (const GroupSpec* found = findGroup(sub, name)) return found;
  return nullptr;
}

void collectCommands(const GroupSpec& group, std::vector<CommandSpec>& out) {
  out.insert(out.end(), group.commands.begin(), group.commands.end());
  for (const auto& sub : group.groups) collectCommands(sub, out);
}

void collectGroupNames(const GroupSpec& group, std::vector<std::string>& out) {
  out.push_back(group.name);
  for (const auto& sub : group.groups) collectGroupNames(sub, out);
}

}  // namespace

std::string joined(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

double RestartBackoff::delay(int consecutive_crashes) const {
  const double d = initial_s * std::pow(factor, std::max(0, consecutive_crashes - 1));
  return std::min(d, max_s);
}

GroupSpec loadGroupFile(const std::string& path, const Environment& launcher_env) {
  return GroupFileParser(path, launcher_env).parse();
}

std::vector<CommandSpec> selectCommands(const GroupSpec& root, const std::string& group, const std::string& host) {
  const GroupSpec* selected = group.empty() ? &root : findGroup(root, group);
  if (!selected) {
    std::vector<std::string> names;
    collectGroupNames(root, names);
    throw std::runtime_error("no group named '" + group + "' (groups: " + joined(names) + ")");
  }
  std::vector<CommandSpec> all, chosen;
  collectCommands(*selected, all);
  std::copy_if(all.begin(), all.end(), std::back_inserter(chosen),
               [&](const CommandSpec& c) { return host.empty() || c.host == host; });
  if (chosen.empty()) {
    std::set<std::string> hosts;
    for (const auto& c : all) hosts.insert(c.host.empty() ? "(none)" : c.host);
    throw std::runtime_error("group '" + selected->path + "' has no commands for host '" + host +
                             "' (hosts in it: " + joined({hosts.begin(), hosts.end()}) + ")");
  }
  std::stable_sort(chosen.begin(), chosen.end(),
                   [](const CommandSpec& a, const CommandSpec& b) { return a.start_order < b.start_order; });
  return chosen;
}

std::string expandVariables(const std::string& text, const Environment& vars, const std::string& where) {
  std::string out;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t open = text.find("${", pos);
    if (open == std::string::npos) break;
    const size_t close = text.find('}', open + 2);
    if (close == std::string::npos) throw std::runtime_error(where + ": '${' without a closing '}'");
    const std::string name = text.substr(open + 2, close - open - 2);
    const auto it = vars.find(name);
    if (it == vars.end())
      throw std::runtime_error(where + ": unknown variable ${" + name +
                               "} (known: GROUP_DIR, the launcher's environment and 'environment' entries)");
    out += text.substr(pos, open - pos) + it->second;
    pos = close + 1;
  }
  return out + text.substr(std::min(pos, text.size()));
}

int parseSignal(const std::string& text) {
  std::string upper;
  for (unsigned char c : text) upper += static_cast<char>(std::toupper(c));
  if (upper.rfind("SIG", 0) == 0) upper = upper.substr(3);
  for (const auto& s : kSignals)
    if (upper == s.name) return s.number;
  if (!upper.empty() && std::all_of(upper.begin(), upper.end(), [](unsigned char c) { return std::isdigit(c); }) &&
      upper.size() <= 2) {
    const int n = std::stoi(upper);
    if (n >= 1 && n <= 31) return n;
  }
  return -1;
}

std::string signalName(int signal) {
  for (const auto& s : kSignals)
    if (s.number == signal) return std::string("SIG") + s.name;
  return "signal " + std::to_string(signal);
}

}  // namespace polarslam
