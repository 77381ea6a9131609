#pragma once
// The laser feature stage's configuration option, shared by polarslam-features and
// `polarslam features`: one YAML file (a robot file, config/laser-features.yaml, or an EKF
// pipeline file such as config/ekf.yaml), read by the same loader as every other stage.
#include <string>

#include "pipeline/feature_pipeline.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace polarslam {

class LaserFeatureOptions {
 public:
  /// Adds --config to `app`.
  void add(CLI::App& app);
  /// The EKF pipeline's configuration from the file (the default robot's without one).
  FeaturePipelineConfig resolvePipeline(SlamSensors sensors) const;
  const std::string& configPath() const { return config_; }

 private:
  std::string config_;
};

}  // namespace polarslam
