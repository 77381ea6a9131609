// The launcher's bookkeeping: start schedule, restart back-off, shutdown.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include "launch/process_table.hpp"
#include "launch/status_view.hpp"

namespace polarslam {
namespace {

using namespace std::chrono_literals;

CommandSpec command(const std::string& name, double start_delay = 0.0, bool respawn = true) {
  CommandSpec c;
  c.name = name;
  c.argv = {"sleep", "100"};
  c.start_delay_s = start_delay;
  c.auto_respawn = respawn;
  c.backoff = RestartBackoff{0.25, 2.0, 1.0, 10.0};
  return c;
}

const LaunchClock::time_point t0{};
const ExitStatus kKilled{true, SIGKILL};
const ExitStatus kFailure{false, 3};
const ExitStatus kSuccess{false, 0};

TEST(ProcessTable, StartsEachCommandItsDelayAfterThePrevious) {
  ProcessTable table({command("a"), command("b", 1.0), command("c", 0.5)}, t0);
  EXPECT_EQ(table.dueToStart(t0), std::vector<size_t>{0});
  EXPECT_EQ(table.dueToStart(t0 + 1s), (std::vector<size_t>{0, 1}));
  EXPECT_EQ(table.dueToStart(t0 + 1499ms), (std::vector<size_t>{0, 1}));
  EXPECT_EQ(table.dueToStart(t0 + 1500ms), (std::vector<size_t>{0, 1, 2}));
  table.started(0, 100, t0);
  EXPECT_EQ(*table.nextStart(t0), t0 + 1s);
  EXPECT_EQ(table[0].state, RunState::Running);
  EXPECT_EQ(*table.indexOfPid(100), 0u);
  EXPECT_FALSE(table.indexOfPid(101).has_value());
}

TEST(ProcessTable, CrashRestartsWithDoublingBackoff) {
  ProcessTable table({command("a")}, t0);
  table.started(0, 100, t0);
  EXPECT_EQ(table.exited(0, kKilled, t0 + 1s), RunState::Restarting);
  EXPECT_EQ(table[0].pid, -1);
  EXPECT_EQ(table[0].last_exit, "killed by SIGKILL");
  EXPECT_EQ(*table.nextStart(t0), t0 + 1250ms);
  EXPECT_TRUE(table.dueToStart(t0 + 1249ms).empty());
  table.started(0, 101, t0 + 1250ms);
  EXPECT_EQ(table[0].restarts, 1);
  EXPECT_EQ(table.exited(0, kFailure, t0 + 2s), RunState::Restarting);
  EXPECT_EQ(*table.nextStart(t0), t0 + 2500ms);
  table.started(0, 102, t0 + 2500ms);
  table.exited(0, kFailure, t0 + 3s);
  EXPECT_EQ(*table.nextStart(t0), t0 + 4s);  // 1 s cap
  table.started(0, 103, t0 + 4s);
  EXPECT_EQ(table[0].restarts, 3);
}

TEST(ProcessTable, LongRunBeforeACrashResetsTheBackoff) {
  ProcessTable table({command("a")}, t0);
  table.started(0, 100, t0);
  table.exited(0, kKilled, t0 + 1s);
  table.started(0, 101, t0 + 2s);
  table.exited(0, kKilled, t0 + 3s);
  EXPECT_EQ(*table.nextStart(t0), t0 + 3500ms);
  table.started(0, 102, t0 + 4s);
  table.exited(0, kKilled, t0 + 14s);  // ran 10 s: counts as a first crash again
  EXPECT_EQ(*table.nextStart(t0), t0 + 14250ms);
}

TEST(ProcessTable, CleanExitOrNoRespawnEndsTheProcess) {
  ProcessTable table({command("done"), command("fragile", 0.0, false)}, t0);
  table.started(0, 100, t0);
  table.started(1, 101, t0);
  EXPECT_EQ(table.exited(0, kSuccess, t0 + 1s), RunState::Stopped);
  EXPECT_TRUE(table.anyActive());
  EXPECT_EQ(table.exited(1, kFailure, t0 + 1s), RunState::Crashed);
  EXPECT_EQ(table[1].last_exit, "exit 3");
  EXPECT_FALSE(table.anyActive());
  EXPECT_TRUE(table.anyFailed());
  EXPECT_FALSE(table.nextStart(t0).has_value());
}

TEST(ProcessTable, ExitAfterAStopRequestIsAStopEvenWhenKilled) {
  CommandSpec slow = command("b");
  slow.stop_grace_s = 2.5;
  ProcessTable table({command("a"), slow}, t0);
  table.started(0, 100, t0);
  table.started(1, 101, t0);
  table.cancelPendingStarts();
  table.stopping(1, t0 + 1s);
  EXPECT_EQ(table[1].kill_deadline, t0 + 3500ms);
  EXPECT_EQ(table.exited(1, kKilled, t0 + 3500ms), RunState::Stopped);
  // A crash during shutdown is not restarted.
  EXPECT_EQ(table.exited(0, kKilled, t0 + 2s), RunState::Crashed);
  EXPECT_FALSE(table.anyActive());
}

TEST(ProcessTable, ShutdownCancelsPendingStarts) {
  ProcessTable table({command("a"), command("b", 5.0)}, t0);
  table.started(0, 100, t0);
  table.exited(0, kKilled, t0 + 1s);
  table.cancelPendingStarts();
  EXPECT_EQ(table[0].state, RunState::Crashed);
  EXPECT_EQ(table[1].state, RunState::Stopped);
  EXPECT_FALSE(table.anyActive());
  EXPECT_TRUE(table.dueToStart(t0 + 10s).empty());
}

TEST(ProcessTable, AFirstStartWaitsUntilItsConsumersReportRunningOrItsTimeoutPasses) {
  CommandSpec player = command("player", 1.0, false);
  player.wait_for = {"a", "b"};
  player.wait_timeout_s = 10.0;
  ProcessTable table({command("a"), command("b"), player}, t0);
  table.started(0, 100, t0);
  table.started(1, 101, t0);
  EXPECT_EQ(table.awaited(2), (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(table.dueToStart(t0 + 2s).empty());
  EXPECT_EQ(*table.nextStart(t0), t0 + 1s);         // its delay first,
  EXPECT_EQ(*table.nextStart(t0 + 2s), t0 + 11s);   // then its timeout
  table.reportedRunning(0);
  EXPECT_EQ(table.awaited(2), std::vector<std::string>{"b"});
  EXPECT_TRUE(table.dueToStart(t0 + 2s).empty());
  table.reportedRunning(1);
  EXPECT_TRUE(table.awaited(2).empty());
  EXPECT_EQ(table.dueToStart(t0 + 2s), std::vector<size_t>{2});
  EXPECT_TRUE(table.dueToStart(t0 + 500ms).empty());  // never before its delay

  // A restarted consumer must report again; one that crashed for good is not waited for.
  table.exited(1, kKilled, t0 + 3s);
  EXPECT_EQ(table[1].state, RunState::Restarting);
  EXPECT_EQ(table.awaited(2), std::vector<std::string>{"b"});
  table.startFailed(1, "gone");
  EXPECT_TRUE(table.awaited(2).empty());
}

TEST(ProcessTable, AConsumerThatNeverReportsHoldsTheStartOnlyUntilTheTimeout) {
  CommandSpec player = command("player", 0.0, false);
  player.wait_for = {"a"};
  player.wait_timeout_s = 5.0;
  ProcessTable table({command("a"), player}, t0);
  table.started(0, 100, t0);
  EXPECT_EQ(table.dueToStart(t0 + 4999ms), std::vector<size_t>{});
  EXPECT_EQ(table.dueToStart(t0 + 5s), std::vector<size_t>{1});
  EXPECT_EQ(table.awaited(1), std::vector<std::string>{"a"});  // the launcher names it when it starts anyway
}

TEST(ProcessTable, StopsTheHighestStartOrderFirstAndEqualOnesTogether) {
  const auto ordered = [](const std::string& name, int start_order) {
    CommandSpec c = command(name);
    c.start_order = start_order;
    return c;
  };
  // As group files give them: sorted by start_order, ties in file order.
  ProcessTable table({ordered("recorder", -10), ordered("ekf", 0), ordered("psm", 0), ordered("features", 2),
                      ordered("player", 10)},
                     t0);
  for (size_t i = 0; i < 4; ++i) table.started(i, static_cast<int>(100 + i), t0);
  table.cancelPendingStarts();  // the player never started: nothing of start_order 10 runs
  EXPECT_EQ(table.running(), (std::vector<size_t>{0, 1, 2, 3}));
  EXPECT_EQ(table.nextToStop(), std::vector<size_t>{3});
  table.stopping(3, t0);
  EXPECT_EQ(table.nextToStop(), (std::vector<size_t>{1, 2}));
  table.stopping(1, t0);
  EXPECT_EQ(table.nextToStop(), std::vector<size_t>{2});  // its partner is already stopping
  table.stopping(2, t0);
  EXPECT_EQ(table.nextToStop(), std::vector<size_t>{0});
  table.stopping(0, t0);
  EXPECT_TRUE(table.nextToStop().empty());
  EXPECT_TRUE(table.running().empty());
}

TEST(ProcessTable, FailedStartIsKeptWithItsReason) {
  ProcessTable table({command("ghost"), command("b")}, t0);
  table.startFailed(0, "executable 'ghost' not found");
  table.started(1, 100, t0);
  EXPECT_EQ(table[0].state, RunState::Failed);
  EXPECT_TRUE(table.dueToStart(t0 + 100s).empty());
  EXPECT_TRUE(table.anyActive());
  EXPECT_TRUE(table.anyFailed());
}

TEST(ProcessTable, ExitStatusFromWaitStatus) {
  const ExitStatus exited = ExitStatus::fromWaitStatus(7 << 8);  // W_EXITCODE(7, 0)
  EXPECT_FALSE(exited.signaled);
  EXPECT_EQ(exited.code, 7);
  EXPECT_EQ(exited.describe(), "exit 7");
  const ExitStatus killed = ExitStatus::fromWaitStatus(SIGTERM);
  EXPECT_TRUE(killed.signaled);
  EXPECT_EQ(killed.describe(), "killed by SIGTERM");
  EXPECT_TRUE(ExitStatus::fromWaitStatus(0).clean());
}

TEST(StatusView, TableShowsEveryCommand) {
  ProcessTable table({command("sim"), command("ekf-slam"), command("ghost")}, t0);
  table.started(0, 4242, t0);
  table.setUsage(0, 12.34, 56.78);
  table.started(1, 4243, t0);
  table.exited(1, kKilled, t0 + 2s);
  table.startFailed(2, "executable 'ghost' not found");
  const auto lines = formatStatusTable(table, t0 + 83s);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "NAME      STATE          PID RESTARTS   CPU%   RSS_MB   UPTIME  NOTE");
  EXPECT_EQ(lines[1], "sim       running       4242        0   12.3     56.8     1:23  ");
  EXPECT_EQ(lines[2], "ekf-slam  restarting       -        0    0.0      0.0        -  last: killed by SIGKILL");
  EXPECT_EQ(lines[3], "ghost     failed           -        0    0.0      0.0        -  executable 'ghost' not found");
  EXPECT_EQ(formatStatusTable(table, t0, 10)[3], "ghost     ");
  EXPECT_EQ(formatUptime(3723.9), "1:02:03");
}

TEST(StatusView, PrintableDropsTerminalControl) {
  EXPECT_EQ(printable("\x1b[1;31mred\x1b[0m\tplain\r\x07"), "red plain");
  EXPECT_EQ(printable("\x1b[2K\x1b[1Gline\x1b"), "line");
  EXPECT_EQ(printable("caf\xc3\xa9 100%"), "caf\xc3\xa9 100%");
}

}  // namespace
}  // namespace polarslam
