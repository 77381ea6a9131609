#pragma once
// χ² distribution: CDF through the regularised lower incomplete gamma function, quantile by
// bisection on the CDF (exact to double precision; no table or approximation).
namespace polarslam {

/// P(a, x) = γ(a, x)/Γ(a), a > 0, x ≥ 0.
double regularizedLowerGamma(double a, double x);

/// P(X ≤ x) for X ~ χ²(dof). Throws std::invalid_argument for dof ≤ 0.
double chiSquaredCdf(double x, double dof);

/// x with chiSquaredCdf(x, dof) = probability, 0 < probability < 1.
/// Throws std::invalid_argument outside that range or for dof ≤ 0.
double chiSquaredQuantile(double probability, double dof);

}  // namespace polarslam
