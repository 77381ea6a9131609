#include "run_logs.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <stdexcept>

namespace polarslam {
namespace {

std::string clockTime() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm local{};
  localtime_r(&t, &local);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%H:%M:%S", &local);
  char out[48];
  std::snprintf(out, sizeof(out), "%s.%03lld", buf, static_cast<long long>(ms));
  return out;
}

std::string envOr(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

}  // namespace

RunLogs::RunLogs(std::string dir) : dir_(std::move(dir)) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (!std::filesystem::is_directory(dir_))
    throw std::runtime_error("cannot create the run folder '" + dir_ + "': " + ec.message());
}

void RunLogs::write(const std::string& name, const std::string& line) {
  auto it = files_.find(name);
  if (it == files_.end()) {
    it = files_.emplace(name, std::ofstream(dir_ + "/" + name + ".log", std::ios::app)).first;
  }
  it->second << clockTime() << ' ' << line << '\n';
}

void RunLogs::flush() {
  for (auto& [name, file] : files_) file.flush();
}

std::string defaultRunDir(const std::string& host) {
  const std::string home = envOr("HOME", "/tmp");
  const std::string state = envOr("XDG_STATE_HOME", home + "/.local/state");
  const std::string base = envOr("POLARSLAM_LAUNCH_LOGS", state + "/polarslam/launch");
  const std::time_t t = std::time(nullptr);
  std::tm local{};
  localtime_r(&t, &local);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", &local);
  return base + "/" + stamp + "-" + host + "-" + std::to_string(getpid());
}

}  // namespace polarslam
