#pragma once
// Starting real polarslam processes (and LCM's own tools) from integration tests.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "source_path.hpp"

extern char** environ;

namespace polarslam::testing {

inline std::string binPath(const std::string& name) { return std::string(POLARSLAM_BINARY_DIR) + "/bin/" + name; }

/// A child process that is killed (SIGKILL) if still running when the object goes away.
class ChildProcess {
 public:
  /// Starts argv[0] (searched on PATH when it has no slash); stdout/stderr go to `log_path` if given.
  explicit ChildProcess(const std::vector<std::string>& argv, const std::string& log_path = "") {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!log_path.empty()) {
      posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      posix_spawn_file_actions_adddup2(&actions, 1, 2);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int rc = posix_spawnp(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() {
    if (running()) {
      ::kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  pid_t pid() const { return pid_; }
  bool running() {
    if (exited_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) record(status);
    return !exited_;
  }
  /// Waits up to `timeout` for the process to end; returns true if it did.
  bool waitFor(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (running()) {
      if (std::chrono::steady_clock::now() >= end) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return true;
  }
  void signal(int sig) { if (running()) ::kill(pid_, sig); }
  /// Exit code, or 128 + signal number; -1 while running.
  int exitCode() const { return exit_code_; }

 private:
  void record(int status) {
    exited_ = true;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
};

/// The whole content of a text file ("" when it cannot be read).
inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A JSON file (report.json) parsed; a discarded value when it is missing or malformed.
inline nlohmann::json readJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

/// A number of a report.json (NaN when the report lacks it).
inline double figure(const nlohmann::json& report, const char* key) {
  return report.contains(key) ? report[key].get<double>() : std::nan("");
}

/// An empty folder of this test in the temporary folder: polarslam-NAME-PID.
inline std::filesystem::path freshDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-" + name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// Runs a command to its end, its output into `out`; its exit code, or -1 if it outlived `limit`.
inline int runToEnd(const std::vector<std::string>& argv, const std::filesystem::path& out, std::chrono::seconds limit) {
  ChildProcess p(argv, out.string());
  if (!p.waitFor(limit)) return -1;
  return p.exitCode();
}

}  // namespace polarslam::testing
