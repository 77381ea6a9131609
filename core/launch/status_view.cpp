#include "launch/status_view.hpp"

#include <algorithm>
#include <cstdio>

namespace polarslam {
namespace {

std::string fitted(std::string line, size_t width) {
  if (width > 0 && line.size() > width) line.resize(width);
  return line;
}

std::string note(const ProcessRecord& r) {
  if (!r.error.empty()) return r.error;
  if (!r.last_exit.empty()) return "last: " + r.last_exit;
  return "";
}

}  // namespace

std::string printable(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '\x1b') {
      // CSI: ESC '[' parameters… final byte in '@'..'~'; other escapes are two bytes long.
      if (i + 1 < text.size() && text[i + 1] == '[') {
        i += 2;
        while (i < text.size() && (text[i] < '@' || text[i] > '~')) ++i;
      } else {
        ++i;
      }
    } else if (c == '\t') {
      out += ' ';
    } else if (c >= 0x20 && c != 0x7f) {
      out += static_cast<char>(c);
    }
  }
  return out;
}

std::string formatUptime(double seconds) {
  const long s = static_cast<long>(std::max(0.0, seconds));
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof(buf), "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(buf, sizeof(buf), "%ld:%02ld", s / 60, s % 60);
  return buf;
}

std::vector<std::string> formatStatusTable(const ProcessTable& table, LaunchClock::time_point now, size_t width) {
  size_t name_width = 4;
  for (const auto& r : table.records()) name_width = std::max(name_width, r.spec.name.size());
  const int nw = static_cast<int>(name_width);
  std::vector<std::string> lines;
  char buf[512];
  std::snprintf(buf, sizeof(buf), "%-*s  %-10s %7s %8s %6s %8s %8s  %s", nw, "NAME", "STATE", "PID", "RESTARTS",
                "CPU%", "RSS_MB", "UPTIME", "NOTE");
  lines.push_back(fitted(buf, width));
  for (const auto& r : table.records()) {
    const bool running = r.state == RunState::Running || r.state == RunState::Stopping;
    const std::string pid = running ? std::to_string(r.pid) : "-";
    const std::string uptime =
        running ? formatUptime(std::chrono::duration<double>(now - r.started_at).count()) : "-";
    std::snprintf(buf, sizeof(buf), "%-*s  %-10s %7s %8d %6.1f %8.1f %8s  ", nw, r.spec.name.c_str(),
                  stateName(r.state).c_str(), pid.c_str(), r.restarts, r.cpu_percent, r.rss_mb, uptime.c_str());
    lines.push_back(fitted(buf + note(r), width));
  }
  return lines;
}

}  // namespace polarslam
