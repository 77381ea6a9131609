#pragma once
// The estimators `polarslam run --pipeline NAME` can run, by name.
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "pipeline/estimator.hpp"

namespace polarslam {

struct PipelineOptions {
  std::string sensors = "fused";  ///< laser | sonar | fused (feature SLAM)
  std::string config;             ///< optional YAML with estimator parameters
};

using PipelineFactory = std::function<std::unique_ptr<Estimator>(const PipelineOptions&)>;

/// name → factory; every pipeline adds itself in pipelines.cpp.
const std::map<std::string, PipelineFactory>& pipelines();

/// The parameters a pipeline would run with (its configuration file over the defaults), as the
/// YAML its --config takes; "" for pipelines without parameters.
std::string effectiveConfigYaml(const std::string& pipeline, const PipelineOptions& options);

}  // namespace polarslam
