// polarslam simulate: runs the simulated robot as fast as possible into an LCM log.
#include <filesystem>
#include <iostream>

#include "command_registry.hpp"
#include "common/program_info.hpp"
#include "common/lcm_log.hpp"
#include "common/progress.hpp"
#include "common/sim_channels.hpp"

namespace polarslam {
namespace {

struct SimulateOptions {
  std::string world = dataPath("config/worlds/office.yaml");
  std::string robot = dataPath("config/robots/default.yaml");
  std::string out;
  double seconds = 0.0;
  uint64_t seed = 1;
};

void runSimulate(const SimulateOptions& o) {
  Simulator sim(loadWorld(o.world), loadRobotDescription(o.robot), o.seed);
  LcmLogWriter writer(o.out);
  auto sink = makeSimChannels(SensorChannels{}, [&](const std::string& channel, int64_t utime, const auto& msg) {
    writer.write(channel, utime, msg);
  });
  ProgressBar progress("simulate");
  const double limit = o.seconds > 0.0 ? o.seconds : 3600.0;
  while (sim.time() < limit && !sim.finished()) {
    sim.step(sink);
    progress.update(o.seconds > 0.0 ? sim.time() / o.seconds : 0.0);
  }
  progress.finish();
  writer.close();
  std::cout << "wrote " << o.out << ": " << writer.events() << " messages, " << sim.time()
            << " s simulated (world " << o.world << ", seed " << o.seed << ")\n";
}

void setupSimulate(CLI::App& sub) {
  auto o = std::make_shared<SimulateOptions>();
  sub.add_option("--world", o->world, "world YAML")->check(CLI::ExistingFile)->capture_default_str();
  sub.add_option("--robot", o->robot, "robot and sensor YAML")->check(CLI::ExistingFile)->capture_default_str();
  sub.add_option("--seconds", o->seconds, "simulated seconds (0 = until the path ends)")->check(CLI::NonNegativeNumber);
  sub.add_option("--seed", o->seed, "random seed")->capture_default_str();
  sub.add_option("--out,-o", o->out, "LCM log to write")->required();
  sub.callback([o] { runSimulate(*o); });
}

RegisterCommand reg_simulate("simulate", "Simulate the robot in a world and write an LCM log", setupSimulate);

}  // namespace
}  // namespace polarslam
