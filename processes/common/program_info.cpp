#include "common/program_info.hpp"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

namespace polarslam {
namespace {

namespace fs = std::filesystem;

fs::path executableFolder() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : self.parent_path();
}

}  // namespace

std::string polarslamVersion() { return std::string("polarslam ") + POLARSLAM_VERSION; }

void addVersionFlag(CLI::App& app) { app.set_version_flag("--version", polarslamVersion(), "print the version and exit"); }

void addPrintConfigFlag(CLI::App& app, std::function<std::string()> yaml) {
  auto requested = std::make_shared<bool>(false);
  app.add_flag("--print-config", *requested, "print the parameters in effect (YAML) and exit");
  app.final_callback([requested, yaml = std::move(yaml)] {
    if (!*requested) return;
    std::cout << yaml();
    throw CLI::Success();
  });
}

std::string dataDirectory() {
  const fs::path installed = executableFolder() / ".." / "share" / "polarslam";
  std::error_code ec;
  if (fs::is_directory(installed / "config", ec)) return fs::weakly_canonical(installed, ec).string();
  return POLARSLAM_SOURCE_DIR;  // a program run from its build tree
}

std::string dataPath(const std::string& relative) { return (fs::path(dataDirectory()) / relative).string(); }

}  // namespace polarslam
