#pragma once
// The options that work in a saved map (docs/maps.md), shared by polarslam-psm-slam and
// `polarslam run --pipeline psm-slam`: --load-map, --mode and --initial-pose, read into the
// SavedMapOptions both hand to the same session/estimator factory. --save-map is each
// program's own (the live one also saves on SAVE_MAP requests).
#include <string>

#include "pipeline/psm_slam_session.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace polarslam {

class SavedMapCli {
 public:
  /// Adds --load-map, --mode and --initial-pose to `app`.
  void add(CLI::App& app);
  /// The options as given, with `save_map`; throws std::runtime_error for a malformed --initial-pose.
  SavedMapOptions resolve(const std::string& save_map) const;
  const std::string& loadMap() const { return options_.load_map; }
  const std::string& mode() const { return options_.mode; }
  bool hasInitialPose() const { return !initial_pose_.empty(); }

 private:
  SavedMapOptions options_;
  std::string initial_pose_;
};

}  // namespace polarslam
