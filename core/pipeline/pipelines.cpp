#include "pipeline/pipelines.hpp"

#include "pipeline/feature_slam_estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"

namespace polarslam {

const std::map<std::string, PipelineFactory>& pipelines() {
  static const std::map<std::string, PipelineFactory> factories = {
      {"odometry", [](const PipelineOptions&) { return std::make_unique<OdometryEstimator>(); }},
      {"recorded", [](const PipelineOptions&) { return std::make_unique<RecordedEstimator>(); }},
      {"ekf",
       [](const PipelineOptions& o) -> std::unique_ptr<Estimator> {
         const SlamSensors sensors = parseSlamSensors(o.sensors);
         return std::make_unique<FeatureSlamEstimator>(loadFeaturePipelineConfig(o.config, sensors));
       }},
      {"psm-slam",
       [](const PipelineOptions& o) -> std::unique_ptr<Estimator> {
         return std::make_unique<PsmSlamEstimator>(o.config.empty() ? PsmSlamEstimatorConfig{}
                                                                    : loadPsmSlamEstimatorConfig(o.config));
       }},
  };
  return factories;
}

}  // namespace polarslam
