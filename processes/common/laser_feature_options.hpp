#pragma once
// Command-line options of the laser feature extractor, shared by polarslam-features and
// `polarslam features`: a YAML file (robot file, config/laser-features.yaml or an EKF pipeline
// file) plus overrides.

#include <optional>
#include <string>

#include "laser/laser_feature_extractor.hpp"
#include "pipeline/feature_pipeline.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace polarslam {

class LaserFeatureOptions {
 public:
  /// Adds --config and the error-model overrides to `app`.
  void add(CLI::App& app);
  /// The EKF pipeline's configuration from the YAML file (the default robot's without one), then
  /// every override given on the command line applied to its laser feature part.
  FeaturePipelineConfig resolvePipeline(SlamSensors sensors) const;

 private:
  void applyOverrides(LaserFeatureConfig& config) const;

  std::string config_;
  std::optional<double> noise_sigma_, quantum_, scan_bias_sigma_, fixed_bias_, growth_, incidence_, tilt_deg_,
      tilt_axis_deg_, yaw_error_deg_, systematic_scale_;
  bool no_corners_ = false;
};

}  // namespace polarslam
