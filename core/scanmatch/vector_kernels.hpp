#pragma once
// The vector instruction sets the scan matcher's inner loops (projection, joint system) run on.
// Each kernel set adds the same terms in the same order, so every one gives the same bits; the
// matcher uses the widest the processor has, chosen at run time.

// GCC's target pragmas compile the AVX2 kernels into any x86-64 build.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define POLARSLAM_AVX2_KERNELS 1
#else
#define POLARSLAM_AVX2_KERNELS 0
#endif

#include <cstddef>
#include <cstdint>

namespace polarslam {

enum class VectorKernels { Baseline, Avx2 };

bool vectorKernelsAvailable(VectorKernels kernels);
/// The widest kernels this processor runs.
VectorKernels widestVectorKernels();
const char* vectorKernelsName(VectorKernels kernels);

namespace detail {
// The arithmetic of a scan's preparation (prepared_scan.cpp, docs/algorithms.md §4, §11.1).

/// slope[i] = moment[i]/denominator[i], rounded to single precision, where the denominator is
/// positive; NaN elsewhere.
void divideSlopes(const double* moment, const double* denominator, size_t n, float* slope, VectorKernels kernels);

/// PreparedScan::SurfaceTerms from the scan's slopes (per beam), filtered ranges, slope
/// variances, flags and its geometry's cos/sin tables; NaN where a bearing is flagged or its
/// slope unknown. The outputs must hold `size` rounded up to a multiple of four.
struct SurfaceInputs {
  const float *slope, *range, *slope_variance;
  const double *cos, *sin;
  const uint8_t* flags;
  size_t size;
  double increment;
};
struct SurfaceOutputs {
  double *rho, *cos_beta, *normal_x, *normal_y, *rho_cos_beta, *beta_variance;
};
void surfaceTerms(const SurfaceInputs& in, const SurfaceOutputs& out, VectorKernels kernels);
}  // namespace detail

}  // namespace polarslam
