#include "launch/executable_search.hpp"

#include <unistd.h>

#include <filesystem>
#include <sstream>

namespace polarslam {
namespace {

bool isExecutableFile(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

}  // namespace

std::string findExecutable(const std::string& program, const std::string& search_path,
                           const std::string& working_dir) {
  if (program.empty()) return "";
  if (program.find('/') != std::string::npos) {
    std::filesystem::path p(program);
    if (p.is_relative() && !working_dir.empty()) p = std::filesystem::path(working_dir) / p;
    return isExecutableFile(p) ? p.lexically_normal().string() : "";
  }
  std::istringstream dirs(search_path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    // An empty PATH entry means the working directory, as for execvp.
    std::filesystem::path base = dir.empty() ? std::filesystem::path(working_dir.empty() ? "." : working_dir)
                                             : std::filesystem::path(dir);
    if (base.is_relative() && !working_dir.empty()) base = std::filesystem::path(working_dir) / base;
    if (isExecutableFile(base / program)) return (base / program).lexically_normal().string();
  }
  return "";
}

}  // namespace polarslam
