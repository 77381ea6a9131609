#pragma once
// What the launcher shows in the terminal. On a TTY: a live status table above the latest output
// lines (full-screen, redrawn twice a second). Otherwise: every output line as "[name] text" and
// the status table every few seconds, as plain lines.
#include <chrono>
#include <cstdio>
#include <deque>
#include <string>

#include "launch/process_table.hpp"

namespace polarslam {

class Console {
 public:
  Console(bool live_table, std::string title, double status_period_s);
  Console(const Console&) = delete;
  Console& operator=(const Console&) = delete;
  ~Console();

  /// One output line of process `name` (or of the launcher itself, name "launch").
  void line(const std::string& name, const std::string& text);
  /// Redraws the live table, or prints the periodic status lines, when due (or when `force`).
  void refresh(const ProcessTable& table, LaunchClock::time_point now, bool force = false);
  /// The earliest time refresh() has something to do.
  LaunchClock::time_point nextRefresh() const { return next_refresh_; }
  /// Leaves the live screen and prints the final table.
  void finish(const ProcessTable& table, LaunchClock::time_point now);

 private:
  void redraw(const ProcessTable& table, LaunchClock::time_point now);

  bool live_;
  bool finished_ = false;
  std::string title_;
  LaunchClock::duration period_;
  LaunchClock::time_point next_refresh_;
  std::deque<std::string> recent_;  // live mode: the latest output lines
};

}  // namespace polarslam
