#pragma once
// Subcommands of the `polarslam` CLI register themselves from their own cmd_*.cpp file:
//   static polarslam::RegisterCommand reg("simulate", "Simulate a run into an LCM log", setupSimulate);
// where setupSimulate(CLI::App& sub) adds options and sets sub.callback(...). A callback reports
// failure by throwing (std::exception); main prints "polarslam <cmd>: <what>" and exits 1.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace polarslam {

struct Command {
  std::string name, help;
  std::function<void(CLI::App&)> setup;
};

std::vector<Command>& registeredCommands();

struct RegisterCommand {
  RegisterCommand(std::string name, std::string help, std::function<void(CLI::App&)> setup) {
    registeredCommands().push_back({std::move(name), std::move(help), std::move(setup)});
  }
};

}  // namespace polarslam
