#pragma once
// EKF SLAM feature models of thesis App. B, as corrected in docs/algorithms.md §17.8: for lines (α, d),
// right-angle corners (x, y, γ) and points (x, y) in the map frame,
//   h: map → robot (the observation) with H_x = ∂h/∂x_v, H_y = ∂h/∂y_i,
//   g: robot → map (feature initialisation) with G_x = ∂g/∂x_v, G_z = ∂g/∂z.
// Observations in the robot base frame: line (α_r, d_r), corner (φ_r, r_r, γ_r), point (x_r, y_r).
// Every function here is pure; unused rows and columns of the fixed-size 3-wide matrices are 0.
#include <Eigen/Core>

#include "geometry/pose2.hpp"
#include "slam/feature_map.hpp"

namespace polarslam {

using Mat23 = Eigen::Matrix<double, 2, 3>;

// ---- Lines -------------------------------------------------------------------------------------
//
// Flip convention (docs/algorithms.md §17.8): a line is stored with d ≥ 0. When the robot-frame distance of a
// map line comes out negative, the observation flips (d → −d, α → α + π) and s = −1 multiplies
// the d row of H_x and H_y, which are evaluated at the *state's* α_m. In G_x and G_z, evaluated
// at the *stored* (possibly flipped) α_m, the trigonometric entries carry no s.

struct LineObservationModel {
  Vec2 z = Vec2::Zero();  ///< (α_r, d_r), d_r ≥ 0
  Mat23 H_x = Mat23::Zero();
  Mat2 H_y = Mat2::Zero();
  double s = 1.0;          ///< −1 when the observation was flipped
};
/// App. B "transformation from map to robot" for a line and its Jacobians.
LineObservationModel observeLine(const Pose2& robot, const Vec2& map_line);

struct LineInitModel {
  Vec2 y = Vec2::Zero();  ///< (α_m, d_m), d_m ≥ 0
  Mat23 G_x = Mat23::Zero();
  Mat2 G_z = Mat2::Zero();
  double s = 1.0;
};
/// App. B "transformation from robot to map" for a line and its Jacobians.
LineInitModel initLine(const Pose2& robot, const Vec2& observed_line);

// ---- Points ------------------------------------------------------------------------------------

struct PointObservationModel {
  Vec2 z = Vec2::Zero();  ///< (x_r, y_r)
  Mat23 H_x = Mat23::Zero();
  Mat2 H_y = Mat2::Zero();
};
PointObservationModel observePoint(const Pose2& robot, const Vec2& map_point);

struct PointInitModel {
  Vec2 y = Vec2::Zero();  ///< (x_m, y_m)
  Mat23 G_x = Mat23::Zero();
  Mat2 G_z = Mat2::Zero();
};
PointInitModel initPoint(const Pose2& robot, const Vec2& observed_point);

// ---- Right-angle corners -----------------------------------------------------------------------

struct CornerObservationModel {
  Vec3 z = Vec3::Zero();  ///< (φ_r, r_r, γ_r)
  Mat3 H_x = Mat3::Zero();
  Mat3 H_y = Mat3::Zero();
};
/// Needs the apex away from the robot (r_r > 0); at r_r = 0 the bearing is undefined and the
/// Jacobians are returned as zero.
CornerObservationModel observeCorner(const Pose2& robot, const Vec3& map_corner);

struct CornerInitModel {
  Vec3 y = Vec3::Zero();  ///< (x_m, y_m, γ_m)
  Mat3 G_x = Mat3::Zero();
  Mat3 G_z = Mat3::Zero();
};
CornerInitModel initCorner(const Pose2& robot, const Vec3& observed_corner);

// ---- Conversions between feature representations ---------------------------------------------

/// Corner apex and orientation (x, y, γ) → the App. B observation (φ, r, γ), with the Jacobian
/// of that conversion (zero when the apex is at the origin).
struct PolarCorner {
  Vec3 z = Vec3::Zero();
  Mat3 J = Mat3::Zero();
};
PolarCorner cornerToPolar(const Vec3& cartesian);

/// Difference of two observations of the same kind with the angle entries wrapped:
/// lines wrap entry 0, corners entries 0 and 2, points none.
Vec3 observationDifference(MapFeatureKind kind, const Vec3& a, const Vec3& b);

}  // namespace polarslam
