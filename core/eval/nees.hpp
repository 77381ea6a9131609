#pragma once
// Normalised estimation error squared (NEES) of pose estimates with covariance, and the χ²
// acceptance interval of an average over N Monte Carlo runs (Bar-Shalom et al., "Estimation with
// Applications to Tracking and Navigation", §5.4): N·NEES̄ ~ χ²(N·d) for a consistent filter.
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

/// eᵀ P⁻¹ e with e = (x̂ − x, ŷ − y, wrap(θ̂ − θ)). Throws std::invalid_argument when P is not
/// symmetric positive definite or anything is non-finite.
double poseNees(const Pose2& estimate, const Mat3& covariance, const Pose2& truth);

struct NeesInterval {
  double lower = 0.0, upper = 0.0;
};

/// Two-sided interval holding the average of `samples` independent NEES values of dimension
/// `dimension` with the given probability: [χ²_{Nd}((1−c)/2), χ²_{Nd}((1+c)/2)] / N.
NeesInterval averageNeesInterval(int dimension, int samples, double confidence = 0.95);

struct NeesSummary {
  std::vector<double> average_per_step;  ///< average over runs at each step
  double average = 0.0;                  ///< over all runs and steps
  NeesInterval step_interval;            ///< for one step's average over the runs
  double fraction_steps_inside = 0.0;    ///< of average_per_step inside step_interval
};

/// nees[run][step]: every run must have the same number of steps (std::invalid_argument otherwise).
NeesSummary summarizeNees(const std::vector<std::vector<double>>& nees, int dimension, double confidence = 0.95);

}  // namespace polarslam
