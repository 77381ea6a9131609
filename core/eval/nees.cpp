#include "eval/nees.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

#include "geometry/chi_squared.hpp"

namespace polarslam {

double poseNees(const Pose2& estimate, const Mat3& covariance, const Pose2& truth) {
  const Vec3 error(estimate.x - truth.x, estimate.y - truth.y, wrapAngle(estimate.theta - truth.theta));
  if (!error.allFinite() || !covariance.allFinite()) throw std::invalid_argument("poseNees: non-finite input");
  if (!covariance.isApprox(covariance.transpose(), 1e-9))
    throw std::invalid_argument("poseNees: covariance is not symmetric");
  const Eigen::LLT<Mat3> cholesky(covariance);
  if (cholesky.info() != Eigen::Success) throw std::invalid_argument("poseNees: covariance is not positive definite");
  return error.dot(cholesky.solve(error));
}

NeesInterval averageNeesInterval(int dimension, int samples, double confidence) {
  if (dimension <= 0 || samples <= 0) throw std::invalid_argument("averageNeesInterval: needs dimension, samples > 0");
  if (!(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("averageNeesInterval: confidence must lie in (0, 1)");
  const double dof = static_cast<double>(dimension) * samples;
  const double tail = 0.5 * (1.0 - confidence);
  return {chiSquaredQuantile(tail, dof) / samples, chiSquaredQuantile(1.0 - tail, dof) / samples};
}

NeesSummary summarizeNees(const std::vector<std::vector<double>>& nees, int dimension, double confidence) {
  if (nees.empty() || nees.front().empty()) throw std::invalid_argument("summarizeNees: no NEES values");
  const size_t steps = nees.front().size();
  for (const auto& run : nees)
    if (run.size() != steps) throw std::invalid_argument("summarizeNees: runs differ in length");
  NeesSummary summary;
  summary.step_interval = averageNeesInterval(dimension, static_cast<int>(nees.size()), confidence);
  double total = 0.0;
  size_t inside = 0;
  for (size_t k = 0; k < steps; ++k) {
    double sum = 0.0;
    for (const auto& run : nees) sum += run[k];
    const double average = sum / static_cast<double>(nees.size());
    summary.average_per_step.push_back(average);
    total += sum;
    if (average >= summary.step_interval.lower && average <= summary.step_interval.upper) ++inside;
  }
  summary.average = total / static_cast<double>(nees.size() * steps);
  summary.fraction_steps_inside = static_cast<double>(inside) / static_cast<double>(steps);
  return summary;
}

}  // namespace polarslam
