#pragma once
// Shared machinery of the line and corner error budgets: every systematic source is a range
// perturbation ξ_i, and its effect on a least-squares fit with Jacobian rows h_i and normal
// matrix inverse N⁻¹ = (HᵀH)⁻¹ is N⁻¹·Σ h_i ξ_i — the general form of (A.29)–(A.30). A fit
// output y = f(params) (e.g. a corner's apex) then moves by J·N⁻¹·Σ h_i ξ_i.
#include <Eigen/Core>

#include "laser/laser_error_model.hpp"

namespace polarslam {

/// Σ h_i·ξ_i for every source, accumulated reading by reading.
template <int P>
struct RangeErrorSums {
  using Vec = Eigen::Matrix<double, P, 1>;
  Vec unit_bias = Vec::Zero();  ///< Σ h_i: the response to a 1 m bias in every reading
  Vec incidence = Vec::Zero(), growth = Vec::Zero(), quantization_sin = Vec::Zero(), quantization_cos = Vec::Zero(),
      tilt = Vec::Zero(), motion = Vec::Zero();

  void add(const Vec& h, const ReadingPerturbations& xi) {
    unit_bias += h;
    incidence += h * xi.incidence;
    growth += h * xi.growth;
    quantization_sin += h * xi.quantization_sin;
    quantization_cos += h * xi.quantization_cos;
    tilt += h * xi.tilt;
    motion += h * xi.motion;
  }
};

/// Error of a fit output per source (signed, except the quantisation bound).
template <int Q>
struct SourceErrors {
  using Vec = Eigen::Matrix<double, Q, 1>;
  using Mat = Eigen::Matrix<double, Q, Q>;
  Vec unit_bias = Vec::Zero();  ///< response to a 1 m bias, for the per-scan bias covariance
  Vec fixed_bias = Vec::Zero(), incidence = Vec::Zero(), growth = Vec::Zero(), quantization = Vec::Zero(),
      plane_tilt = Vec::Zero(), yaw = Vec::Zero(), motion = Vec::Zero();

  /// Σ|·| over the systematic sources (§2.3.10).
  Vec bound() const {
    return fixed_bias.cwiseAbs() + incidence.cwiseAbs() + growth.cwiseAbs() + quantization.cwiseAbs() +
           plane_tilt.cwiseAbs() + yaw.cwiseAbs() + motion.cwiseAbs();
  }
  /// Per-scan random bias covariance, (A.21) in general form: σ_rb²·g·gᵀ.
  Mat scanBiasCov(double bias_sigma) const { return bias_sigma * bias_sigma * unit_bias * unit_bias.transpose(); }
};

/// Maps the sums through N⁻¹ and the output Jacobian J (Q×P). `yaw_shift` is the parameter
/// change caused by the mounting yaw error (it turns bearings, not ranges).
template <int Q, int P>
SourceErrors<Q> projectSourceErrors(const RangeErrorSums<P>& sums, const Eigen::Matrix<double, P, P>& normal_inverse,
                                    const Eigen::Matrix<double, Q, P>& jacobian, const LaserErrorParams& params,
                                    const Eigen::Matrix<double, P, 1>& yaw_shift) {
  const Eigen::Matrix<double, Q, P> m = jacobian * normal_inverse;
  SourceErrors<Q> e;
  e.unit_bias = m * sums.unit_bias;
  e.fixed_bias = params.range.fixed_bias * e.unit_bias;  // (2.33), (2.35) in general form
  e.incidence = m * sums.incidence;                      // (A.29)–(A.30) with w|tan β|
  e.growth = m * sums.growth;                            // ... with k(r − r_min)
  // Phase-independent bound of the quantisation bias: max over θ of |cos θ·Δ_sin + sin θ·Δ_cos|.
  const auto in_phase = m * sums.quantization_sin;
  const auto quadrature = m * sums.quantization_cos;
  e.quantization = (in_phase.array().square() + quadrature.array().square()).sqrt().matrix();
  e.plane_tilt = m * sums.tilt;
  e.yaw = jacobian * yaw_shift;
  e.motion = m * sums.motion;
  return e;
}

}  // namespace polarslam
