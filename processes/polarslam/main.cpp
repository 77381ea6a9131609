// polarslam: one command line for offline work (simulate, import, run, match, eval, report...).
#include <algorithm>
#include <exception>
#include <iostream>

#include "common/program_info.hpp"
#include "command_registry.hpp"

namespace polarslam {
std::vector<Command>& registeredCommands() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace polarslam

int main(int argc, char** argv) {
  CLI::App app{"polarslam: 2D SLAM with laser, advanced sonar and odometry"};
  polarslam::addVersionFlag(app);
  app.require_subcommand(0, 1);
  auto& commands = polarslam::registeredCommands();
  std::sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  for (auto& command : commands) command.setup(*app.add_subcommand(command.name, command.help));
  try {
    app.parse(argc, argv);
    if (app.get_subcommands().empty()) std::cout << app.help();
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    const std::string sub = app.get_subcommands().empty() ? "" : " " + app.get_subcommands().front()->get_name();
    std::cerr << "polarslam" << sub << ": " << e.what() << "\n";
    return 1;
  }
  return 0;
}
