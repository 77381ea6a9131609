// Group files: nesting, inherited defaults, variables, start order, host selection, and errors
// that name the file and line.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>

#include "launch/group_file.hpp"

namespace polarslam {
namespace {

class GroupFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("polarslam-groups-" + std::to_string(getpid()) + "-" +
                                ::testing::UnitTest::GetInstance()->current_test_info()->name());
  void SetUp() override { std::filesystem::create_directories(dir_); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const auto path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }
  /// The message of the error loading `text` throws ("" if it loads).
  std::string loadError(const std::string& text) {
    const std::string path = write("bad.yaml", text);
    try {
      loadGroupFile(path, {});
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  std::string badPath() const { return (dir_ / "bad.yaml").string(); }
};

const char* kNested = R"(name: robot-stack
host: robot
environment: {WORLD: "${GROUP_DIR}/worlds/a.yaml", LEVEL: "${HOME_DIR}/x"}
stop_signal: SIGINT
stop_grace: 2
groups:
  - name: estimators
    host: base
    auto_respawn: false
    respawn_backoff: {initial: 0.5, max: 4}
    commands:
      - name: ekf
        exec: polarslam-ekf-slam
        args: [--world, "${WORLD}", --rate, 10]
        environment: {LEVEL: debug}
      - name: shell-one
        command: "echo ${WORLD} && sleep 1"
        stop_signal: KILL
        start_order: -1
        required: true
commands:
  - name: sim
    exec: ./bin/polarslam-sim
    working_dir: /tmp
    start_delay: 1.5
)";

TEST_F(GroupFileTest, NestedGroupsInheritDefaultsAndExpandVariables) {
  const GroupSpec root = loadGroupFile(write("stack.yaml", kNested), {{"HOME_DIR", "/home/r"}});
  const std::string group_dir = std::filesystem::absolute(dir_).lexically_normal().string();
  EXPECT_EQ(root.name, "robot-stack");
  ASSERT_EQ(root.commands.size(), 1u);
  ASSERT_EQ(root.groups.size(), 1u);
  EXPECT_EQ(root.groups[0].path, "robot-stack/estimators");

  const CommandSpec& sim = root.commands[0];
  EXPECT_EQ(sim.argv, std::vector<std::string>{"./bin/polarslam-sim"});
  EXPECT_EQ(sim.host, "robot");
  EXPECT_EQ(sim.working_dir, "/tmp");
  EXPECT_EQ(sim.stop_signal, SIGINT);
  EXPECT_DOUBLE_EQ(sim.stop_grace_s, 2.0);
  EXPECT_DOUBLE_EQ(sim.start_delay_s, 1.5);
  EXPECT_TRUE(sim.auto_respawn);
  EXPECT_FALSE(sim.required);
  EXPECT_EQ(sim.environment.at("LEVEL"), "/home/r/x");
  EXPECT_EQ(sim.environment.at("GROUP_DIR"), group_dir);
  EXPECT_EQ(sim.where, (dir_ / "stack.yaml").string() + ":22");

  const CommandSpec& ekf = root.groups[0].commands[0];
  EXPECT_EQ(ekf.host, "base");
  EXPECT_FALSE(ekf.auto_respawn);
  EXPECT_EQ(ekf.stop_signal, SIGINT);
  EXPECT_EQ(ekf.group_path, "robot-stack/estimators");
  EXPECT_EQ(ekf.argv, (std::vector<std::string>{"polarslam-ekf-slam", "--world", group_dir + "/worlds/a.yaml",
                                                "--rate", "10"}));
  EXPECT_EQ(ekf.environment.at("LEVEL"), "debug");
  EXPECT_DOUBLE_EQ(ekf.backoff.initial_s, 0.5);
  EXPECT_DOUBLE_EQ(ekf.backoff.max_s, 4.0);
  EXPECT_DOUBLE_EQ(ekf.backoff.factor, 2.0);

  const CommandSpec& shell = root.groups[0].commands[1];
  // Shell lines are left to the shell, which sees the same variables in its environment.
  EXPECT_EQ(shell.argv, (std::vector<std::string>{"/bin/sh", "-c", "echo ${WORLD} && sleep 1"}));
  EXPECT_EQ(shell.stop_signal, SIGKILL);
  EXPECT_TRUE(shell.required);
}

TEST_F(GroupFileTest, FileStemNamesAnUnnamedTopGroup) {
  const GroupSpec root = loadGroupFile(write("solo.yaml", "commands:\n  - {name: a, exec: sleep, args: [1]}\n"), {});
  EXPECT_EQ(root.name, "solo");
  EXPECT_EQ(root.commands[0].argv, (std::vector<std::string>{"sleep", "1"}));
}

TEST_F(GroupFileTest, SelectsByGroupAndHostInStartOrder) {
  const GroupSpec root = loadGroupFile(write("stack.yaml", kNested), {{"HOME_DIR", "/h"}});
  auto names = [](const std::vector<CommandSpec>& cmds) {
    std::vector<std::string> n;
    for (const auto& c : cmds) n.push_back(c.name);
    return n;
  };
  // Depth first (a group's commands, then its subgroups), then stable by start_order.
  EXPECT_EQ(names(selectCommands(root, "", "")), (std::vector<std::string>{"shell-one", "sim", "ekf"}));
  EXPECT_EQ(names(selectCommands(root, "", "robot")), std::vector<std::string>{"sim"});
  EXPECT_EQ(names(selectCommands(root, "estimators", "")), (std::vector<std::string>{"shell-one", "ekf"}));
  EXPECT_EQ(names(selectCommands(root, "robot-stack/estimators", "base")),
            (std::vector<std::string>{"shell-one", "ekf"}));
  try {
    selectCommands(root, "estimators", "robot");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "group 'robot-stack/estimators' has no commands for host 'robot' (hosts in it: base)");
  }
  try {
    selectCommands(root, "mapping", "");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "no group named 'mapping' (groups: robot-stack, estimators)");
  }
}

