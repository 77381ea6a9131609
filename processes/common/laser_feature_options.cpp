#include "common/laser_feature_options.hpp"

#include <CLI/CLI.hpp>

namespace polarslam {

void LaserFeatureOptions::add(CLI::App& app) {
  app.add_option("--config", config_,
                 "YAML: a robot file (its laser error model), config/laser-features.yaml, or an EKF pipeline "
                 "file such as config/ekf.yaml (its laser_features section)")
      ->check(CLI::ExistingFile);
}

FeaturePipelineConfig LaserFeatureOptions::resolvePipeline(SlamSensors sensors) const {
  return loadFeaturePipelineConfig(config_, sensors);
}

}  // namespace polarslam
