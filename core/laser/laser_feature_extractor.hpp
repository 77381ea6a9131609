#pragma once
// LaserScan (+ optional break-hint bearings, + optional laser motion) → FeatureSet of polar
// lines and right-angle corners in the laser frame, each with the covariance a Kalman filter
// should use (docs/algorithms.md §16.11): random part σ_r²(HᵀH)⁻¹ + C_b plus the systematic bound.
#include <span>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "laser/corner_fit.hpp"
#include "laser/laser_error_model.hpp"
#include "laser/laser_scan.hpp"
#include "laser/line_errors.hpp"
#include "laser/polar_line_fit.hpp"
#include "laser/segmentation.hpp"

namespace YAML {
class Node;
}  // namespace YAML

namespace polarslam {

class ParameterTable;
class YamlFields;

/// A SICK LMS-like laser of which only the white noise is known: σ_n = 1 cm.
inline LaserErrorParams defaultLaserErrors() {
  LaserErrorParams p;
  p.range.noise_sigma = 0.01;
  return p;
}

struct LaserFeatureConfig {
  LaserErrorParams errors = defaultLaserErrors();
  SegmentationParams segmentation;
  LineFitOptions fit;                   ///< max_incidence: readings beyond it are trimmed from a line
  double outlier_sigmas = 3.0;          ///< readings this many robust σ (≥ σ_r) off the line are dropped,
  int outlier_run_length = 3;           ///< and runs of this many readings on one side of the line
  double outlier_run_sigmas = 1.5;      ///< beyond this many σ (a door jamb, a pillar on a wall),
  int outlier_end_run_length = 2;       ///< and runs of this many at either end of the segment
  double outlier_end_sigmas = 2.0;      ///< beyond this many σ ...
  double outlier_max_fraction = 0.34;   ///< ... unless there are more than this fraction of them
  int outlier_rounds = 2;               ///< drop-and-refit rounds
  /// When a fit's range residuals are too large for σ_r (χ² test of SSE/σ_r² on n − p degrees
  /// of freedom at this probability), its random covariance is scaled by the a-posteriori
  /// variance factor SSE/((n − p)·σ_r²). 0 turns the test off.
  double residual_gate = 0.999;
  bool corners = true;                  ///< fit right-angle corners to perpendicular neighbours
  int corner_split_search = 2;          ///< try moving the arms' junction by up to this many readings
  double corner_max_rms_ratio = 2.0;    ///< corner fit RMS ≤ this × max(arm line RMS, σ_r)
  /// m: the apex may lie this far (+3σ_r + one beam spacing along each arm) from each arm's end
  double corner_junction_distance = 0.02;
};

/// Binds every key of a `laser_features:` section (config/laser-features.yaml) to `config`.
void describeLaserFeatures(ParameterTable& table, LaserFeatureConfig& config);
/// Reads a features file (config/laser-features.yaml: one `laser_features:` section); keys left
/// out keep the defaults. A robot file's error model comes through core/robot instead
/// (laserErrorParams). Throws std::runtime_error "FILE:LINE: ..." on bad input.
LaserFeatureConfig loadLaserFeatureConfig(const std::string& path);
/// Applies a `laser_features:` section (the keys of config/laser-features.yaml) to `config`.
void readLaserFeatureSection(const YamlFields& yaml, const YAML::Node& section, LaserFeatureConfig& config);

/// Everything the extractor computed, for diagnostics and benchmarks.
struct ExtractionDetails {
  int valid_readings = 0;
  Segmentation segmentation;
  std::vector<LineFit> line_fits;              ///< one per output line
  std::vector<double> line_variance_factors;   ///< one per output line (1 = residuals as σ_r predicts)
  std::vector<LineErrorBudget> line_budgets;   ///< one per output line
  std::vector<CornerFit> corner_fits;          ///< one per output corner
  std::vector<CornerErrorBudget> corner_budgets;
};

class LaserFeatureExtractor {
 public:
  explicit LaserFeatureExtractor(const LaserFeatureConfig& config = {});

  /// Features of one scan in the laser frame (frame "laser", sensor_pose = scan.laser_pose,
  /// utime/seq copied). `break_bearings` (rad, laser frame) force segment breaks; `motion` is the
  /// laser's velocity during the scan (enters the systematic bound). Never throws on bad scans:
  /// a scan validateScan() refuses gives an empty set.
  FeatureSet extract(const LaserScan& scan, std::span<const double> break_bearings = {},
                     const SensorMotion& motion = {}, ExtractionDetails* details = nullptr) const;

  const LaserFeatureConfig& config() const { return config_; }

  /// A-posteriori variance factor of a fit with n readings and p parameters: SSE/((n − p)·σ_r²)
  /// when SSE/σ_r² fails the χ²(n − p) test at config().residual_gate, otherwise 1.
  double varianceFactor(double residual_rms, int n, int p) const;

 private:
  LaserFeatureConfig config_;
  LaserErrorModel model_;
  double gate_z_ = 0.0;  ///< standard normal quantile of residual_gate (Wilson–Hilferty χ² quantiles)
};

}  // namespace polarslam
