#pragma once
// The SLAM feature map and scan anchors as plain structs: the EKF produces them, the grid
// (pose regeneration) and the report consume them. Conventions follow thesis App. B
// (docs/algorithms.md §17.8): lines (α, d), corners (x, y, γ), points (x, y) in the map frame; observations
// in the robot base frame: line (α_r, d_r), corner (φ_r, r_r, γ_r), point (x_r, y_r).
#include <cstdint>
#include <vector>

#include "geometry/features.hpp"

namespace polarslam {

enum class MapFeatureKind : int8_t { Line = 0, Corner = 1, Point = 2 };

inline int parameterCount(MapFeatureKind kind) { return kind == MapFeatureKind::Corner ? 3 : 2; }

struct MapFeature {
  int64_t id = 0;
  MapFeatureKind kind = MapFeatureKind::Line;
  Vec3 params = Vec3::Zero();  ///< unused entries 0
  Mat3 cov = Mat3::Zero();     ///< marginal covariance, top-left block used
  Vec2 endpoint_a = Vec2::Zero(), endpoint_b = Vec2::Zero();  ///< lines: observed extent
  int observations = 0;
};

struct FeatureMap {
  int64_t utime = 0;
  PoseStamped robot;  ///< current robot pose in the map frame
  std::vector<MapFeature> features;
};

/// One map feature as the robot saw it when a scan was taken.
struct AnchorObservation {
  int64_t feature_id = 0;
  MapFeatureKind kind = MapFeatureKind::Line;
  Vec3 z = Vec3::Zero();    ///< robot-frame observation (App. B h())
  Mat3 cov = Mat3::Zero();  ///< its covariance, top-left block used
};

/// The robot pose at a laser scan's time, relative to the map features near it (thesis §3.7.2).
struct ScanAnchors {
  int64_t utime = 0;  ///< utime of the laser scan
  PoseStamped pose;   ///< SLAM pose of the robot base at scan time
  std::vector<AnchorObservation> anchors;
};

}  // namespace polarslam
