#pragma once
// Summaries of pose covariances (x, y, θ).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "geometry/pose2.hpp"

namespace polarslam {

/// Standard deviation of the position along its most uncertain direction.
inline double largestPositionSigma(const Mat3& cov) {
  const Mat2 position = cov.topLeftCorner<2, 2>();
  return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat2>(position).eigenvalues().maxCoeff()));
}

}  // namespace polarslam
