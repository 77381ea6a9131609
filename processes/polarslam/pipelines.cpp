#include "pipelines.hpp"

namespace polarslam {

const std::map<std::string, PipelineFactory>& pipelines() {
  static const std::map<std::string, PipelineFactory> factories = {
      {"odometry", [](const PipelineOptions&) { return std::make_unique<OdometryEstimator>(); }},
  };
  return factories;
}

}  // namespace polarslam