TEST_F(GroupFileTest, ErrorsNameFileAndLine) {
  const std::string f = badPath();
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: [unclosed\n"),
            f + ":4: YAML syntax error: end of sequence flow not found");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    respawn: yes\n"),
            f + ":4: unknown key 'respawn' in command in bad (allowed: name, exec, command, args, environment, "
                "working_dir, host, auto_respawn, stop_signal, stop_grace, respawn_backoff, start_order, start_delay, "
                "wait_for, wait_timeout, required)");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    wait_for: [b]\n"),
            f + ":2: wait_for names 'b', which is not a command of this file");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    wait_for: [a]\n"),
            f + ":2: 'a' waits for itself (wait_for)");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    wait_for: b\n"),
            f + ":4: bad/a.wait_for: expected a list");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    command: sleep 1\n"),
            f + ":4: bad/a: give either 'exec' (a program) or 'command' (a shell line), not both");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    args: [1]\n"),
            f + ":2: bad/a: missing key 'exec' (a program) or 'command' (a shell line)");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    stop_signal: SIGFOO\n"),
            f + ":4: bad/a.stop_signal: expected a signal such as SIGINT, SIGTERM or SIGKILL");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    stop_grace: -1\n"),
            f + ":4: bad/a.stop_grace: -1 is outside the allowed range [0, 600]");
  EXPECT_EQ(loadError("commands:\n  - name: a\n    exec: sleep\n    args: [\"${NOPE}\"]\n"),
            f + ":4: bad/a.args[0]: unknown variable ${NOPE} (known: GROUP_DIR, the launcher's environment and "
                "'environment' entries)");
  EXPECT_EQ(loadError("commands:\n  - {name: a, exec: sleep}\ngroups:\n  - name: g\n    commands:\n"
                      "      - {name: a, exec: true}\n"),
            f + ":6: command name 'a' already used at " + f + ":2");
  EXPECT_EQ(loadError("commands:\n  - name: 'two words'\n    exec: sleep\n"),
            f + ":2: command in bad: name must be letters, digits, '_', '-' or '.'");
  EXPECT_EQ(loadError("groups:\n  - name: empty\n"), f + ":2: group 'bad/empty' has neither commands nor groups");
  EXPECT_EQ(loadError("- just a list\n"), f + ":1: expected a map of keys at the top level");
  EXPECT_EQ(loadError(""), f + ":1: expected a map of keys at the top level");
}

TEST_F(GroupFileTest, MissingFileIsNamed) {
  try {
    loadGroupFile((dir_ / "none.yaml").string(), {});
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), (dir_ / "none.yaml").string() + ": cannot open (no such file)");
  }
}

