#include "launch/proc_stats.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace polarslam {

std::optional<ProcStat> parseProcStat(const std::string& line) {
  // "PID (COMM) S PPID PGRP ..." where COMM is free text: the last ')' ends it.
  const size_t open = line.find('('), close = line.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return std::nullopt;
  ProcStat s;
  try {
    s.pid = std::stoi(line.substr(0, open));
  } catch (const std::exception&) {
    return std::nullopt;
  }
  s.comm = line.substr(open + 1, close - open - 1);
  std::istringstream rest(line.substr(close + 1));
  // Fields 3.. of proc(5): state ppid pgrp session tty_nr tpgid flags minflt cminflt majflt
  // cmajflt utime stime cutime cstime priority nice num_threads itrealvalue starttime vsize rss
  uint64_t skip = 0, utime = 0, stime = 0;
  int64_t iskip = 0;
  rest >> s.state >> s.ppid >> s.pgrp;
  for (int i = 0; i < 8; ++i) rest >> iskip;  // session .. cmajflt
  rest >> utime >> stime;
  for (int i = 0; i < 7; ++i) rest >> iskip;  // cutime .. starttime
  rest >> skip >> s.rss_pages;                // vsize rss
  if (!rest) return std::nullopt;
  s.cpu_ticks = utime + stime;
  return s;
}

std::vector<ProcStat> listProcesses(const std::string& proc_root) {
  std::vector<ProcStat> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(proc_root, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || !std::isdigit(static_cast<unsigned char>(name[0]))) continue;
    std::ifstream in(entry.path() / "stat");
    std::string line;
    if (!std::getline(in, line)) continue;
    if (auto s = parseProcStat(line)) out.push_back(*s);
  }
  return out;
}

std::map<int, GroupUsage> usageByProcessGroup(const std::vector<ProcStat>& processes) {
  std::map<int, GroupUsage> groups;
  for (const auto& p : processes) {
    GroupUsage& g = groups[p.pgrp];
    g.cpu_ticks += p.cpu_ticks;
    g.rss_pages += p.rss_pages;
    ++g.members;
  }
  return groups;
}

double cpuPercent(uint64_t ticks_before, uint64_t ticks_now, double elapsed_s, long ticks_per_second) {
  // A member that exits takes its ticks with it: the group total can shrink. Count that as idle.
  if (ticks_now <= ticks_before || elapsed_s <= 0.0 || ticks_per_second <= 0) return 0.0;
  return 100.0 * static_cast<double>(ticks_now - ticks_before) / static_cast<double>(ticks_per_second) / elapsed_s;
}

}  // namespace polarslam
