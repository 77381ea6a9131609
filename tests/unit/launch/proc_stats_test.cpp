// /proc parsing: process groups, CPU ticks and resident pages.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>

#include "launch/proc_stats.hpp"

namespace polarslam {
namespace {

TEST(ProcStats, ParsesAStatLineWhoseNameHoldsSpacesAndParentheses) {
  const std::string line =
      "4242 (my (odd) name) S 17 4240 4240 0 -1 4194560 120 0 3 0 250 75 9 4 20 0 1 0 5000 12345678 321 "
      "18446744073709551615 1 1 0 0 0 0 0 0 0 0 0 0 17 1 0 0 0 0 0";
  const auto s = parseProcStat(line);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->pid, 4242);
  EXPECT_EQ(s->comm, "my (odd) name");
  EXPECT_EQ(s->state, 'S');
  EXPECT_EQ(s->ppid, 17);
  EXPECT_EQ(s->pgrp, 4240);
  EXPECT_EQ(s->cpu_ticks, 325u);  // utime 250 + stime 75; children's 9 + 4 not counted
  EXPECT_EQ(s->rss_pages, 321);
  EXPECT_FALSE(parseProcStat("").has_value());
  EXPECT_FALSE(parseProcStat("12 (cut").has_value());
  EXPECT_FALSE(parseProcStat("12 (short) S 1 2").has_value());
}

TEST(ProcStats, ListsThisProcessAndAChildInItsOwnGroup) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    setpgid(0, 0);
    pause();
    _exit(0);
  }
  setpgid(child, child);  // both sides set it: no race with the listing below
  const auto all = listProcesses();
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);

  auto find = [&](int pid) { return std::find_if(all.begin(), all.end(), [&](const ProcStat& p) { return p.pid == pid; }); };
  const auto self = find(getpid());
  ASSERT_NE(self, all.end());
  EXPECT_EQ(self->pgrp, getpgrp());
  EXPECT_EQ(self->ppid, getppid());
  EXPECT_GT(self->rss_pages, 0);
  const auto kid = find(child);
  ASSERT_NE(kid, all.end());
  EXPECT_EQ(kid->ppid, getpid());
  EXPECT_EQ(kid->pgrp, child);

  const auto groups = usageByProcessGroup(all);
  EXPECT_EQ(groups.at(child).members, 1);
  EXPECT_EQ(groups.at(child).rss_pages, kid->rss_pages);
}

TEST(ProcStats, SumsUsageOverAGroup) {
  const std::vector<ProcStat> procs = {
      {1, "a", 'S', 0, 10, 100, 5}, {2, "b", 'S', 1, 10, 50, 7}, {3, "c", 'R', 1, 20, 1, 1}};
  const auto groups = usageByProcessGroup(procs);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups.at(10).cpu_ticks, 150u);
  EXPECT_EQ(groups.at(10).rss_pages, 12);
  EXPECT_EQ(groups.at(10).members, 2);
  EXPECT_EQ(groups.at(20).members, 1);
}

TEST(ProcStats, CpuPercentIsTicksOverElapsedTime) {
  EXPECT_DOUBLE_EQ(cpuPercent(100, 150, 1.0, 100), 50.0);
  EXPECT_DOUBLE_EQ(cpuPercent(0, 300, 1.5, 100), 200.0);  // two cores busy
  EXPECT_DOUBLE_EQ(cpuPercent(150, 100, 1.0, 100), 0.0);  // a member left with its ticks
  EXPECT_DOUBLE_EQ(cpuPercent(0, 100, 0.0, 100), 0.0);
}

}  // namespace
}  // namespace polarslam
