#pragma once
// The sums of PSM's steps, vectorised (they are most of a match's arithmetic): the joint
// (x, y, θ) system (docs/algorithms.md §11.1: over the bearings where the projected current scan
// and the reference both have a usable sample, the information matrix HᵀWH, the gradient HᵀWe,
// Σw, Σw·e² and the error index), the orientation step's slope fit and its shift cost (§8).
#include <cstddef>
#include <cstdint>

#include "geometry/pose2.hpp"
#include "scanmatch/vector_kernels.hpp"

namespace polarslam {

/// Per reference bearing: the projected range r'' and its tag, the reference range and flags,
/// and the reference's surface terms (PreparedScan::SurfaceTerms; beta_variance is read only
/// for JointTerms::SlopeNoise and may be null otherwise).
struct JointInputs {
  const float* projected;
  const float* measured;
  const uint8_t* tag;
  const uint8_t* flags;
  const double *rho, *cos_beta, *normal_x, *normal_y, *rho_cos_beta, *beta_variance;
  size_t size;
};

struct JointLimits {
  double min_range, max_range;  ///< projected ranges outside are not used
  double max_error;             ///< residual gate (the error index takes those below half of it)
  double max_slope;             ///< |ρ| above this (grazing incidence) is left out
};

struct JointSums {
  double a11 = 0, a12 = 0, a13 = 0, a22 = 0, a23 = 0, a33 = 0;  ///< HᵀWH, upper triangle
  double g1 = 0, g2 = 0, g3 = 0;                                ///< HᵀW·e (normal distances)
  double sum_w = 0, sum_we2 = 0;
  double sum_abs_error = 0;  ///< Σ|e| over the `in_index` samples within max_error/2
  int used = 0, in_index = 0;
  /// Σ w·var(β)·(uuᵀ − hhᵀ), u = ∂h/∂β = (h2, −h1, u3), over the same samples as HᵀWH: what the
  /// noise of the reference's slopes adds to it per unit range variance, to second order. Its
  /// (2,2) entry is −s11.
  double s11 = 0, s12 = 0, s13 = 0, s23 = 0, s33 = 0;
};

/// Which part of the joint system to sum: all of it; only the translation's (a13, a23, a33
/// and g3 left at 0; the rest the same bits); or only the slope noise's s11..s33 (with `used`).
enum class JointTerms { All, Translation, SlopeNoise };

/// The sums at `pose` (the current laser in the reference laser frame) with weights
/// w = c/(c + e²).
JointSums sumJointSystem(const JointInputs& in, const Pose2& pose, double c, const JointLimits& limits,
                         VectorKernels kernels, JointTerms terms = JointTerms::All);

/// The orientation step's slope fit (§8): samples i of the projection against reference
/// bearings i + k (the pointers offset by the shift k), both masked (0 = unusable), with the
/// reference's range-profile slope (NaN where unknown).
struct SlopeFitInputs {
  const float *projected, *projected_mask, *reference, *reference_mask, *slope;
  size_t size;
  double max_error;  ///< residual gate
};
struct SlopeFitSums {
  double num = 0, den = 0;  ///< Σ w·slope·r and Σ w·slope², w = c/(c + r²)
};
SlopeFitSums sumSlopeFit(const SlopeFitInputs& in, double c, VectorKernels kernels);

/// The orientation search's cost e(k) (§8) at one shift: samples i of the projection against
/// reference bearings i + k (the pointers offset by k), both masked (0 = unusable, values 0 there).
struct ShiftCostInputs {
  const float *projected, *projected_mask, *reference, *reference_mask;
  size_t size;
  float truncation;  ///< each |difference| counts at most this
};
struct ShiftCostSums {
  float sum = 0;    ///< Σ min(|p_i − r_{i+k}|, truncation) over pairs usable in both
  float pairs = 0;  ///< how many such pairs (exact)
};
ShiftCostSums sumShiftCost(const ShiftCostInputs& in, VectorKernels kernels);

/// The projected ranges the orientation search uses: values[j] = range[j] where the sample is
/// usable (tag 0, min_range < range < max_range) and 0 elsewhere, mask[j] = 1 or 0.
struct MaskInputs {
  const float* range;
  const uint8_t* tag;
  size_t size;
  double min_range, max_range;
};
void maskSamples(const MaskInputs& in, float* values, float* mask, VectorKernels kernels);

}  // namespace polarslam
