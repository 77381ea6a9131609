#pragma once
// What every polarslam program knows about itself: its version (--version) and where the data
// installed with it lives (config/ files), so that defaults such as config/robots/default.yaml
// are found from any folder — installed (<prefix>/bin → <prefix>/share/polarslam) or in the
// build tree (the source tree's files).
#include <functional>
#include <string>

namespace CLI {
class App;
}  // namespace CLI

namespace polarslam {

/// "polarslam 0.2.0 (git 1a2b3c4)".
std::string polarslamVersion();
/// Adds --version (prints polarslamVersion() and exits).
void addVersionFlag(CLI::App& app);
/// Adds --print-config: once the command line is parsed, prints `yaml()` (the parameters in
/// effect, which depend on the other options) and exits with status 0.
void addPrintConfigFlag(CLI::App& app, std::function<std::string()> yaml);
/// The folder holding config/ (and logs/ in the source tree).
std::string dataDirectory();
/// dataDirectory() / relative, e.g. dataPath("config/robots/default.yaml").
std::string dataPath(const std::string& relative);

}  // namespace polarslam
