#pragma once
// The launcher's status table, as text lines for the terminal.
#include <string>
#include <vector>

#include "launch/process_table.hpp"

namespace polarslam {

/// A header line and one line per command: name, state, pid, restarts, CPU %, RSS, uptime and
/// the last exit or error. Lines are cut to `width` characters (0: no limit).
std::vector<std::string> formatStatusTable(const ProcessTable& table, LaunchClock::time_point now, size_t width = 0);

/// `text` without terminal control: ESC sequences (colours, cursor moves) and control characters
/// removed, tabs turned into spaces, so a line cannot disturb the live table.
std::string printable(const std::string& text);

/// "12:34" or "1:02:03" for a duration in seconds.
std::string formatUptime(double seconds);

}  // namespace polarslam
