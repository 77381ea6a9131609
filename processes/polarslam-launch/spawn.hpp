#pragma once
// Starting one supervised command: fork/exec into its own process group, stdin from /dev/null,
// stdout and stderr into one pipe the launcher reads.
#include <string>

#include "launch/group_file.hpp"

namespace polarslam {

struct SpawnResult {
  int pid = -1;        // also the process group id
  int output_fd = -1;  // read end of the child's stdout + stderr (non-blocking)
  std::string error;   // set when nothing was started
  std::string detail;  // more about the error, for the log (e.g. the PATH searched)
};

/// `base_env` is the launcher's environment; `bin_dir` is put first on the child's PATH so that
/// sibling executables of the launcher are found. The child gets SIGKILL if the launcher dies.
SpawnResult spawnCommand(const CommandSpec& spec, const Environment& base_env, const std::string& bin_dir);

/// The environment a command runs with (base + PATH with bin_dir first + its own entries).
Environment commandEnvironment(const CommandSpec& spec, const Environment& base_env, const std::string& bin_dir);

}  // namespace polarslam
