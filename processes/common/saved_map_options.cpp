#include "common/saved_map_options.hpp"

#include <CLI/CLI.hpp>

namespace polarslam {

void SavedMapCli::add(CLI::App& app) {
  app.add_option("--load-map", options_.load_map, "PSM SLAM: a map saved by --save-map to work in (see --mode)")
      ->check(CLI::ExistingDirectory);
  app.add_option("--mode", options_.mode,
                 "with --load-map: localize = match against the stored reference scans and add none; continue = "
                 "map on from the stored map (new reference scans and loop closures join its graph; --save-map "
                 "saves the whole)")
      ->check(CLI::IsMember({"localize", "continue"}))
      ->capture_default_str();
  app.add_option("--initial-pose", initial_pose_,
                 "with --load-map: the start in the map frame, x,y,theta (m, m, rad); without it the start is "
                 "searched among the reference scans");
}

SavedMapOptions SavedMapCli::resolve(const std::string& save_map) const {
  SavedMapOptions options = options_;
  options.save_map = save_map;
  if (!initial_pose_.empty()) options.initial_pose = parseInitialPose(initial_pose_);
  return options;
}

}  // namespace polarslam
