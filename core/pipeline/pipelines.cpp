#include "pipeline/pipelines.hpp"

#include "pipeline/feature_slam_estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"

namespace polarslam {

const std::map<std::string, PipelineFactory>& pipelines() {
  static const std::map<std::string, PipelineFactory> factories = {
      {"odometry", [](const PipelineOptions&) { return std::make_unique<OdometryEstimator>(); }},
      {"recorded", [](const PipelineOptions&) { return std::make_unique<RecordedEstimator>(); }},
      {"psm", [](const PipelineOptions&) { return std::make_unique<LaserOdometryEstimator>(); }},
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

std::string effectiveConfigYaml(const std::string& pipeline, const PipelineOptions& o) {
  ParameterTable table;
  if (pipeline == "psm-slam") {
    PsmSlamEstimatorConfig config = loadPsmSlamEstimatorConfig(o.config);
    describePsmSlamEstimatorConfig(table, config);
    return table.yaml();
  }
  if (pipeline == "ekf") {
    FeaturePipelineConfig config = loadFeaturePipelineConfig(o.config, parseSlamSensors(o.sensors));
    FeaturePipelineTables tables;
    describeFeaturePipeline(tables, config);
    return "ekf:\n" + tables.ekf.yaml(2) + "fusion:\n" + tables.fusion.yaml(2) + "laser_features:\n" +
           tables.laser_features.yaml(2);
  }
  return {};
}

}  // namespace polarslam
