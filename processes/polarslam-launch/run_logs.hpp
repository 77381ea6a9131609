#pragma once
// The run folder: one log file per supervised command (NAME.log, across its restarts) and
// launcher.log for the launcher's own events; each line stamped with the wall-clock time.
#include <fstream>
#include <map>
#include <string>

namespace polarslam {

class RunLogs {
 public:
  /// Creates `dir` (and its parents); throws if it cannot.
  explicit RunLogs(std::string dir);
  const std::string& dir() const { return dir_; }
  void write(const std::string& name, const std::string& line);
  void flush();

 private:
  std::string dir_;
  std::map<std::string, std::ofstream> files_;
};

/// DIR/YYYYmmdd-HHMMSS-HOST-PID under $POLARSLAM_LAUNCH_LOGS, else $XDG_STATE_HOME/polarslam/launch,
/// else ~/.local/state/polarslam/launch.
std::string defaultRunDir(const std::string& host);

}  // namespace polarslam
