#pragma once
// Linux /proc figures for supervised processes: who belongs to which process group, CPU time
// and resident memory.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace polarslam {

/// The fields of /proc/PID/stat the launcher uses.
struct ProcStat {
  int pid = 0;
  std::string comm;
  char state = '?';
  int ppid = 0;
  int pgrp = 0;
  uint64_t cpu_ticks = 0;  // utime + stime, in clock ticks
  int64_t rss_pages = 0;
};

/// Parses one /proc/PID/stat line; nullopt if it is not one. `comm` may hold spaces and ')'.
std::optional<ProcStat> parseProcStat(const std::string& line);

/// Every process currently listed under `proc_root` (processes that vanish meanwhile are skipped).
std::vector<ProcStat> listProcesses(const std::string& proc_root = "/proc");

/// CPU time and memory summed over the members of each process group.
struct GroupUsage {
  uint64_t cpu_ticks = 0;
  int64_t rss_pages = 0;
  int members = 0;
};
std::map<int, GroupUsage> usageByProcessGroup(const std::vector<ProcStat>& processes);

/// CPU % from two cumulative tick counts `elapsed_s` apart (100 % = one core busy).
double cpuPercent(uint64_t ticks_before, uint64_t ticks_now, double elapsed_s, long ticks_per_second);

}  // namespace polarslam
