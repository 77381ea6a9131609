#pragma once
// The App. B observation models h(x_v, y) (map feature seen from a robot pose) with their
// Jacobians, as pose regeneration needs them (docs/algorithms.md §17.8; line flip convention included).
#include "slam/feature_map.hpp"

namespace polarslam {

struct AnchorPrediction {
  bool valid = false;      ///< false: the model is undefined or discontinuous here
  int dims = 2;            ///< rows used: 2 (line, point) or 3 (corner)
  Vec3 z = Vec3::Zero();   ///< predicted robot-frame observation
  Mat3 H_x = Mat3::Zero(); ///< ∂h/∂(x, y, θ); unused rows 0
  Mat3 H_y = Mat3::Zero(); ///< ∂h/∂y (feature parameters); unused rows/columns 0
};

/// Predicts how `feature` looks from robot pose `pose`. Lines passing closer than
/// `min_line_distance` to the robot are invalid (the d ≥ 0 flip makes h discontinuous there);
/// so are corners and points closer than 1 mm (bearing undefined).
AnchorPrediction predictAnchor(const Pose2& pose, const MapFeature& feature, double min_line_distance = 0.05);

/// z_measured − z_predicted with angle components wrapped into (−π, π] (unused rows 0).
Vec3 anchorResidual(MapFeatureKind kind, const Vec3& measured, const Vec3& predicted);

}  // namespace polarslam
