// YAML configuration of the laser feature extractor (see loadLaserFeatureConfig).
#include <cmath>

#include "laser/laser_feature_extractor.hpp"
#include "config/yaml_fields.hpp"

namespace polarslam {
namespace {

/// `errors:` map of (2.8) in the keys of config/robots/default.yaml's laser section.
void readRangeErrors(const YamlFields& y, const YAML::Node& node, const std::string& ctx, LaserErrorParams& p,
                     bool strict) {
  if (strict)
    y.requireMap(node, ctx,
                 {"fixed_bias", "scan_bias_sigma", "growth", "incidence", "max_incidence_deg", "quantum", "noise_sigma",
                  "compensate_quantizer_offset", "output_noise_sigma"});
  RangeErrorParams& r = p.range;
  r.fixed_bias = y.number(node, "fixed_bias", ctx, r.fixed_bias, -1.0, 1.0);
  r.scan_bias_sigma = y.number(node, "scan_bias_sigma", ctx, r.scan_bias_sigma, 0.0, 1.0);
  r.growth = y.number(node, "growth", ctx, r.growth, -0.5, 0.5);
  r.incidence = y.number(node, "incidence", ctx, r.incidence, -1.0, 1.0);
  r.max_incidence = deg2rad(y.number(node, "max_incidence_deg", ctx, rad2deg(r.max_incidence), 1.0, 89.9));
  r.quantum = y.number(node, "quantum", ctx, r.quantum, 0.0, 1.0);
  r.noise_sigma = y.number(node, "noise_sigma", ctx, r.noise_sigma, 0.0, 1.0);
  p.output_noise_sigma = y.number(node, "output_noise_sigma", ctx, p.output_noise_sigma, 0.0, 1.0);
  // An uncompensated truncating quantiser reads q/2 short on average: one more identical bias.
  if (!y.boolean(node, "compensate_quantizer_offset", ctx, true)) r.fixed_bias = std::abs(r.fixed_bias) + r.quantum / 2;
}

void readSegmentation(const YamlFields& y, const YAML::Node& node, const std::string& ctx, SegmentationParams& s) {
  y.requireMap(node, ctx,
               {"min_line_points", "min_line_length", "split_distance", "split_sigmas", "break_angle_deg",
                "break_sigmas", "max_gap_beams", "corner_tolerance_deg"});
  s.min_line_points = y.integer(node, "min_line_points", ctx, s.min_line_points, 3, 100000);
  s.min_line_length = y.number(node, "min_line_length", ctx, s.min_line_length, 0.0, 100.0);
  s.split_distance = y.number(node, "split_distance", ctx, s.split_distance, 0.0, 10.0);
  s.split_sigmas = y.number(node, "split_sigmas", ctx, s.split_sigmas, 0.0, 100.0);
  s.break_angle = deg2rad(y.number(node, "break_angle_deg", ctx, rad2deg(s.break_angle), 0.1, 89.0));
  s.break_sigmas = y.number(node, "break_sigmas", ctx, s.break_sigmas, 0.0, 100.0);
  s.max_gap_beams = y.integer(node, "max_gap_beams", ctx, s.max_gap_beams, 0, 1000);
  s.corner_tolerance = deg2rad(y.number(node, "corner_tolerance_deg", ctx, rad2deg(s.corner_tolerance), 0.0, 45.0));
}

}  // namespace

void readLaserFeatureSection(const YamlFields& y, const YAML::Node& node, LaserFeatureConfig& c) {
  const std::string ctx = "laser_features";
  y.requireMap(node, ctx,
               {"errors", "tilt_deg", "tilt_axis_deg", "yaw_error_deg", "systematic_scale", "max_incidence_deg",
                "outlier_sigmas", "outlier_run_length", "outlier_run_sigmas", "outlier_end_run_length",
                "outlier_end_sigmas", "outlier_max_fraction", "residual_gate", "corners", "corner_split_search",
                "corner_max_rms_ratio", "corner_junction_distance", "segmentation"});
  if (y.has(node, "errors")) readRangeErrors(y, node["errors"], ctx + ".errors", c.errors, true);
  c.errors.tilt = deg2rad(y.number(node, "tilt_deg", ctx, rad2deg(c.errors.tilt), -45.0, 45.0));
  c.errors.tilt_axis = deg2rad(y.number(node, "tilt_axis_deg", ctx, rad2deg(c.errors.tilt_axis), -360.0, 360.0));
  c.errors.yaw_error = deg2rad(y.number(node, "yaw_error_deg", ctx, rad2deg(c.errors.yaw_error), -45.0, 45.0));
  c.errors.systematic_scale = y.number(node, "systematic_scale", ctx, c.errors.systematic_scale, 0.0, 100.0);
  c.fit.max_incidence = deg2rad(y.number(node, "max_incidence_deg", ctx, rad2deg(c.fit.max_incidence), 1.0, 89.9));
  c.outlier_sigmas = y.number(node, "outlier_sigmas", ctx, c.outlier_sigmas, 1.0, 1000.0);
  c.outlier_run_length = y.integer(node, "outlier_run_length", ctx, c.outlier_run_length, 1, 100000);
  c.outlier_run_sigmas = y.number(node, "outlier_run_sigmas", ctx, c.outlier_run_sigmas, 0.5, 1000.0);
  c.outlier_end_run_length = y.integer(node, "outlier_end_run_length", ctx, c.outlier_end_run_length, 1, 100000);
  c.outlier_end_sigmas = y.number(node, "outlier_end_sigmas", ctx, c.outlier_end_sigmas, 0.5, 1000.0);
  c.outlier_max_fraction = y.number(node, "outlier_max_fraction", ctx, c.outlier_max_fraction, 0.0, 0.9);
  c.residual_gate = y.number(node, "residual_gate", ctx, c.residual_gate, 0.0, 0.999999);
  c.corners = y.boolean(node, "corners", ctx, c.corners);
  c.corner_split_search = y.integer(node, "corner_split_search", ctx, c.corner_split_search, 0, 100);
  c.corner_max_rms_ratio = y.number(node, "corner_max_rms_ratio", ctx, c.corner_max_rms_ratio, 1.0, 100.0);
  c.corner_junction_distance =
      y.number(node, "corner_junction_distance", ctx, c.corner_junction_distance, 0.0, 10.0);
  if (y.has(node, "segmentation")) readSegmentation(y, node["segmentation"], ctx + ".segmentation", c.segmentation);
}

LaserFeatureConfig loadLaserFeatureConfig(const std::string& path) {
  const YamlFields y(path);
  const YAML::Node& root = y.root();
  if (!root.IsMap()) y.fail(root, "expected a map with a 'laser' (robot file) or 'laser_features' section");
  if (!y.has(root, "laser") && !y.has(root, "laser_features"))
    y.fail(root, "neither a 'laser' (robot file) nor a 'laser_features' section");
  LaserFeatureConfig c;
  if (y.has(root, "laser")) {  // robot file: the simulator's own laser error model
    const YAML::Node& laser = root["laser"];
    c.errors = LaserErrorParams{};
    if (y.has(laser, "errors")) readRangeErrors(y, laser["errors"], "laser.errors", c.errors, false);
    c.errors.tilt = deg2rad(y.number(laser, "tilt_deg", "laser", 0.0, -45.0, 45.0));
    c.errors.tilt_axis = deg2rad(y.number(laser, "tilt_axis_deg", "laser", 0.0, -360.0, 360.0));
  }
  if (y.has(root, "laser_features")) readLaserFeatureSection(y, root["laser_features"], c);
  return c;
}

}  // namespace polarslam
