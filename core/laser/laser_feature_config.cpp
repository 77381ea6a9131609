// YAML configuration of the laser feature extractor: one ParameterTable (config/laser-features.yaml
// lists every key with its default).
#include "config/parameter_table.hpp"
#include "laser/laser_feature_extractor.hpp"

namespace polarslam {
namespace {

/// The range error model (2.8) as the extractor sees it.
void describeRangeErrors(ParameterTable& t, LaserErrorParams& p) {
  RangeErrorParams& r = p.range;
  t.number("noise_sigma", r.noise_sigma, 0.0, 1.0, "m, white noise (before the quantiser, if there is one)");
  t.number("quantum", r.quantum, 0.0, 1.0, "m, truncating quantiser step q_r; 0 = none");
  t.number("output_noise_sigma", p.output_noise_sigma, 0.0, 1.0, "m, white noise after the quantiser");
  t.number("scan_bias_sigma", r.scan_bias_sigma, 0.0, 1.0, "m, std of a bias drawn anew for every scan");
  t.number("fixed_bias", r.fixed_bias, -1.0, 1.0,
           "m, |r_b|: bias of every reading (an uncompensated quantiser adds q_r/2 here)");
  t.number("growth", r.growth, -0.5, 0.5, "|k|: bias k (r - r_min)");
  t.number("incidence", r.incidence, -1.0, 1.0, "m, |w|: bias w |tan(beta)|");
  t.angle("max_incidence_deg", r.max_incidence, 1.0, 89.9, "beta clamp of the incidence term");
}

void describeSegmentation(ParameterTable& t, SegmentationParams& s) {
  t.integer("min_line_points", s.min_line_points, 3, 100000, "fewer readings: not a line");
  t.number("min_line_length", s.min_line_length, 0.0, 100.0, "m, first to last reading");
  t.number("split_distance", s.split_distance, 0.0, 10.0, "m, + split_sigmas * sigma_r: split-and-merge threshold");
  t.number("split_sigmas", s.split_sigmas, 0.0, 100.0, "range sigmas added to split_distance");
  t.angle("break_angle_deg", s.break_angle, 0.1, 89.0, "adaptive breakpoint detector's lambda");
  t.number("break_sigmas", s.break_sigmas, 0.0, 100.0, "range sigmas added to the breakpoint threshold");
  t.integer("max_gap_beams", s.max_gap_beams, 0, 1000, "invalid readings tolerated inside a line");
  t.angle("corner_tolerance_deg", s.corner_tolerance, 0.0, 45.0, "neighbouring lines at 90 +- this: corner candidates");
}

void describeOutliers(ParameterTable& t, LaserFeatureConfig& c) {
  t.number("outlier_sigmas", c.outlier_sigmas, 1.0, 1000.0, "readings this many robust sigma off a line are dropped");
  t.integer("outlier_run_length", c.outlier_run_length, 1, 100000, "and runs of this many on one side of the line");
  t.number("outlier_run_sigmas", c.outlier_run_sigmas, 0.5, 1000.0, "beyond this many sigma (door jambs, pillars)");
  t.integer("outlier_end_run_length", c.outlier_end_run_length, 1, 100000, "and runs of this many at a segment's end");
  t.number("outlier_end_sigmas", c.outlier_end_sigmas, 0.5, 1000.0, "beyond this many sigma ...");
  t.number("outlier_max_fraction", c.outlier_max_fraction, 0.0, 0.9,
           "... unless more than this fraction of the readings would go");
  t.number("residual_gate", c.residual_gate, 0.0, 0.999999,
           "chi2 test of a fit's residuals; failing fits get their covariance scaled; 0 = off");
}

void describeCorners(ParameterTable& t, LaserFeatureConfig& c) {
  t.boolean("corners", c.corners, "fit right-angle corners to perpendicular neighbouring lines");
  t.integer("corner_split_search", c.corner_split_search, 0, 100, "readings the arms' junction may move");
  t.number("corner_max_rms_ratio", c.corner_max_rms_ratio, 1.0, 100.0, "corner fit RMS <= this * max(arm RMS, sigma_r)");
  t.number("corner_junction_distance", c.corner_junction_distance, 0.0, 10.0,
           "m (+3 sigma_r + a beam spacing along the arm), apex to each arm's end");
}

}  // namespace

void describeLaserFeatures(ParameterTable& t, LaserFeatureConfig& c) {
  describeRangeErrors(t.section("errors", "range error model (2.8)"), c.errors);
  t.angle("tilt_deg", c.errors.tilt, -45.0, 45.0, "scan-plane tilt (-> systematic bound, second order)");
  t.angle("tilt_axis_deg", c.errors.tilt_axis, -360.0, 360.0, "bearing of the in-plane tilt axis");
  t.angle("yaw_error_deg", c.errors.yaw_error, -45.0, 45.0, "mounting yaw uncertainty (-> alpha bound)");
  t.number("systematic_scale", c.errors.systematic_scale, 0.0, 100.0, "filter covariance adds (scale * bound)^2");
  t.angle("max_incidence_deg", c.fit.max_incidence, 1.0, 89.9, "readings meeting a line beyond this are dropped");
  describeOutliers(t, c);
  describeCorners(t, c);
  describeSegmentation(t.section("segmentation", "breakpoints and split-and-merge"), c.segmentation);
}

void readLaserFeatureSection(const YamlFields& y, const YAML::Node& node, LaserFeatureConfig& c) {
  ParameterTable table;
  describeLaserFeatures(table, c);
  table.read(y, node, "laser_features");
}

LaserFeatureConfig loadLaserFeatureConfig(const std::string& path) {
  const YamlFields y(path);
  const YAML::Node& root = y.root();
  if (!root.IsMap() || !y.has(root, "laser_features")) y.fail(root, "expected a map with a 'laser_features' section");
  y.requireMap(root, "laser features file", {"laser_features"});
  LaserFeatureConfig c;
  readLaserFeatureSection(y, root["laser_features"], c);
  return c;
}

}  // namespace polarslam