TEST(GroupFile, ShippedGroupFilesLoad) {
  const std::string groups = std::string(POLARSLAM_SOURCE_DIR) + "/config/groups/";
  const GroupSpec sim = loadGroupFile(groups + "sim-only.yaml", {});
  ASSERT_EQ(selectCommands(sim, "", "").size(), 1u);
  EXPECT_EQ(selectCommands(sim, "", "")[0].argv[0], "polarslam-sim");

  const GroupSpec pipeline = loadGroupFile(groups + "pipeline.yaml", {});
  const auto commands = selectCommands(pipeline, "", "");
  ASSERT_EQ(commands.size(), 9u);
  for (const std::string program : {"polarslam-sim", "polarslam-features", "polarslam-fusion", "polarslam-ekf-slam",
                                    "polarslam-psm", "polarslam-psm-slam", "polarslam-grid", "polarslam-bridge"}) {
    // The program is argv[0], or the word after 'exec ' in a shell line.
    const auto runs = [&](const CommandSpec& c) {
      return c.argv[0] == program || (c.argv[0] == "/bin/sh" && c.argv[2].rfind("exec " + program + " ", 0) == 0);
    };
    // Two grids: one from the EKF's anchors, one from PSM SLAM's graph.
    EXPECT_EQ(std::count_if(commands.begin(), commands.end(), runs), program == "polarslam-grid" ? 2 : 1) << program;
  }
  // The simulator starts last so that no consumer misses its first messages.
  EXPECT_EQ(selectCommands(pipeline, "", "").back().argv[0], "polarslam-sim");
  EXPECT_EQ(selectCommands(pipeline, "", "robot").size() + selectCommands(pipeline, "", "base").size(), 9u);
}

// Consumers start before the stages feeding them, so that none misses the first messages; the
// launcher stops in the reverse order, so that each still hears its feeders' last messages.
TEST(GroupFile, ShippedGroupsStartConsumersFirstSoTheyStopLast) {
  const std::string groups = std::string(POLARSLAM_SOURCE_DIR) + "/config/groups/";
  const auto namesInStartOrder = [&](const std::string& file) {
    std::vector<std::string> names;
    for (const auto& c : selectCommands(loadGroupFile(groups + file, {}), "", "")) names.push_back(c.name);
    return names;
  };
  EXPECT_EQ(namesInStartOrder("pipeline.yaml"),
            (std::vector<std::string>{"bridge", "grid", "grid-psm", "ekf-slam", "psm", "psm-slam", "fusion", "features", "sim"}));
  EXPECT_EQ(namesInStartOrder("replay.yaml"),
            (std::vector<std::string>{"recorder", "bridge", "grid", "grid-psm", "ekf-slam", "psm-slam", "fusion", "features",
                                      "player"}));
  // The producer also waits until every other stage has subscribed (the recorder reports nothing).
  for (const std::string file : {"pipeline.yaml", "replay.yaml"}) {
    auto commands = selectCommands(loadGroupFile(groups + file, {}), "", "");
    std::vector<std::string> consumers;
    for (const auto& c : commands)
      if (c.name != commands.back().name && c.name != "recorder") consumers.push_back(c.name);
    EXPECT_EQ(commands.back().wait_for, consumers) << file;
  }
}

TEST(GroupFile, ExpandsVariables) {
  const Environment vars{{"A", "1"}, {"LONG_NAME", "two"}};
  EXPECT_EQ(expandVariables("x${A}y${LONG_NAME}z$A", vars, "w"), "x1ytwoz$A");
  EXPECT_EQ(expandVariables("", vars, "w"), "");
  EXPECT_THROW(expandVariables("${A", vars, "w"), std::runtime_error);
}

TEST(GroupFile, ParsesSignals) {
  EXPECT_EQ(parseSignal("SIGINT"), SIGINT);
  EXPECT_EQ(parseSignal("term"), SIGTERM);
  EXPECT_EQ(parseSignal("Kill"), SIGKILL);
  EXPECT_EQ(parseSignal("2"), 2);
  EXPECT_EQ(parseSignal("0"), -1);
  EXPECT_EQ(parseSignal("99"), -1);
  EXPECT_EQ(parseSignal("SIGFOO"), -1);
  EXPECT_EQ(signalName(SIGKILL), "SIGKILL");
  EXPECT_EQ(signalName(SIGSEGV), "signal " + std::to_string(SIGSEGV));
}

TEST(GroupFile, BackoffDoublesUpToItsLimit) {
  const RestartBackoff b{0.2, 2.0, 1.0, 10.0};
  EXPECT_DOUBLE_EQ(b.delay(1), 0.2);
  EXPECT_DOUBLE_EQ(b.delay(2), 0.4);
  EXPECT_DOUBLE_EQ(b.delay(3), 0.8);
  EXPECT_DOUBLE_EQ(b.delay(4), 1.0);
  EXPECT_DOUBLE_EQ(b.delay(40), 1.0);
}

}  // namespace
}  // namespace polarslam
