#pragma once
// Geometric features measured by the laser, the sonar, or both, with their error models.
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

enum class FeatureSource : int8_t { Laser = 0, Sonar = 1, Fused = 2 };

/// Line x cos α + y sin α = d, d ≥ 0   (2.9)
struct LineFeature {
  FeatureSource source = FeatureSource::Laser;
  double alpha = 0.0, d = 0.0;
  Mat2 cov = Mat2::Zero();          ///< covariance a Kalman filter should use
  Mat2 random_cov = Mat2::Zero();   ///< random part: σ_r²(HᵀH)⁻¹ (2.25) + per-scan bias (A.21)
  Vec2 systematic_bound = Vec2::Zero();  ///< Σ|Δα_k|, Σ|Δd_k| over systematic sources
  Vec2 endpoint_a = Vec2::Zero(), endpoint_b = Vec2::Zero();
  int num_points = 0;
  int first_index = -1, last_index = -1;  ///< beams used (laser), -1 otherwise
};

/// Right-angle corner: apex and γ, the bisector direction pointing from the apex into free space.
struct CornerFeature {
  FeatureSource source = FeatureSource::Laser;
  bool convex = false;
  double x = 0.0, y = 0.0, gamma = 0.0;
  Mat3 cov = Mat3::Zero();
  int num_points = 0;
};

struct PointFeature {
  FeatureSource source = FeatureSource::Laser;
  double x = 0.0, y = 0.0;
  Mat2 cov = Mat2::Zero();
};

/// Variance used for an unknown angle (e.g. a sonar corner's orientation).
inline constexpr double kUnknownAngleVariance = 1e4;

struct FeatureSet {
  int64_t utime = 0;
  int64_t seq = 0;
  std::string frame = "laser";  ///< "laser" or "base"
  Pose2 sensor_pose;            ///< pose of `frame` in the robot base frame
  std::vector<LineFeature> lines;
  std::vector<CornerFeature> corners;
  std::vector<PointFeature> points;
  int num_rejected = 0;
  /// Laser sets: sonar break-hint bearings (rad, laser frame) the segmenter used.
  std::vector<double> break_hints;
};

struct PoseStamped {
  int64_t utime = 0;
  Pose2 pose;
  Mat3 cov = Mat3::Zero();
};

}  // namespace polarslam
