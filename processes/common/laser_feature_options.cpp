#include "common/laser_feature_options.hpp"

#include <CLI/CLI.hpp>

namespace polarslam {

void LaserFeatureOptions::add(CLI::App& app) {
  app.add_option("--config", config_,
                 "YAML: a robot file (its laser error model), config/laser-features.yaml, or an EKF pipeline "
                 "file such as config/ekf.yaml (its laser_features section)")
      ->check(CLI::ExistingFile);
  app.add_option("--noise-sigma", noise_sigma_, "m, white range noise sigma_n (default 0.01)");
  app.add_option("--quantum", quantum_, "m, range quantisation step q_r (0 = none)");
  app.add_option("--scan-bias-sigma", scan_bias_sigma_, "m, std of a range bias drawn per scan");
  app.add_option("--fixed-bias", fixed_bias_, "m, |r_b|, constant range bias bound");
  app.add_option("--growth", growth_, "|k|, bias growing with range, k (r - r_min)");
  app.add_option("--incidence", incidence_, "m, |w|, bias w |tan(incidence)|");
  app.add_option("--tilt-deg", tilt_deg_, "scan-plane tilt");
  app.add_option("--tilt-axis-deg", tilt_axis_deg_, "bearing of the tilt axis");
  app.add_option("--yaw-error-deg", yaw_error_deg_, "mounting yaw uncertainty");
  app.add_option("--systematic-scale", systematic_scale_, "filter covariance adds (scale * systematic bound)^2");
  app.add_flag("--no-corners", no_corners_, "extract lines only");
}

FeaturePipelineConfig LaserFeatureOptions::resolvePipeline(SlamSensors sensors) const {
  FeaturePipelineConfig c = loadFeaturePipelineConfig(config_, sensors);
  applyOverrides(c.laser);
  return c;
}

void LaserFeatureOptions::applyOverrides(LaserFeatureConfig& c) const {
  LaserErrorParams& e = c.errors;
  auto set = [](const std::optional<double>& option, double& target, double scale = 1.0) {
    if (option) target = *option * scale;
  };
  set(noise_sigma_, e.range.noise_sigma);
  set(quantum_, e.range.quantum);
  set(scan_bias_sigma_, e.range.scan_bias_sigma);
  set(fixed_bias_, e.range.fixed_bias);
  set(growth_, e.range.growth);
  set(incidence_, e.range.incidence);
  set(tilt_deg_, e.tilt, deg2rad(1.0));
  set(tilt_axis_deg_, e.tilt_axis, deg2rad(1.0));
  set(yaw_error_deg_, e.yaw_error, deg2rad(1.0));
  set(systematic_scale_, e.systematic_scale);
  for (double v : {e.range.noise_sigma, e.range.quantum, e.range.scan_bias_sigma, e.systematic_scale})
    if (!(v >= 0.0) || !std::isfinite(v)) throw std::runtime_error("error-model options must be finite and >= 0");
  if (no_corners_) c.corners = false;
}

}  // namespace polarslam
